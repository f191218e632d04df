"""The quadrotor: its parameters (one place, cited), its MJCF and the scene holding a batch of copies.

The airframe is a DJI Phantom 4 class quadrotor, the paper's vehicle class (DESIGN.md "Quadrotor").
``models/quadrotor/quadrotor.xml`` is the visual/structural MJCF; :func:`load_quadrotor` reads it with
PyMJCF (dm_control) and writes the numbers of :class:`QuadrotorParams` into it, so the XML and the
controller can never disagree. :func:`build_scene` attaches N copies to a scene root (our own sea plane,
or a root element the caller passes in, e.g. the ship stage's scene) each under a free joint.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from dm_control import mjcf

MODEL_FILE = Path(__file__).resolve().parents[2] / "models" / "quadrotor" / "quadrotor.xml"
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
      - rated wind ~10 m/s (DESIGN.md; DJI quotes level-5 wind resistance for the class).
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
    root = mjcf.from_path(str(MODEL_FILE))
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
    body_id (n_drones,): the airframe bodies (where drag is applied); actuator_index (n_drones, 4).
    """

    model: mujoco.MjModel
    mjcf_root: mjcf.RootElement
    n_drones: int
    qpos_index: np.ndarray
    qvel_index: np.ndarray
    body_id: np.ndarray
    actuator_index: np.ndarray
    params: QuadrotorParams = field(default=PHANTOM4)


def build_scene(n_drones: int, params: QuadrotorParams = PHANTOM4, timestep_s: float = 0.005,
                root: mjcf.RootElement | None = None, spacing_m: float = 2.0) -> Scene:
    """Attach ``n_drones`` quadrotors (free joints, no mutual collisions) to ``root`` and compile.

    ``root`` defaults to :func:`sea_scene`; pass e.g. the ship stage's scene to fly around the ship
    (its timestep is then overwritten with ``timestep_s`` and contacts are disabled: the simulator
    detects lost flights itself, drones never touch anything).
    """
    if n_drones < 1:
        raise ValueError("n_drones must be >= 1")
    root = sea_scene(timestep_s) if root is None else root
    root.option.timestep = timestep_s
    root.option.flag.contact = "disable"
    frames = []
    for i in range(n_drones):
        quad = load_quadrotor(params, name=f"drone{i}")
        frame = root.worldbody.attach(quad)
        frame.pos = [spacing_m * i, 0.0, 10.0]
        frames.append(frame.add("freejoint", name="root"))
    model = mujoco.MjModel.from_xml_string(root.to_xml_string(), root.get_assets())
    qpos_index = np.zeros((n_drones, 7), dtype=int)
    qvel_index = np.zeros((n_drones, 6), dtype=int)
    body_id = np.zeros(n_drones, dtype=int)
    actuator_index = np.zeros((n_drones, 4), dtype=int)
    for i in range(n_drones):
        joint = model.joint(frames[i].full_identifier)
        qpos_index[i] = joint.qposadr[0] + np.arange(7)
        qvel_index[i] = joint.dofadr[0] + np.arange(6)
        body_id[i] = model.body(f"drone{i}/airframe").id
        actuator_index[i] = [model.actuator(f"drone{i}/motor_{r}").id for r in ROTOR_NAMES]
    return Scene(model, root, n_drones, qpos_index, qvel_index, body_id, actuator_index, params)
