import mujoco
import numpy as np
from dm_control import mjcf

from wrp_eval.sim.vehicle import PHANTOM4, build_scene, load_quadrotor


def test_params_in_compiled_model_match_the_spec():
    scene = build_scene(3)
    m = scene.model
    assert np.allclose(m.body_mass[scene.body_id], 1.38)
    assert np.allclose(m.body_inertia[scene.body_id], PHANTOM4.inertia_kg_m2)
    assert np.allclose(m.actuator_ctrlrange[scene.actuator_index.ravel(), 1], PHANTOM4.max_thrust_per_motor_n)
    # thrust-to-weight 2: four motors at full thrust lift twice the weight
    assert np.isclose(4 * PHANTOM4.max_thrust_per_motor_n, 2 * 1.38 * 9.81)
    # 350 mm motor diagonal
    xy = PHANTOM4.rotor_positions_m
    assert np.isclose(np.linalg.norm(xy[0] - xy[3]), 0.350)


def test_drones_never_collide():
    m = build_scene(4).model
    drone_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] != 0]
    assert np.all(m.geom_contype[drone_geoms] == 0) and np.all(m.geom_conaffinity[drone_geoms] == 0)


def test_mixer_hand_cases():
    mix = PHANTOM4.mixer()
    w = np.full(4, 2.0) @ mix.T
    assert np.allclose(w, [8.0, 0, 0, 0])
    # more thrust on the left rotors (+y) rolls right-wing-down: positive moment about x
    assert (np.array([1.0, 0.0, 1.0, 0.0]) @ mix.T)[1] > 0
    # more thrust on the front rotors pitches nose down: negative moment about y
    assert (np.array([1.0, 1.0, 0.0, 0.0]) @ mix.T)[2] < 0


def test_open_loop_hover_and_yaw_torque_match_the_mixer():
    scene = build_scene(1)
    m, d = scene.model, mujoco.MjData(scene.model)
    d.ctrl[scene.actuator_index[0]] = PHANTOM4.weight_n / 4
    mujoco.mj_forward(m, d)
    assert np.allclose(d.qacc[scene.qvel_index[0]], 0.0, atol=1e-9)
    # differential thrust of the CW pair: yaw acceleration = k * dT * 2 / Izz
    dt = 0.5
    d.ctrl[scene.actuator_index[0]] = PHANTOM4.weight_n / 4 + dt * PHANTOM4.rotor_spin_sign
    mujoco.mj_forward(m, d)
    expected = PHANTOM4.yaw_torque_per_newton_m * 4 * dt / PHANTOM4.inertia_kg_m2[2]
    assert np.isclose(d.qacc[scene.qvel_index[0][5]], expected, rtol=1e-6)


def test_attach_to_a_caller_scene():
    root = mjcf.RootElement(model="ship_scene")
    root.worldbody.add("geom", name="hull", type="box", size=[70, 10, 5], pos=[0, 0, 5])
    scene = build_scene(2, root=root)
    assert scene.model.geom("hull").id >= 0
    assert scene.model.nu == 8
    assert load_quadrotor().find("actuator", "motor_fl") is not None
