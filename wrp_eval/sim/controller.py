"""Geometric SE(3) tracking controller with integral action, vectorised over a batch of vehicles.

Split in two loops at two rates, as on a real autopilot (PX4: position loop ~50 Hz, attitude/rate loops
250 Hz and faster): the position loop here (a compiled kernel, once per simulation chunk) and the attitude loop inside
MuJoCo (actuators of vehicle.build_scene, every physics step).

Lee, Leok, McClamroch (2010), "Geometric tracking control of a quadrotor UAV on SE(3)", CDC:
  F_des = m (-k_p e_p - k_v e_v - k_i int e_p + g e3 + a_d),   f = F_des . R e3,
  b3_d = F_des / |F_des|,  b1_d, b2_d from the yaw command (see __call__),
  e_R = 1/2 vee(R_d^T R - R^T R_d),  M = -k_R e_R - k_W W + W x J W   (W_d = 0: set-point attitude).
The integral term (Goodarzi, Lee, Lee 2013 add one for disturbance rejection) removes the steady offset a
constant wind would leave; it is clamped (anti-windup). The horizontal part of F_des is limited to the
vehicle's max tilt. The total thrust is shared equally by the four motors (clipped to [0, max thrust]);
the attitude torques come from the attitude actuators (torque-limited to what the rotors can add).

The position loop runs once per simulation chunk (zero-order hold), see README.md for the rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.compiled import as_rows, kernel
from wrp_eval.sim.vehicle import GRAVITY_M_S2, QuadrotorParams


@dataclass(frozen=True)
class ControllerGains:
    """Gains per unit mass (position) and per unit inertia (attitude): k_R = J w_att^2, k_W = 2 zeta J w_att.

    The attitude gains are compiled into the MuJoCo model (FlightSimulator builds the scene with them)."""

    # position loop: a triple closed-loop pole at -2 rad/s, (s + 2)^3 = s^3 + kv s^2 + kp s + ki (README.md:
    # the former kp 4, kv 3.6, ki 1.2 had a slow integral pole at -0.48 rad/s: the integral picked up the
    # transit transient and unwound over ~2 s, leaving 2-10 cm at the photo). 2 rad/s is 7x below the
    # attitude bandwidth, as a cascade needs.
    kp: float = 12.0           # 1/s^2
    kv: float = 6.0            # 1/s
    ki: float = 8.0            # 1/s^3
    integral_limit_m_s2: float = 7.0   # clamp of k_i * int e_p (m/s^2)
    attitude_bandwidth_rad_s: float = 14.0
    attitude_damping: float = 0.8
    yaw_bandwidth_rad_s: float = 5.0


GAIN_PRESETS: dict[str, ControllerGains] = {
    "default": ControllerGains(),
    # softer position loop (triple pole at -1.2 rad/s), e.g. for gentle photo flights
    "soft": ControllerGains(kp=4.32, kv=3.6, ki=1.728, attitude_bandwidth_rad_s=10.0),
    # stiffer hold against gusts (triple pole at -2.5 rad/s)
    "stiff": ControllerGains(kp=18.75, kv=7.5, ki=15.625, attitude_bandwidth_rad_s=16.0),
}

_Angle = TypeVar("_Angle", float, NDArray[np.float64])


@kernel
def quat_row_to_matrix(quat: NDArray[np.float64], rot: NDArray[np.float64]) -> None:
    """Write the rotation matrix (world from body) of the unit quaternion ``quat`` (4,) (w, x, y, z) into
    ``rot`` (3, 3)."""
    w, x, y, z = quat[0], quat[1], quat[2], quat[3]
    xx, yy, zz, xy, xz, yz, wx, wy, wz = x * x, y * y, z * z, x * y, x * z, y * z, w * x, w * y, w * z
    rot[0, 0] = 1 - 2 * (yy + zz)
    rot[0, 1] = 2 * (xy - wz)
    rot[0, 2] = 2 * (xz + wy)
    rot[1, 0] = 2 * (xy + wz)
    rot[1, 1] = 1 - 2 * (xx + zz)
    rot[1, 2] = 2 * (yz - wx)
    rot[2, 0] = 2 * (xz - wy)
    rot[2, 1] = 2 * (yz + wx)
    rot[2, 2] = 1 - 2 * (xx + yy)


@kernel
def _quat_rows_to_matrix(quat: NDArray[np.float64]) -> NDArray[np.float64]:
    rot = np.empty((quat.shape[0], 3, 3))
    for row in range(quat.shape[0]):
        quat_row_to_matrix(quat[row], rot[row])
    return rot


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices (world from body) from (n, 4) unit quaternions (w, x, y, z)."""
    return _quat_rows_to_matrix(np.asarray(quat, dtype=float))


