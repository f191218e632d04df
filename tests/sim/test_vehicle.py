import mujoco
import numpy as np
import pytest
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
    hull = scene.model.geom("hull")
    assert hull.bodyid[0] == 0 and np.allclose(hull.size, [70, 10, 5])   # the caller's geom, on the world body
    # per drone: four motors, three drag-force and three attitude actuators; one mocap attitude target
    assert scene.model.nu == 2 * 10 and scene.model.nmocap == 2
    assert load_quadrotor().find("actuator", "motor_fl") is not None


def _quat(yaw, pitch, roll):
    """(w, x, y, z) of the Z-Y-X rotation."""
    q = np.zeros(4)
    mujoco.mju_euler2Quat(q, np.array([roll, pitch, yaw]), "XYZ")
    return q


def test_attitude_actuators_sense_the_so3_error_and_the_body_rate():
    scene = build_scene(1)
    m, d = scene.model, mujoco.MjData(scene.model)
    q_d, q = _quat(2.5, 0.2, -0.1), _quat(2.6, 0.25, -0.05)
    d.mocap_quat[scene.mocap_index[0]] = q_d
    d.qpos[scene.qpos_index[0][3:]] = q
    d.qvel[scene.qvel_index[0][3:]] = [0.3, -0.2, 0.1]       # body rates (rad/s)
    mujoco.mj_forward(m, d)
    r_d, r = np.zeros(9), np.zeros(9)
    mujoco.mju_quat2Mat(r_d, q_d)
    mujoco.mju_quat2Mat(r, q)
    r_d, r = r_d.reshape(3, 3), r.reshape(3, 3)
    err = r_d.T @ r
    angle = np.arccos((np.trace(err) - 1) / 2)
    rotvec = angle / (2 * np.sin(angle)) * np.array([err[2, 1] - err[1, 2], err[0, 2] - err[2, 0],
                                                     err[1, 0] - err[0, 1]])
    att = scene.attitude_index[0]
    assert np.allclose(d.actuator_length[att], rotvec, atol=1e-9)
    # the rate they damp: the body angular velocity expressed in the desired frame
    assert np.allclose(d.actuator_velocity[att], err @ np.array([0.3, -0.2, 0.1]), atol=1e-9)
    k_r, k_w = PHANTOM4.attitude_gains((14.0, 14.0, 5.0), 0.8)
    expected = np.clip(-k_r * rotvec - k_w * d.actuator_velocity[att], -PHANTOM4.max_torque_n_m,
                       PHANTOM4.max_torque_n_m)
    assert np.allclose(d.actuator_force[att], expected, atol=1e-9)


def test_attitude_loop_inside_mujoco_brings_a_tilted_drone_to_the_target():
    scene = build_scene(1)
    m, d = scene.model, mujoco.MjData(scene.model)
    d.mocap_quat[scene.mocap_index[0]] = _quat(0.4, 0.0, 0.0)
    d.qpos[scene.qpos_index[0][3:]] = _quat(0.0, 0.3, -0.2)
    d.ctrl[scene.actuator_index[0]] = PHANTOM4.weight_n / 4
    for _ in range(int(2.0 / m.opt.timestep)):       # 2 s at the physics rate
        mujoco.mj_step(m, d)
    quat = d.qpos[scene.qpos_index[0][3:]]
    # within 0.01 deg of the target attitude, at rest
    dist = np.zeros(3)
    mujoco.mju_subQuat(dist, quat, _quat(0.4, 0.0, 0.0))
    assert np.degrees(np.linalg.norm(dist)) < 0.01
    assert np.abs(d.qvel[scene.qvel_index[0][3:]]).max() < 1e-3


def test_attitude_torque_is_limited_to_what_the_rotors_can_add():
    tau = PHANTOM4.max_torque_n_m
    # roll: all four motors shift by min(hover, headroom) = W/4 with lever arm a/sqrt(2) each
    half = PHANTOM4.weight_n / 4
    assert tau[0] == pytest.approx(4 * half * PHANTOM4.arm_length_m / np.sqrt(2))
    assert tau[2] == pytest.approx(4 * half * PHANTOM4.yaw_torque_per_newton_m)
    # the same as the mixer gives for that differential thrust
    dt = np.array([half, -half, half, -half])
    assert (dt @ PHANTOM4.mixer().T)[1] == pytest.approx(tau[0])


def test_drag_actuators_push_the_centre_of_mass_in_the_world_frame():
    scene = build_scene(2)
    m, d = scene.model, mujoco.MjData(scene.model)
    q = _quat(2.0, 0.3, -0.2)            # yawed and tilted: the force must not turn with the body
    d.qpos[scene.qpos_index[1][3:]] = q
    d.mocap_quat[scene.mocap_index[1]] = q
    force = np.array([1.5, -0.7, 0.4])
    d.ctrl[scene.drag_index[1]] = force
    mujoco.mj_forward(m, d)
    dofs = scene.qvel_index[1]
    gravity = np.array([0.0, 0.0, -9.81])
    assert np.allclose(d.qacc[dofs[:3]], force / PHANTOM4.mass_kg + gravity, atol=1e-9)
    assert np.allclose(d.qacc[dofs[3:]], 0.0, atol=1e-9)      # at the centre of mass: no moment
    assert np.allclose(d.qacc[scene.qvel_index[0][:3]], gravity, atol=1e-9)   # only drone 1 is pushed
