"""Marine surface layer: Charnock roughness, log-law profiles, and the synthetic mean field.

Frames and the wind-direction convention are :mod:`wrp_eval.frames`'s: the direction is the compass bearing
the wind blows FROM (a "270 deg" wind blows from the west toward the east), the ship heading the compass
bearing of the bow, the ship frame x = bow, y = port, z = up.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.frames import ship_to_enu, wind_velocity
from wrp_eval.wind.grid import WindGrid

GRAVITY_MPS2 = 9.81
VON_KARMAN = 0.40
MIN_ROUGHNESS_M = 1e-6     # floor on z0 so that calm columns keep a finite log law


def charnock_roughness(speed_10m_m_s: ArrayLike, alpha: float = 0.011,
                       iterations: int = 60) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sea-surface roughness z0 (m) and friction velocity u* (m/s) from the 10 m wind speed.

    Charnock (1955): z0 = alpha u*^2 / g, with the neutral log law u* = kappa U10 / ln(10 / z0);
    solved by fixed-point iteration (it contracts: d z0/d z0 ~ 2 u*/(kappa U10) * ... << 1 at sea).
    alpha ~ 0.011 (open ocean, Smith 1988, JGR 93(C12)) .. 0.018 (coastal / young sea, Wu 1980, JPO 10).
    """
    u10 = np.maximum(np.asarray(speed_10m_m_s, dtype=float), 0.0)
    z0 = np.full_like(u10, 1e-4)
    for _ in range(iterations):
        ustar = VON_KARMAN * u10 / np.log(10.0 / z0)
        z0 = np.maximum(alpha * ustar**2 / GRAVITY_MPS2, MIN_ROUGHNESS_M)
    ustar = VON_KARMAN * u10 / np.log(10.0 / z0)
    return z0, ustar


def log_law_factor(height_m: ArrayLike, z0_m: ArrayLike,
                   reference_height_m: float = 10.0) -> NDArray[np.float64]:
    """U(z) / U(z_ref) of the neutral log law, ln(z/z0) / ln(z_ref/z0); 0 at and below z0."""
    z = np.asarray(height_m, dtype=float)
    z0 = np.asarray(z0_m, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.log(np.maximum(z, z0) / z0) / np.log(reference_height_m / z0)
    return np.where(z > z0, f, 0.0)


def synthetic_marine_grid(speed_10m_m_s: float, direction_deg: float, heading_deg: float,
                          x_m: ArrayLike, y_m: ArrayLike, z_m: ArrayLike, charnock_alpha: float = 0.011,
                          veer_deg_per_100m: float = 0.0, gradient_per_km: float = 0.0) -> WindGrid:
    """A neutral marine boundary layer on a ship-frame grid (the embedded default mean field).

    Speed: U(z) = U10(x, y) ln(z/z0) / ln(10/z0) with Charnock z0 (so u*/kappa ln(z/z0)); 0 at z <= z0.
    Veer: the FROM direction turns clockwise by ``veer_deg_per_100m`` per 100 m above 10 m (Ekman veering
    in the northern hemisphere is clockwise with height; use a negative value for backing).
    Gradient: U10 scales by (1 + gradient_per_km * s / 1000), s = downwind distance (m) of the column from the
    ship, clipped at 0 - a mild horizontal gradient across the grid. W = 0.
    Axes x_m (nx,), y_m (ny,), z_m (nz,) in the ship frame; z_m strictly increasing, >= 0.
    """
    x_m, y_m, z_m = (np.asarray(a, dtype=float) for a in (x_m, y_m, z_m))
    heading = np.deg2rad(heading_deg)
    direction = np.deg2rad(direction_deg)
    gx, gy = np.meshgrid(x_m, y_m, indexing="ij")                     # (nx, ny)
    east, north = ship_to_enu(gx, gy, heading)
    de, dn, _ = wind_velocity(1.0, direction)                          # unit downwind vector (east, north)
    downwind_m = east * de + north * dn
    u10 = np.maximum(speed_10m_m_s * (1.0 + gradient_per_km * downwind_m / 1000.0), 0.0)
    z0, _ = charnock_roughness(u10, charnock_alpha)
    speed = u10[..., None] * log_law_factor(z_m[None, None, :], z0[..., None])       # (nx, ny, nz)
    from_dir = direction + np.deg2rad(veer_deg_per_100m) * (z_m - 10.0) / 100.0        # (nz,)
    velocity = wind_velocity(speed, from_dir[None, None, :], heading)                # (nx, ny, nz, 3)
    heights = np.broadcast_to(z_m, speed.shape).copy()
    return WindGrid(x_m, y_m, heights, velocity, 0.0, source="synthetic marine boundary layer")
