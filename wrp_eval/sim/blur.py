"""Motion blur of a photo: how far the image moves during the exposure, in pixels, batch-first.

A static point on the optical axis at depth Z seen by a camera moving with linear velocity v and angular
velocity w (both in the camera frame: x right, y down, z optical axis) moves in the image, at the image
centre, by (Longuet-Higgins & Prazdny 1980, "The interpretation of a moving retinal image", Proc. R. Soc. B
208; the point's velocity relative to the camera is -v - w x P with P = (0, 0, Z)):

    du/dt = f_px (-v_x / Z - w_y),        dv/dt = f_px (-v_y / Z + w_x)         [px/s]

so the blur over an exposure t_e is t_e |(du/dt, dv/dt)|. The translation term alone is |v_perp| t_e / GSD
with GSD = Z / f_px (the camera's ground sampling distance at the viewpoint); the rotation term alone
|w_perp| t_e f_px. Practice keeps the blur within half a pixel to a pixel (the half-pixel rule: ArduPilot
Mission Planner issue 1601; Sieberth, Wackrow & Chandler 2016, ISPRS J. Photogramm. 122, show that blur
degrades and can prevent automatic photogrammetric processing).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation


def angular_velocity(rot_before: NDArray[np.float64], rot_after: NDArray[np.float64],
                     dt_s: float) -> NDArray[np.float64]:
    """(n, 3) rad/s mean angular velocity, in the camera frame, of cameras turning from ``rot_before`` to
    ``rot_after`` (n, 3, 3) world from camera over ``dt_s`` s."""
    relative = np.einsum("nji,njk->nik", rot_before, rot_after)          # R_before^T R_after
    rotvec: NDArray[np.float64] = Rotation.from_matrix(relative).as_rotvec()
    return rotvec / dt_s


def motion_blur_px(velocity_m_s: NDArray[np.float64], rotation: NDArray[np.float64], omega_rad_s: NDArray[np.float64],
                   depth_m: NDArray[np.float64], exposure_s: float, focal_px: float) -> NDArray[np.float64]:
    """Blur length (n,) px at the image centre.

    velocity_m_s (n, 3): the camera's world velocity; rotation (n, 3, 3): world from camera; omega_rad_s
    (n, 3): angular velocity in the camera frame; depth_m (n,): distance along the optical axis to the
    photographed surface (NaN: unknown, then the blur is NaN); exposure_s: shutter time; focal_px."""
    v: NDArray[np.float64] = np.einsum("nji,nj->ni", rotation, velocity_m_s)  # R^T v: camera frame
    du = -v[:, 0] / depth_m - omega_rad_s[:, 1]
    dv = -v[:, 1] / depth_m + omega_rad_s[:, 0]
    return exposure_s * focal_px * np.hypot(du, dv)
