"""The camera model and the pose conventions every stage shares.

Conventions (the project's, README.md "Where things live"): world frame x along the ship (bow +x), y to
port, z up, sea at z = 0.
A view is a position plus ``yaw`` (heading of the optical axis, radians, counter-clockwise from +x),
``pitch`` (gimbal pitch of the optical axis above the horizontal, radians; negative looks down) and
``roll`` (rotation about the optical axis, radians; 0 = horizon level; positive = the camera turned clockwise
as seen from behind it, i.e. its right side down: the aircraft convention, positive roll = right wing down,
a right-handed rotation about the forward axis; "+RWD" in the sign list DAVE-ML takes from the AIAA
recommended practice, https://daveml.org/DTDs/1p5b2/Ref/ar01s06s03.html). World-from-camera =
Rz(yaw) Ry(-pitch) Rx(roll) C0, C0 = the camera at yaw = pitch = roll = 0 (columns (0, -1, 0), (0, 0, -1),
(1, 0, 0)): the Z-Y-X (yaw, pitch, roll) order of drone photo metadata (DJI's XMP GimbalYawDegree /
GimbalPitchDegree / GimbalRollDegree, "rotation order ZYX", DJI Mavic 3M user manual, Data Storage).
The camera frame is OpenCV's: x right, y down, z along the optical axis.

Defaults are the paper's camera (Sec. 5.1): f = 44.7846 mm on a 36 mm-wide sensor; the paper does not
give the image size, we take a 6000 x 4000 px (24 MP, 3:2) full-frame sensor, configurable.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.compiled import as_rows, contiguous, kernel


@dataclass(frozen=True)
class Camera:
    """Pinhole intrinsics. Lengths in millimetres on the sensor, sizes in pixels."""

    focal_mm: float = 44.7846
    sensor_width_mm: float = 36.0
    image_width_px: int = 6000
    image_height_px: int = 4000

    @property
    def sensor_height_mm(self) -> float:
        return self.sensor_width_mm * self.image_height_px / self.image_width_px

    @property
    def focal_px(self) -> float:
        return self.focal_mm * self.image_width_px / self.sensor_width_mm

    @property
    def half_fov_x(self) -> float:
        """Half horizontal field of view, radians."""
        return float(np.arctan(0.5 * self.sensor_width_mm / self.focal_mm))

    @property
    def half_fov_y(self) -> float:
        """Half vertical field of view, radians."""
        return float(np.arctan(0.5 * self.sensor_height_mm / self.focal_mm))

    @overload
    def gsd_m(self, distance_m: float) -> float: ...
    @overload
    def gsd_m(self, distance_m: NDArray[np.float64]) -> NDArray[np.float64]: ...
    def gsd_m(self, distance_m: float | NDArray[np.float64]) -> float | NDArray[np.float64]:
        """Ground sampling distance (m/px) at ``distance_m``: D * sensor_width / (f * image_width)."""
        return distance_m * self.sensor_width_mm / (self.focal_mm * self.image_width_px)

    def distance_for_gsd(self, gsd_m: float) -> float:
        """Distance (m) at which one pixel covers ``gsd_m`` metres."""
        return gsd_m * self.focal_mm * self.image_width_px / self.sensor_width_mm

    @overload
    def footprint_m(self, distance_m: float) -> tuple[float, float]: ...
    @overload
    def footprint_m(self, distance_m: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
    def footprint_m(self, distance_m: float | NDArray[np.float64]
                    ) -> tuple[float | NDArray[np.float64], float | NDArray[np.float64]]:
        """(width, height) in metres of the image footprint on a plane facing the camera at ``distance_m``."""
        gsd = self.gsd_m(distance_m)
        return gsd * self.image_width_px, gsd * self.image_height_px


def optical_axes(yaw: ArrayLike, pitch: ArrayLike) -> NDArray[np.float64]:
    """Unit optical axes (n, 3) from yaw and pitch (n,) in radians."""
    yaw = np.asarray(yaw, dtype=float)
    pitch = np.asarray(pitch, dtype=float)
    cp = np.cos(pitch)
    return np.stack([cp * np.cos(yaw), cp * np.sin(yaw), np.sin(pitch)], axis=-1)


def yaw_pitch_towards(positions: ArrayLike, targets: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Yaw and pitch (radians, each (n,)) that point cameras at ``positions`` (n, 3) to ``targets`` (n, 3)."""
    d = np.asarray(targets, dtype=float) - np.asarray(positions, dtype=float)
    yaw = np.arctan2(d[..., 1], d[..., 0])
    pitch = np.arctan2(d[..., 2], np.hypot(d[..., 0], d[..., 1]))
    return yaw, pitch