@kernel
def yaw_of(rot: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n,) heading of the body x axis (rad, CCW from world +x) from (n, 3, 3) rotations."""
    return np.arctan2(rot[:, 1, 0], rot[:, 0, 0])


def tilt_of(rot: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n,) angle (rad) between the body z axis and world up."""
    return np.arccos(np.clip(rot[:, 2, 2], -1.0, 1.0))


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (n, 3) arrays (np.cross is several times slower on small batches)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles wrapped to [-pi, pi) (numbers, lists or arrays)."""
    angles: NDArray[np.float64] = np.asarray(a, dtype=float)
    return wrapped(angles)


@kernel
def wrapped(a: _Angle) -> _Angle:
    """:func:`wrap_angle` of a number or an array, for kernels."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


@kernel
def _attitude_row(b3x: float, b3y: float, b3z: float, yaw: float) -> tuple[float, float, float, float]:
    """(w, x, y, z) of R_d for one unit thrust axis b3 and heading ``yaw`` (:func:`attitude_quaternion`)."""
    cy, sy = np.cos(yaw), np.sin(yaw)
    bx = cy * b3x + sy * b3y
    by = -sy * b3x + cy * b3y
    phi = -np.arcsin(np.minimum(np.maximum(by, -1.0), 1.0))
    theta = np.arctan2(bx, b3z)
    cz, sz = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
    ct, st = np.cos(0.5 * theta), np.sin(0.5 * theta)
    cp, sp = np.cos(0.5 * phi), np.sin(0.5 * phi)
    return (cz * ct * cp + sz * st * sp, cz * ct * sp - sz * st * cp, cz * st * cp + sz * ct * sp,
            sz * ct * cp - cz * st * sp)


@kernel
def _attitude_rows(b3: NDArray[np.float64], yaw: NDArray[np.float64]) -> NDArray[np.float64]:
    quat = np.empty((b3.shape[0], 4))
    for row in range(b3.shape[0]):
        quat[row, 0], quat[row, 1], quat[row, 2], quat[row, 3] = _attitude_row(b3[row, 0], b3[row, 1], b3[row, 2],
                                                                               yaw[row])
    return quat


