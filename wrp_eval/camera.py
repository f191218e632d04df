"""The camera model and the pose conventions every stage shares.

Conventions (the project's, README.md "Where things live"): world frame x along the ship (bow +x), y to
port, z up, sea at z = 0.
A view is a position plus ``yaw`` (heading of the optical axis, radians, counter-clockwise from +x)
and ``pitch`` (gimbal pitch of the optical axis above the horizontal, radians; negative looks down).
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


def camera_rotations(yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """World-from-camera rotations (n, 3, 3): columns are the camera x (right), y (down), z (optical axis).

    Roll is zero: the gimbal keeps the horizon level.
    """
    yaw = np.atleast_1d(np.asarray(yaw, dtype=float))
    pitch = np.atleast_1d(np.asarray(pitch, dtype=float))
    z_axis = optical_axes(yaw, pitch)
    x_axis = np.stack([np.sin(yaw), -np.cos(yaw), np.zeros_like(yaw)], axis=-1)
    y_axis = np.cross(z_axis, x_axis)
    return np.stack([x_axis, y_axis, z_axis], axis=-1)


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