@kernel
def _level_row(yaw: float, pitch: float, rot: NDArray[np.float64]) -> None:
    """Write the roll-free world-from-camera rotation of one view into ``rot`` (3, 3): columns x = (sin yaw,
    -cos yaw, 0), z = the optical axis (:func:`optical_axes`), y = z x x."""
    cp = np.cos(pitch)
    z0, z1, z2 = cp * np.cos(yaw), cp * np.sin(yaw), np.sin(pitch)
    x0, x1, x2 = np.sin(yaw), -np.cos(yaw), 0.0
    rot[0, 0], rot[1, 0], rot[2, 0] = x0, x1, x2
    rot[0, 1], rot[1, 1], rot[2, 1] = z1 * x2 - z2 * x1, z2 * x0 - z0 * x2, z0 * x1 - z1 * x0
    rot[0, 2], rot[1, 2], rot[2, 2] = z0, z1, z2


@kernel
def _rotation_rows(yaw: NDArray[np.float64], pitch: NDArray[np.float64],
                   roll: NDArray[np.float64]) -> NDArray[np.float64]:
    n = yaw.size
    rot = np.empty((n, 3, 3))
    for row in range(n):
        _level_row(yaw[row], pitch[row], rot[row])
        if roll.size and roll[row] != 0:     # rows with zero roll stay bit-identical to the level camera
            c, s = np.cos(roll[row]), np.sin(roll[row])
            for d in range(3):
                # R_level @ Rz(roll): the new right axis is c x + s y, the new down axis -s x + c y
                x, y = rot[row, d, 0], rot[row, d, 1]
                rot[row, d, 0], rot[row, d, 1] = c * x + s * y, -s * x + c * y
    return rot


def camera_rotations(yaw: ArrayLike, pitch: ArrayLike, roll: ArrayLike | None = None) -> NDArray[np.float64]:
    """World-from-camera rotations (n, 3, 3): columns are the camera x (right), y (down), z (optical axis).

    yaw, pitch (n,) rad; roll (n,) rad about the optical axis (module docstring: positive turns the camera
    clockwise as seen from behind, its x axis towards its y axis, right side down). Roll None or 0 is the
    level gimbal: exactly the roll-free matrices (those rows are not touched). One compiled loop over the
    views (:mod:`wrp_eval.compiled`).
    """
    yaw = np.atleast_1d(np.asarray(yaw, dtype=float))
    pitch = np.atleast_1d(np.asarray(pitch, dtype=float))
    shape = np.broadcast_shapes(yaw.shape, pitch.shape)
    yaw, pitch = (contiguous(as_rows(name, a, shape)).reshape(-1) for name, a in (("yaw", yaw), ("pitch", pitch)))
    roll = np.empty(0) if roll is None else contiguous(as_rows("roll", roll, shape)).reshape(-1)
    return _rotation_rows(yaw, pitch, roll).reshape(shape + (3, 3))


