"""Geometric SE(3) tracking controller with integral action, vectorised over a batch of vehicles.

Split in two loops at two rates, as on a real autopilot (PX4: position loop ~50 Hz, attitude/rate loops
250 Hz and faster): the position loop here (numpy, once per simulation chunk) and the attitude loop inside
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

import numpy as np

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


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices (world from body) from (n, 4) unit quaternions (w, x, y, z)."""
    w, x, y, z = quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3]
    xx, yy, zz, xy, xz, yz, wx, wy, wz = x * x, y * y, z * z, x * y, x * z, y * z, w * x, w * y, w * z
    rot = np.empty((quat.shape[0], 3, 3))
    rot[:, 0, 0] = 1 - 2 * (yy + zz)
    rot[:, 0, 1] = 2 * (xy - wz)
    rot[:, 0, 2] = 2 * (xz + wy)
    rot[:, 1, 0] = 2 * (xy + wz)
    rot[:, 1, 1] = 1 - 2 * (xx + zz)
    rot[:, 1, 2] = 2 * (yz - wx)
    rot[:, 2, 0] = 2 * (xz - wy)
    rot[:, 2, 1] = 2 * (yz + wx)
    rot[:, 2, 2] = 1 - 2 * (xx + yy)
    return rot


def yaw_of(rot: np.ndarray) -> np.ndarray:
    """(n,) heading of the body x axis (rad, CCW from world +x) from (n, 3, 3) rotations."""
    return np.arctan2(rot[:, 1, 0], rot[:, 0, 0])


def tilt_of(rot: np.ndarray) -> np.ndarray:
    """(n,) angle (rad) between the body z axis and world up."""
    return np.arccos(np.clip(rot[:, 2, 2], -1.0, 1.0))


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (n, 3) arrays (np.cross is several times slower on small batches)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles wrapped to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def attitude_quaternion(b3: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """(n, 4) unit quaternions (w, x, y, z) of R_d = [b1 b2 b3] with b1 = y_c x b3 / |.|, y_c the horizontal
    normal of the heading ``yaw`` (n,) rad, b3 (n, 3) unit thrust axes (tilt < 90 deg).

    This R_d has Z-Y-X Euler angles (yaw, theta, phi) with Rz(-yaw) b3 = (cos phi sin theta, -sin phi,
    cos phi cos theta), so q = q_z(yaw) q_y(theta) q_x(phi): a handful of trig functions per vehicle
    instead of a matrix-to-quaternion conversion.
    """
    cy, sy = np.cos(yaw), np.sin(yaw)
    bx = cy * b3[:, 0] + sy * b3[:, 1]
    by = -sy * b3[:, 0] + cy * b3[:, 1]
    phi = -np.arcsin(np.clip(by, -1.0, 1.0))
    theta = np.arctan2(bx, b3[:, 2])
    cz, sz = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
    ct, st = np.cos(0.5 * theta), np.sin(0.5 * theta)
    cp, sp = np.cos(0.5 * phi), np.sin(0.5 * phi)
    return np.stack([cz * ct * cp + sz * st * sp,
                     cz * ct * sp - sz * st * cp,
                     cz * st * cp + sz * ct * sp,
                     sz * ct * cp - cz * st * sp], axis=1)


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

    def __call__(self, pos, vel, body_z, ref_pos, ref_vel, ref_acc, ref_yaw, dt_s, integrate=None):
        """(thrust (n,) N, R_d quaternion (n, 4)) for pos/vel (n, 3) world, body_z (n, 3) = R e3.

        ``integrate`` (n,) bool: where the position-error integral may grow (None: everywhere). The flight
        freezes it while the reference moves (conditional integration, an anti-windup scheme: Astrom &
        Hagglund 2006, "Advanced PID Control", Sec. 3.5): the integral is for the steady wind, and errors
        during accelerations would otherwise wind it up and leave a slow overshoot at the viewpoint.
        """
        g = self.gains
        m = self.params.mass_kg
        e_p = pos - ref_pos
        e_v = vel - ref_vel
        if integrate is None:
            self.integral += e_p * dt_s
        else:
            self.integral += np.where(integrate[:, None], e_p * dt_s, 0.0)
        lim = g.integral_limit_m_s2 / max(g.ki, 1e-9)
        norm = np.sqrt((self.integral ** 2).sum(axis=1, keepdims=True))
        self.integral *= np.minimum(1.0, lim / np.maximum(norm, 1e-12))
        acc = -g.kp * e_p - g.kv * e_v - g.ki * self.integral + ref_acc
        acc[:, 2] += GRAVITY_M_S2
        acc[:, 2] = np.maximum(acc[:, 2], 0.2 * GRAVITY_M_S2)
        # tilt limit: the horizontal demand may not exceed vertical * tan(max tilt)
        horiz = np.hypot(acc[:, 0], acc[:, 1])
        scale = np.minimum(1.0, acc[:, 2] * self.tan_max_tilt / np.maximum(horiz, 1e-12))
        acc[:, :2] *= scale[:, None]
        norm_acc = np.sqrt((acc ** 2).sum(axis=1))
        b3 = acc / norm_acc[:, None]
        # f = F_des . R e3 (Lee et al. 2010): less thrust while the attitude still lags the demand
        thrust = m * (acc * body_z).sum(axis=1)
        return np.clip(thrust, 0.0, self.max_total_thrust), attitude_quaternion(b3, ref_yaw)
