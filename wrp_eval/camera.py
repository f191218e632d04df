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

import numpy as np


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

    def gsd_m(self, distance_m: float | np.ndarray) -> float | np.ndarray:
        """Ground sampling distance (m/px) at ``distance_m``: D * sensor_width / (f * image_width)."""
        return distance_m * self.sensor_width_mm / (self.focal_mm * self.image_width_px)

    def distance_for_gsd(self, gsd_m: float) -> float:
        """Distance (m) at which one pixel covers ``gsd_m`` metres."""
        return gsd_m * self.focal_mm * self.image_width_px / self.sensor_width_mm

    def footprint_m(self, distance_m: float | np.ndarray) -> tuple:
        """(width, height) in metres of the image footprint on a plane facing the camera at ``distance_m``."""
        gsd = self.gsd_m(distance_m)
        return gsd * self.image_width_px, gsd * self.image_height_px


def optical_axes(yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """Unit optical axes (n, 3) from yaw and pitch (n,) in radians."""
    yaw = np.asarray(yaw, dtype=float)
    pitch = np.asarray(pitch, dtype=float)
    cp = np.cos(pitch)
    return np.stack([cp * np.cos(yaw), cp * np.sin(yaw), np.sin(pitch)], axis=-1)


def yaw_pitch_towards(positions: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Yaw and pitch (radians, each (n,)) that point cameras at ``positions`` (n, 3) to ``targets`` (n, 3)."""
    d = np.asarray(targets, dtype=float) - np.asarray(positions, dtype=float)
    yaw = np.arctan2(d[..., 1], d[..., 0])
    pitch = np.arctan2(d[..., 2], np.hypot(d[..., 0], d[..., 1]))
    return yaw, pitch


def camera_rotations(yaw: np.ndarray, pitch: np.ndarray, roll: np.ndarray | None = None) -> np.ndarray:
    """World-from-camera rotations (n, 3, 3): columns are the camera x (right), y (down), z (optical axis).

    yaw, pitch (n,) rad; roll (n,) rad about the optical axis (module docstring: positive turns the camera
    clockwise as seen from behind, its x axis towards its y axis, right side down). Roll None or 0 is the
    level gimbal: exactly the roll-free matrices (those rows are not touched).
    """
    yaw = np.atleast_1d(np.asarray(yaw, dtype=float))
    pitch = np.atleast_1d(np.asarray(pitch, dtype=float))
    z_axis = optical_axes(yaw, pitch)
    x_axis = np.stack([np.sin(yaw), -np.cos(yaw), np.zeros_like(yaw)], axis=-1)
    y_axis = np.cross(z_axis, x_axis)
    rot = np.stack([x_axis, y_axis, z_axis], axis=-1)
    if roll is None:
        return rot
    roll = np.broadcast_to(np.asarray(roll, dtype=float), yaw.shape)
    rows = np.flatnonzero(roll != 0)  # rows with zero roll stay bit-identical to the level camera
    if rows.size:
        c, s = np.cos(roll[rows]), np.sin(roll[rows])
        # R_level @ Rz(roll): the new right axis is c x + s y, the new down axis -s x + c y
        x_new = c[:, None] * rot[rows, :, 0] + s[:, None] * rot[rows, :, 1]
        y_new = -s[:, None] * rot[rows, :, 0] + c[:, None] * rot[rows, :, 1]
        rot[rows, :, 0] = x_new
        rot[rows, :, 1] = y_new
    return rot


def camera_angles(rotations: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of :func:`camera_rotations`: world-from-camera rotations (n, 3, 3) -> yaw, pitch, roll (n,) rad.

    yaw in (-pi, pi], pitch in [-pi/2, pi/2], roll in (-pi, pi]. At pitch +-pi/2 (optical axis vertical)
    yaw and roll turn about the same axis (gimbal lock); there the whole turn goes to yaw and roll is 0
    (the matrix is still reproduced).
    """
    rot = np.asarray(rotations, dtype=float).reshape(-1, 3, 3)
    x_axis, z_axis = rot[:, :, 0], rot[:, :, 2]
    horizontal = np.hypot(z_axis[:, 0], z_axis[:, 1])
    pitch = np.arctan2(z_axis[:, 2], horizontal)  # atan2, not arcsin: exact near the vertical
    vertical = horizontal < 1e-12
    # level right axis (sin yaw, -cos yaw, 0) gives yaw where the optical axis does not (vertical views)
    yaw = np.where(vertical, np.arctan2(x_axis[:, 0], -x_axis[:, 1]), np.arctan2(z_axis[:, 1], z_axis[:, 0]))
    level = camera_rotations(yaw, pitch)
    # Rz(roll) = R_level^T R: cos roll = x_level . x, sin roll = y_level . x
    roll = np.arctan2(np.einsum("ni,ni->n", level[:, :, 1], x_axis), np.einsum("ni,ni->n", level[:, :, 0], x_axis))
    return yaw, pitch, np.where(vertical, 0.0, roll)


def project(points: np.ndarray, positions: np.ndarray, rotations: np.ndarray,
            camera: Camera) -> tuple[np.ndarray, np.ndarray]:
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


def in_image(uv: np.ndarray, depth: np.ndarray, camera: Camera) -> np.ndarray:
    """Boolean mask (same leading shape as depth): in front of the camera and inside the image."""
    return ((depth > 0) & (uv[..., 0] >= 0) & (uv[..., 0] <= camera.image_width_px)
            & (uv[..., 1] >= 0) & (uv[..., 1] <= camera.image_height_px))