def attitude_quaternion(b3: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """(n, 4) unit quaternions (w, x, y, z) of R_d = [b1 b2 b3] with b1 = y_c x b3 / |.|, y_c the horizontal
    normal of the heading ``yaw`` (n,) rad, b3 (n, 3) unit thrust axes (tilt < 90 deg).

    This R_d has Z-Y-X Euler angles (yaw, theta, phi) with Rz(-yaw) b3 = (cos phi sin theta, -sin phi,
    cos phi cos theta), so q = q_z(yaw) q_y(theta) q_x(phi): a handful of trig functions per vehicle
    instead of a matrix-to-quaternion conversion.
    """
    b3 = np.asarray(b3, dtype=float)
    return _attitude_rows(as_rows("b3", b3, (len(b3), 3)), as_rows("yaw", yaw, (len(b3),)))


@kernel
def _position_loop_rows(pos: NDArray[np.float64], vel: NDArray[np.float64], body_z: NDArray[np.float64],
                        ref_pos: NDArray[np.float64], ref_vel: NDArray[np.float64], ref_acc: NDArray[np.float64],
                        ref_yaw: NDArray[np.float64], integrate: NDArray[np.bool_], integral: NDArray[np.float64],
                        dt_s: float, kp: float, kv: float, ki: float, integral_limit: float, mass_kg: float,
                        tan_max_tilt: float,
                        max_total_thrust: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(thrust (n,) N, R_d quaternions (n, 4)) of the position loop (:meth:`PositionController.__call__`), row by
    row; ``integral`` (n, 3) is updated in place."""
    n = pos.shape[0]
    thrust, quat = np.empty(n), np.empty((n, 4))
    e_p, acc = np.empty(3), np.empty(3)
    for row in range(n):
        for d in range(3):
            e_p[d] = pos[row, d] - ref_pos[row, d]
            if integrate[row]:
                integral[row, d] += e_p[d] * dt_s
        norm = np.sqrt(integral[row, 0] ** 2 + integral[row, 1] ** 2 + integral[row, 2] ** 2)
        clamp = np.minimum(1.0, integral_limit / np.maximum(norm, 1e-12))
        for d in range(3):
            integral[row, d] *= clamp
            acc[d] = -kp * e_p[d] - kv * (vel[row, d] - ref_vel[row, d]) - ki * integral[row, d] + ref_acc[row, d]
        acc[2] = np.maximum(acc[2] + GRAVITY_M_S2, 0.2 * GRAVITY_M_S2)
        # tilt limit: the horizontal demand may not exceed vertical * tan(max tilt)
        scale = np.minimum(1.0, acc[2] * tan_max_tilt / np.maximum(np.hypot(acc[0], acc[1]), 1e-12))
        acc[0] *= scale
        acc[1] *= scale
        norm_acc = np.sqrt(acc[0] ** 2 + acc[1] ** 2 + acc[2] ** 2)
        # f = F_des . R e3 (Lee et al. 2010): less thrust while the attitude still lags the demand
        f = mass_kg * (acc[0] * body_z[row, 0] + acc[1] * body_z[row, 1] + acc[2] * body_z[row, 2])
        thrust[row] = np.minimum(np.maximum(f, 0.0), max_total_thrust)
        quat[row, 0], quat[row, 1], quat[row, 2], quat[row, 3] = _attitude_row(
            acc[0] / norm_acc, acc[1] / norm_acc, acc[2] / norm_acc, ref_yaw[row])
    return thrust, quat


class PositionController:
    """Batched outer (position) loop of the SE(3) controller. State: the position-error integral (n, 3).

    Output: total thrust f (n,) N and the desired attitude R_d as a quaternion (n, 4); the attitude loop
    (tau = -k_R e_R - k_W omega) runs inside MuJoCo every physics step (vehicle.build_scene).
    """

    def __init__(self, params: QuadrotorParams, gains: ControllerGains, n: int):
        self.params = params
        self.gains = gains
        self.tan_max_tilt = np.tan(params.max_tilt_rad)
        self.max_total_thrust = 4.0 * params.max_thrust_per_motor_n
        self.integral = np.zeros((n, 3))

    def reset(self, mask: np.ndarray | None = None) -> None:
        if mask is None:
            self.integral[:] = 0.0
        else:
            self.integral[mask] = 0.0

    def __call__(self, pos: ArrayLike, vel: ArrayLike, body_z: ArrayLike, ref_pos: ArrayLike, ref_vel: ArrayLike,
                 ref_acc: ArrayLike, ref_yaw: ArrayLike, dt_s: float,
                 integrate: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(thrust (n,) N, R_d quaternion (n, 4)) for pos/vel (n, 3) world, body_z (n, 3) = R e3.

        ``integrate`` (n,) bool: where the position-error integral may grow (None: everywhere). The flight
        freezes it while the reference moves (conditional integration, an anti-windup scheme: Astrom &
        Hagglund 2006, "Advanced PID Control", Sec. 3.5): the integral is for the steady wind, and errors
        during accelerations would otherwise wind it up and leave a slow overshoot at the viewpoint.
        """
        g = self.gains
        n = len(self.integral)
        vectors = (as_rows(name, value, (n, 3)) for name, value in (("pos", pos), ("vel", vel), ("body_z", body_z),
                                                                    ("ref_pos", ref_pos), ("ref_vel", ref_vel),
                                                                    ("ref_acc", ref_acc)))
        integrate = as_rows("integrate", True if integrate is None else integrate, (n,), bool)
        pos, vel, body_z, ref_pos, ref_vel, ref_acc = vectors
        return _position_loop_rows(pos, vel, body_z, ref_pos, ref_vel, ref_acc, as_rows("ref_yaw", ref_yaw, (n,)),
                                   integrate, self.integral, float(dt_s), g.kp, g.kv, g.ki,
                                   g.integral_limit_m_s2 / max(g.ki, 1e-9), self.params.mass_kg, self.tan_max_tilt,
                                   self.max_total_thrust)
