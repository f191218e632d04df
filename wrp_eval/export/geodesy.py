"""Ship frame <-> geographic coordinates, and camera yaw <-> compass heading.

Ship frame: x towards the bow, y to port, z up, metres, origin on the sea surface at the proxy centre.
The bow points at the ship's true heading H (degrees clockwise from north); port is 90 deg
counter-clockwise from the bow seen from above (bearing H - 90). Hence, in local east/north metres:

    east  = x sin H - y cos H
    north = x cos H + y sin H

Local east/north offsets are carried to latitude/longitude along the WGS84 geodesic from the ship's
reference position (pyproj.Geod, Karney 2013, "Algorithms for geodesics", J. Geodesy 87: azimuth
atan2(east, north), distance hypot(east, north)). This is the azimuthal equidistant projection centred on
the ship; within a few km it agrees with the true local tangent plane to far below a millimetre (the
difference grows like d^3 / (3 R^2): 8 micrometres at 1 km) - tests check it against a hand-written
ECEF/ENU tangent plane. The inverse uses ``Geod.inv`` and is exact to numerical precision.

Heading: the camera yaw is counter-clockwise from ship +x; a compass heading is clockwise from north, so
compass = H - yaw_deg, normalised to [0, 360).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pyproj import Geod

WGS84 = Geod(ellps="WGS84")


@dataclass(frozen=True)
class ShipPose:
    """Where the ship frame sits on Earth: origin latitude/longitude (deg) and true heading (deg, CW from N)."""

    lat_deg: float
    lon_deg: float
    heading_deg: float


def ship_to_east_north(points: np.ndarray, heading_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Rotate ship-frame points (n, 3) or (n, 2) into local (east (n,), north (n,)) metres."""
    p = np.asarray(points, dtype=float)
    h = np.radians(heading_deg)
    east = p[:, 0] * np.sin(h) - p[:, 1] * np.cos(h)
    north = p[:, 0] * np.cos(h) + p[:, 1] * np.sin(h)
    return east, north


def east_north_to_ship(east: np.ndarray, north: np.ndarray, heading_deg: float) -> np.ndarray:
    """Inverse of :func:`ship_to_east_north`: (n, 2) ship-frame (x, y) metres."""
    h = np.radians(heading_deg)
    e, n = np.asarray(east, dtype=float), np.asarray(north, dtype=float)
    return np.stack([e * np.sin(h) + n * np.cos(h), -e * np.cos(h) + n * np.sin(h)], axis=-1)


def ship_to_geographic(points: np.ndarray, pose: ShipPose) -> tuple[np.ndarray, np.ndarray]:
    """Ship-frame points (n, 3) -> (lat_deg (n,), lon_deg (n,)) on WGS84. Heights are left to the caller."""
    east, north = ship_to_east_north(points, pose.heading_deg)
    n = east.shape[0]
    azimuth = np.degrees(np.arctan2(east, north))
    distance = np.hypot(east, north)
    lon, lat, _ = WGS84.fwd(np.full(n, pose.lon_deg), np.full(n, pose.lat_deg), azimuth, distance)
    return np.asarray(lat, dtype=float), np.asarray(lon, dtype=float)


def geographic_to_ship(lat_deg: np.ndarray, lon_deg: np.ndarray, pose: ShipPose) -> np.ndarray:
    """(lat, lon) degrees (n,) -> ship-frame (x, y) metres (n, 2); inverse of :func:`ship_to_geographic`."""
    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float)
    n = lat.shape[0]
    azimuth, _, distance = WGS84.inv(np.full(n, pose.lon_deg), np.full(n, pose.lat_deg), lon, lat)
    az = np.radians(np.asarray(azimuth, dtype=float))
    distance = np.asarray(distance, dtype=float)
    return east_north_to_ship(distance * np.sin(az), distance * np.cos(az), pose.heading_deg)


def yaw_to_compass_deg(yaw_rad: np.ndarray, ship_heading_deg: float) -> np.ndarray:
    """Camera yaw (rad, CCW from ship +x) -> compass heading (deg, CW from true north) in [0, 360)."""
    return np.mod(ship_heading_deg - np.degrees(np.asarray(yaw_rad, dtype=float)), 360.0)


def compass_to_yaw_rad(compass_deg: np.ndarray, ship_heading_deg: float) -> np.ndarray:
    """Compass heading (deg) -> camera yaw (rad, CCW from ship +x) in (-pi, pi]."""
    yaw_deg = ship_heading_deg - np.asarray(compass_deg, dtype=float)
    return np.radians(wrap_180(yaw_deg))


def wrap_180(angle_deg: np.ndarray) -> np.ndarray:
    """Angles (deg) into (-180, 180]."""
    a = np.mod(np.asarray(angle_deg, dtype=float) + 180.0, 360.0) - 180.0
    return np.where(a == -180.0, 180.0, a)
