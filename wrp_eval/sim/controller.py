"""Geometric SE(3) tracking controller with integral action, vectorised over a batch of vehicles.

Lee, Leok, McClamroch (2010), "Geometric tracking control of a quadrotor UAV on SE(3)", CDC:
  F_des = m (-k_p e_p - k_v e_v - k_i int e_p + g e3 + a_d),   f = F_des . R e3,
  b3_d = F_des / |F_des|,  b1_d, b2_d from the yaw command (see __call__),
  e_R = 1/2 vee(R_d^T R - R^T R_d),  M = -k_R e_R - k_W W + W x J W   (W_d = 0: set-point attitude).
The integral term (Goodarzi, Lee, Lee 2013 add one for disturbance rejection) removes the steady offset a
constant wind would leave; it is clamped (anti-windup). The horizontal part of F_des is limited to the
vehicle's max tilt. Motor thrusts come from the inverse mixer, clipped to [0, max thrust].

The controller runs once per simulation chunk (zero-order hold), see README.md for the rate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.sim.vehicle import GRAVITY_M_S2, QuadrotorParams


@dataclass(frozen=True)
class ControllerGains:
    """Gains per unit mass (position) and per unit inertia (attitude): k_R = J w_att^2, k_W = 2 zeta J w_att."""

    kp: float = 4.0            # 1/s^2
    kv: float = 3.6            # 1/s
    ki: float = 1.2            # 1/s^3
    integral_limit_m_s2: float = 7.0   # clamp of k_i * int e_p (m/s^2)
    attitude_bandwidth_rad_s: float = 14.0
    attitude_damping: float = 0.8
    yaw_bandwidth_rad_s: float = 5.0


GAIN_PRESETS: dict[str, ControllerGains] = {
    "default": ControllerGains(),
    # softer position loop, e.g. for gentle photo flights
    "soft": ControllerGains(kp=2.0, kv=2.6, ki=0.5, attitude_bandwidth_rad_s=10.0),
    # stiffer hold against gusts
    "stiff": ControllerGains(kp=6.0, kv=4.5, ki=2.0, attitude_bandwidth_rad_s=16.0),
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


class GeometricController:
    """Batched SE(3) controller. State: the position-error integral (n, 3)."""

    def __init__(self, params: QuadrotorParams, gains: ControllerGains, n: int):
        self.params = params
        self.gains = gains
        inertia = np.asarray(params.inertia_kg_m2, dtype=float)
        w = np.array([gains.attitude_bandwidth_rad_s] * 2 + [gains.yaw_bandwidth_rad_s])
        self.k_r = inertia * w ** 2
        self.k_w = 2.0 * gains.attitude_damping * inertia * w
        self.inertia = inertia
        self.unmix = np.linalg.inv(params.mixer())
        self.max_thrust = params.max_thrust_per_motor_n
        self.tan_max_tilt = np.tan(params.max_tilt_rad)
        self.integral = np.zeros((n, 3))

    def reset(self, mask: np.ndarray | None = None) -> None:
        if mask is None:
            self.integral[:] = 0.0
        else:
            self.integral[mask] = 0.0

    def __call__(self, pos, vel, rot, omega, ref_pos, ref_vel, ref_acc, ref_yaw, dt_s):
        """Motor thrusts (n, 4) N for states pos/vel (n, 3) world, rot (n, 3, 3), omega (n, 3) body rad/s."""
        g = self.gains
        m = self.params.mass_kg
        e_p = pos - ref_pos
        e_v = vel - ref_vel
        self.integral += e_p * dt_s
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
        force = m * acc
        b3 = force / np.sqrt((force ** 2).sum(axis=1, keepdims=True))
        # b1_d = y_c x b3 (y_c the horizontal normal of the heading) keeps the Z-Y-X yaw of R_d exactly at
        # the commanded heading when tilted (Lee's b3 x b1_c form would shift it; the camera yaw counts)
        y_c = np.stack([-np.sin(ref_yaw), np.cos(ref_yaw), np.zeros_like(ref_yaw)], axis=1)
        b1 = cross(y_c, b3)
        b1 /= np.sqrt((b1 ** 2).sum(axis=1, keepdims=True))
        b2 = cross(b3, b1)
        rot_d = np.stack([b1, b2, b3], axis=2)
        # e_R = 1/2 vee(R_d^T R - R^T R_d)
        err = np.matmul(rot_d.transpose(0, 2, 1), rot)
        skew = err - np.transpose(err, (0, 2, 1))
        e_r = 0.5 * np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)
        thrust = (force * rot[:, :, 2]).sum(axis=1)
        j_omega = omega * self.inertia
        moment = -self.k_r * e_r - self.k_w * omega + cross(omega, j_omega)
        wrench = np.concatenate([thrust[:, None], moment], axis=1)
        motors = wrench @ self.unmix.T
        return np.clip(motors, 0.0, self.max_thrust)