@kernel
def _angle_rows(rot: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    n = rot.shape[0]
    yaw, pitch, roll = np.empty(n), np.empty(n), np.zeros(n)
    level = np.empty((3, 3))
    for row in range(n):
        horizontal = np.hypot(rot[row, 0, 2], rot[row, 1, 2])
        pitch[row] = np.arctan2(rot[row, 2, 2], horizontal)     # atan2, not arcsin: exact near the vertical
        if horizontal < 1e-12:
            # level right axis (sin yaw, -cos yaw, 0) gives yaw where the optical axis does not (vertical views)
            yaw[row] = np.arctan2(rot[row, 0, 0], -rot[row, 1, 0])
            continue
        yaw[row] = np.arctan2(rot[row, 1, 2], rot[row, 0, 2])
        _level_row(yaw[row], pitch[row], level)
        # Rz(roll) = R_level^T R: cos roll = x_level . x, sin roll = y_level . x
        sin_roll = level[0, 1] * rot[row, 0, 0] + level[1, 1] * rot[row, 1, 0] + level[2, 1] * rot[row, 2, 0]
        cos_roll = level[0, 0] * rot[row, 0, 0] + level[1, 0] * rot[row, 1, 0] + level[2, 0] * rot[row, 2, 0]
        roll[row] = np.arctan2(sin_roll, cos_roll)
    return yaw, pitch, roll


# planned pitch (rad, absolute) from which a view's optical axis counts as vertical (nadir, zenith)
VERTICAL_AXIS_PITCH_RAD = float(np.radians(85.0))


def angles_near_plan(yaw: ArrayLike, pitch: ArrayLike, roll: ArrayLike, plan_yaw: ArrayLike,
                     plan_pitch: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The same rotations (:func:`camera_rotations`) as (yaw, pitch, roll) (n,) rad, each in the form nearer its
    plan (n,) rad. Every rotation has two forms, (y, p, r) and (y + pi, +-pi - p, r + pi) (+ for p > 0); where the
    planned optical axis is vertical (:data:`VERTICAL_AXIS_PITCH_RAD`) a tilt of a fraction of a degree past the
    vertical makes :func:`camera_angles` give the form with the yaw turned by ~180 deg and the roll by ~180 deg.
    There the form with the smaller |yaw - plan_yaw| + |roll| is kept (the other pitch then lies just beyond
    +-pi/2: the camera tipped past the vertical); elsewhere the angles are returned as given."""
    yaw, pitch, roll, plan_yaw, plan_pitch = (np.array(a, dtype=float, ndmin=1) for a in
                                              (yaw, pitch, roll, plan_yaw, plan_pitch))
    other_yaw = np.angle(np.exp(1j * (yaw + np.pi)))
    other_roll = np.angle(np.exp(1j * (roll + np.pi)))
    away = np.abs(np.angle(np.exp(1j * (yaw - plan_yaw)))) + np.abs(roll)
    other_away = np.abs(np.angle(np.exp(1j * (other_yaw - plan_yaw)))) + np.abs(other_roll)
    flip = (np.abs(plan_pitch) >= VERTICAL_AXIS_PITCH_RAD) & (other_away < away)
    return (np.where(flip, other_yaw, yaw), np.where(flip, np.copysign(np.pi, pitch) - pitch, pitch),
            np.where(flip, other_roll, roll))


def camera_angles(rotations: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Inverse of :func:`camera_rotations`: world-from-camera rotations (n, 3, 3) -> yaw, pitch, roll (n,) rad.

    yaw in (-pi, pi], pitch in [-pi/2, pi/2], roll in (-pi, pi]. At pitch +-pi/2 (optical axis vertical)
    yaw and roll turn about the same axis (gimbal lock); there the whole turn goes to yaw and roll is 0
    (the matrix is still reproduced).
    """
    return _angle_rows(np.ascontiguousarray(np.asarray(rotations, dtype=float).reshape(-1, 3, 3)))


def world_rays(rotations: NDArray[np.float64], directions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Camera-frame ``directions`` (r, 3) turned into the world by the world-from-camera ``rotations`` (n, 3, 3):
    (n, r, 3), out[v, k] = R_v d_k. Plain products and sums in index order: the same bits on every CPU (einsum's
    default path is ~100x slower here, its BLAS path picks its kernel, and so its rounding, by CPU)."""
    rot = np.asarray(rotations, dtype=float)[:, None, :, :]
    d = np.asarray(directions, dtype=float)
    out = np.empty((rot.shape[0], d.shape[0], 3))
    for i in range(3):
        out[..., i] = rot[..., i, 0] * d[:, 0] + rot[..., i, 1] * d[:, 1] + rot[..., i, 2] * d[:, 2]
    return out


def project(points: ArrayLike, positions: ArrayLike, rotations: NDArray[np.float64],
            camera: Camera) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Project points into every camera.

    points (m, 3); positions (n, 3); rotations (n, 3, 3) world-from-camera.
    Returns pixel coordinates (n, m, 2) and depth along the optical axis (n, m) in metres
    (points behind a camera have depth <= 0).
    """
    rel = np.asarray(points, dtype=float)[None, :, :] - np.asarray(positions, dtype=float)[:, None, :]
    cam = np.einsum("nij,nmi->nmj", rotations, rel)  # R^T (p - c)
    depth = cam[..., 2]
    safe = np.where(np.abs(depth) > 1e-12, depth, 1e-12)
    f = camera.focal_px
    uv = np.stack([f * cam[..., 0] / safe + camera.image_width_px / 2.0,
                   f * cam[..., 1] / safe + camera.image_height_px / 2.0], axis=-1)
    return uv, depth


def in_image(uv: NDArray[np.float64], depth: NDArray[np.float64], camera: Camera) -> NDArray[np.bool_]:
    """Boolean mask (same leading shape as depth): in front of the camera and inside the image."""
    return ((depth > 0) & (uv[..., 0] >= 0) & (uv[..., 0] <= camera.image_width_px)
            & (uv[..., 1] >= 0) & (uv[..., 1] <= camera.image_height_px))
