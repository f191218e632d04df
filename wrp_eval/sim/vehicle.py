"""The quadrotor: its parameters (one place, cited), its MJCF and the scene holding a batch of copies.

The airframe is a DJI Phantom 4 class quadrotor. The paper (Sec. 4.1) takes its vehicle's parameters from "a
certain type of UAV" (Shi et al. 2017) among "common commercial UAVs" with a pan-tilt camera and names none;
the Phantom 4 is our choice of such a camera quadrotor, its numbers cited in :class:`QuadrotorParams`.
``models/quadrotor/quadrotor.xml`` is the visual/structural MJCF; :func:`load_quadrotor` reads it with
PyMJCF (dm_control) and writes the numbers of :class:`QuadrotorParams` into it, so the XML and the
controller can never disagree. :func:`build_scene` attaches N copies to a scene root (our own sea plane,
or a root element the caller passes in, e.g. the ship stage's scene) each under a free joint.

Inner attitude loop inside MuJoCo: each drone also gets a mocap body ``target{i}`` (its orientation is the
desired attitude R_d set by the position loop between chunks) and three ``general`` actuators with a site
transmission from the drone's ``imu`` site to the target's site (``refsite``). MuJoCo then gives the
actuator length = the rotation vector of R_d^T R (the attitude error, in the desired frame) and velocity =
the body rate in that frame (checked in tests/sim/test_vehicle.py), so with ``biasprm = (0, -k_R, -k_W)``
each physics step applies the PD attitude torque tau = -k_R e_R - k_W omega of Lee et al. (2010), at the
physics rate (200 Hz at 5 ms), while the position loop runs between chunks at a lower rate (README.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np
from dm_control import mjcf
from numpy.typing import ArrayLike, NDArray

from wrp_eval.resources import model_file

GRAVITY_M_S2 = 9.81
ROTOR_NAMES = ("fl", "fr", "rl", "rr")


@dataclass(frozen=True)
class QuadrotorParams:
    """Physical parameters of the vehicle (SI units).

    Sources (DJI Phantom 4 specification sheet, dji.com/phantom-4/info, "Aircraft" and "Gimbal"):
      - mass_kg 1.380: "Weight (battery & propellers included) 1380 g";
      - motor diagonal 0.350 m: "Diagonal size (propellers excluded) 350 mm" -> arm 0.175 m, X layout;
      - rotor_radius_m 0.1195: 9450 propellers, 9.4 in diameter;
      - max_tilt_rad 35 deg: "Max tilt angle 35deg (A-mode)" (S-mode 42deg);
      - gimbal pitch -90..+30 deg: "Controllable range: pitch -90deg to +30deg";
      - rated wind ~10 m/s: DJI Phantom 4 Pro specification sheet (dji.com/phantom-4-pro/info, same
        airframe), "Max Wind Speed Resistance 10 m/s".
    Estimates (not on the spec sheet, documented in README.md):
      - max thrust per motor: thrust-to-weight ratio 2.0 (typical of the class) -> 6.77 N per motor;
      - yaw torque per newton 0.016 m: C_Q/C_T * D for a 9-10 in propeller (C_Q/C_T ~ 0.067 at D 0.24 m);
      - inertia (Ixx, Iyy, Izz) = (0.0101, 0.0130, 0.0193) kg m^2 from a component model: 0.93 kg
        battery+shell box 0.25 x 0.18 x 0.10 m, 0.15 kg gimbal, 4 x 0.075 kg motor+propeller at 0.175 m;
      - body box for the windward area: length 0.25 m, width 0.18 m, height 0.10 m (spec sheet overall
        289.5 mm incl. motors, shell alone ~250 x 180 mm); rotor cylinder height 0.02 m (swept blade
        thickness/pitch band).
    """

    mass_kg: float = 1.38
    inertia_kg_m2: tuple[float, float, float] = (0.0101, 0.0130, 0.0193)
    arm_length_m: float = 0.175
    rotor_radius_m: float = 0.1195
    rotor_height_m: float = 0.02
    body_length_m: float = 0.25
    body_width_m: float = 0.18
    body_height_m: float = 0.10
    thrust_to_weight: float = 2.0
    yaw_torque_per_newton_m: float = 0.016
    max_tilt_rad: float = float(np.radians(35.0))
    gimbal_pitch_range_rad: tuple[float, float] = (float(np.radians(-90.0)), float(np.radians(30.0)))
    # the Phantom 4 gimbal's roll axis is not user-controllable; its mechanical stabilisation range
    gimbal_roll_range_rad: tuple[float, float] = (float(np.radians(-35.0)), float(np.radians(35.0)))
    # camera (gimbal pivot) in the body frame: under the nose
    camera_offset_m: tuple[float, float, float] = (0.08, 0.0, -0.075)

    @property
    def weight_n(self) -> float:
        return self.mass_kg * GRAVITY_M_S2

    @property
    def max_thrust_per_motor_n(self) -> float:
        return self.thrust_to_weight * self.weight_n / 4.0

    @property
    def max_torque_n_m(self) -> np.ndarray:
        """(3,) roll, pitch, yaw torque (N m) the rotors can add around hover: every motor may move by the
        smaller of its hover thrust and its headroom (T_max - T_hover), with the lever arm of the mixer."""
        delta = min(self.weight_n / 4.0, self.max_thrust_per_motor_n - self.weight_n / 4.0)
        xy = self.rotor_positions_m
        return delta * np.array([np.abs(xy[:, 1]).sum(), np.abs(xy[:, 0]).sum(),
                                 4.0 * self.yaw_torque_per_newton_m])

    def attitude_gains(self, bandwidth_rad_s: ArrayLike, damping: float) -> tuple[np.ndarray, np.ndarray]:
        """(k_R (3,) N m/rad, k_W (3,) N m s/rad) of a critically-shaped PD: k_R = J w^2, k_W = 2 zeta J w."""
        inertia = np.asarray(self.inertia_kg_m2, dtype=float)
        w = np.broadcast_to(np.asarray(bandwidth_rad_s, dtype=float), (3,))
        return inertia * w ** 2, 2.0 * damping * inertia * w

    @property
    def rotor_positions_m(self) -> np.ndarray:
        """(4, 2) rotor (x, y) in the body frame, order fl, fr, rl, rr."""
        a = self.arm_length_m / np.sqrt(2.0)
        return np.array([[a, a], [a, -a], [-a, a], [-a, -a]])

    @property
    def rotor_spin_sign(self) -> np.ndarray:
        """(4,) sign of the reaction yaw torque per rotor (+1: the rotor spins clockwise seen from above)."""
        return np.array([1.0, -1.0, -1.0, 1.0])

    def mixer(self) -> np.ndarray:
        """(4, 4) matrix from motor thrusts (N) to [total thrust N, Mx, My, Mz N m] in the body frame."""
        xy = self.rotor_positions_m
        return np.stack([np.ones(4), xy[:, 1], -xy[:, 0], self.yaw_torque_per_newton_m * self.rotor_spin_sign])


PHANTOM4 = QuadrotorParams()


def load_quadrotor(params: QuadrotorParams = PHANTOM4, name: str = "quad") -> mjcf.RootElement:
    """PyMJCF root of one quadrotor, with ``params`` written into mass, inertia, thrust limits and gears."""
    root = mjcf.from_path(str(model_file("quadrotor", "quadrotor.xml")))
    root.model = name
    airframe = root.find("body", "airframe")
    airframe.inertial.mass = params.mass_kg
    airframe.inertial.diaginertia = list(params.inertia_kg_m2)
    xy = params.rotor_positions_m
    for i, rotor in enumerate(ROTOR_NAMES):
        site = root.find("site", f"thrust_{rotor}")
        site.pos = [xy[i, 0], xy[i, 1], site.pos[2]]
        geom = root.find("geom", f"rotor_{rotor}")
        geom.pos = [xy[i, 0], xy[i, 1], geom.pos[2]]
        geom.size = [params.rotor_radius_m, params.rotor_height_m / 2.0]
        motor = root.find("actuator", f"motor_{rotor}")
        motor.ctrlrange = [0.0, params.max_thrust_per_motor_n]
        motor.gear = [0, 0, 1, 0, 0, params.yaw_torque_per_newton_m * params.rotor_spin_sign[i]]
    root.find("site", "camera").pos = list(params.camera_offset_m)
    return root


def sea_scene(timestep_s: float = 0.005) -> mjcf.RootElement:
    """A bare scene: the sea surface (z = 0) as a visual plane, gravity, no contacts."""
    root = mjcf.RootElement(model="sea")
    root.option.timestep = timestep_s
    root.option.flag.contact = "disable"
    root.worldbody.add("geom", name="sea", type="plane", size=[2000, 2000, 1], rgba=[0.1, 0.3, 0.5, 1],
                       contype=0, conaffinity=0)
    return root


@dataclass
class Scene:
    """A compiled scene with ``n_drones`` quadrotors.

    qpos_index (n_drones, 7) / qvel_index (n_drones, 6): columns of each drone's free joint in qpos/qvel;
    body_id (n_drones,): the airframe bodies (where drag is applied); actuator_index (n_drones, 4): motors;
    attitude_index (n_drones, 3): the roll/pitch/yaw attitude actuators; drag_index (n_drones, 3): the
    world-frame x/y/z force actuators the drag goes through (N); mocap_index (n_drones,): each drone's
    attitude target in ``mocap_quat``.
    """

    model: mujoco.MjModel
    mjcf_root: mjcf.RootElement
    n_drones: int
    qpos_index: np.ndarray
    qvel_index: np.ndarray
    body_id: np.ndarray
    actuator_index: np.ndarray
    attitude_index: np.ndarray
    drag_index: np.ndarray
    mocap_index: np.ndarray
    params: QuadrotorParams = field(default=PHANTOM4)


def build_scene(n_drones: int, params: QuadrotorParams = PHANTOM4, timestep_s: float = 0.005,
                root: mjcf.RootElement | None = None, spacing_m: float = 2.0,
                attitude_bandwidth_rad_s: ArrayLike = (14.0, 14.0, 5.0), attitude_damping: float = 0.8,
                attitude_loop: bool = True) -> Scene:
    """Attach ``n_drones`` quadrotors (free joints, no mutual collisions) to ``root`` and compile.

    ``root`` defaults to :func:`sea_scene`; pass e.g. the ship stage's scene to fly around the ship
    (its timestep is then overwritten with ``timestep_s`` and contacts are disabled: the simulator
    detects lost flights itself, drones never touch anything).
    ``attitude_bandwidth_rad_s`` (roll, pitch, yaw) and ``attitude_damping`` set the gains of the attitude
    actuators (module docstring); their torque is limited to what the rotors can add around hover
    (:attr:`QuadrotorParams.max_torque_n_m`). ``attitude_loop=False`` leaves out the targets and the
    attitude actuators (motors only: the bench's reference for what the inner loop costs).
    """
    if n_drones < 1:
        raise ValueError("n_drones must be >= 1")
    root = sea_scene(timestep_s) if root is None else root
    root.option.timestep = timestep_s
    root.option.flag.contact = "disable"
    gains = params.attitude_gains(attitude_bandwidth_rad_s, attitude_damping)
    joints = [_attach_drone(root, i, params, spacing_m, gains, attitude_loop) for i in range(n_drones)]
    model = mujoco.MjModel.from_xml_string(root.to_xml_string(), root.get_assets())
    return Scene(model, root, n_drones, *_drone_indices(model, joints, attitude_loop), params)


def _attach_drone(root: mjcf.RootElement, i: int, params: QuadrotorParams, spacing_m: float,
                  gains: tuple[NDArray[np.float64], NDArray[np.float64]], attitude_loop: bool) -> Any:
    """Attach drone ``i`` (its free joint, drag actuators and, with ``attitude_loop``, its attitude target and
    actuators with ``gains`` = (k_R, k_W)) to ``root``; returns its free joint."""
    quad = load_quadrotor(params, name=f"drone{i}")
    frame = root.worldbody.attach(quad)
    frame.pos = [spacing_m * i, 0.0, 10.0]
    joint = frame.add("freejoint", name="root")
    # drag: a world-frame force at the centre of mass through the free joint's translational dofs (a joint
    # transmission: unlike xfrc_applied, which costs a Jacobian per body and step, it is a fixed unit moment;
    # measured in README.md)
    for axis, name in enumerate("xyz"):
        gear = [0.0] * 6
        gear[axis] = 1.0
        root.actuator.add("general", name=f"drone{i}_drag_{name}", joint=joint, gear=gear, gainprm=[1.0])
    if not attitude_loop:
        return joint
    k_r, k_w = gains
    tau_max = params.max_torque_n_m
    target = root.worldbody.add("body", name=f"target{i}", mocap=True, pos=[spacing_m * i, 0.0, 10.0])
    target_site = target.add("site", name=f"target{i}_frame", group=5)
    for axis, name in enumerate(("roll", "pitch", "yaw")):
        gear = [0.0] * 6
        gear[3 + axis] = 1.0
        # force = ctrl (feed-forward torque, 0) - k_R * length - k_W * velocity, clipped to the rotors'
        root.actuator.add("general", name=f"drone{i}_att_{name}", site=quad.find("site", "imu"),
                          refsite=target_site, gear=gear, gainprm=[1.0], biastype="affine",
                          biasprm=[0.0, -k_r[axis], -k_w[axis]], forcelimited=True,
                          forcerange=[-tau_max[axis], tau_max[axis]])
    return joint


def _drone_indices(
        model: mujoco.MjModel, joints: list[Any], attitude_loop: bool,
) -> tuple[NDArray[np.int_], NDArray[np.int_], NDArray[np.int_], NDArray[np.int_], NDArray[np.int_],
           NDArray[np.int_], NDArray[np.int_]]:
    """Scene's index arrays (qpos, qvel, body, actuator, attitude, drag, mocap) of the drones on ``joints``."""
    n_drones = len(joints)
    qpos_index = np.zeros((n_drones, 7), dtype=int)
    qvel_index = np.zeros((n_drones, 6), dtype=int)
    body_id = np.zeros(n_drones, dtype=int)
    actuator_index = np.zeros((n_drones, 4), dtype=int)
    attitude_index = np.zeros((n_drones, 3), dtype=int)
    drag_index = np.zeros((n_drones, 3), dtype=int)
    mocap_index = np.zeros(n_drones, dtype=int)
    for i, frame_joint in enumerate(joints):
        joint = model.joint(frame_joint.full_identifier)
        qpos_index[i] = joint.qposadr[0] + np.arange(7)
        qvel_index[i] = joint.dofadr[0] + np.arange(6)
        body_id[i] = model.body(f"drone{i}/airframe").id
        actuator_index[i] = [model.actuator(f"drone{i}/motor_{r}").id for r in ROTOR_NAMES]
        drag_index[i] = [model.actuator(f"drone{i}_drag_{a}").id for a in "xyz"]
        if attitude_loop:
            attitude_index[i] = [model.actuator(f"drone{i}_att_{a}").id for a in ("roll", "pitch", "yaw")]
            mocap_index[i] = model.body_mocapid[model.body(f"target{i}").id]
    return qpos_index, qvel_index, body_id, actuator_index, attitude_index, drag_index, mocap_index
