"""The project's frames, the ship's pose on Earth, and the one wind-direction convention.

Frames
    * **ship frame**: origin on the sea surface at the proxy centre, x to the bow, y to port, z up (metres).
    * **ENU**: local east, north, up at the same origin (metres).
    * **ship pose**: latitude/longitude of the ship-frame origin (WGS84, degrees) and the true heading H
      (degrees clockwise from true north, the compass bearing of the bow; the AIS "true heading").

Ship <-> ENU is a rotation about z: the bow points at bearing H and port at H - 90 deg, so

    east  = x sin H - y cos H          x = east sin H + north cos H
    north = x cos H + y sin H          y = -east cos H + north sin H

ENU <-> latitude/longitude: an east/north offset is carried along the WGS84 geodesic from the ship's position
(``pyproj.Geod``; Karney 2013, "Algorithms for geodesics", J. Geodesy 87: azimuth atan2(east, north),
distance hypot(east, north)), i.e. the azimuthal equidistant projection centred on the ship. Within a few km
it agrees with the true local tangent plane to far below a millimetre (the difference grows like
d^3 / (3 R^2): 8 micrometres at 1 km); the inverse (``Geod.inv``) is exact to numerical precision.
The one other projection here, :func:`geographic_to_enu_equirectangular`, only places a mesoscale (WRF/MM5)
grid of ~10 km cells around the ship: see its docstring for why it is not the geodesic one.

Angles: radians inside the code, degrees at the edges. A ship-frame yaw is counter-clockwise from +x (the
bow); a compass bearing is clockwise from true north; compass = H - yaw_deg.

**Wind direction, the one convention at every edge** (config ``wind.direction_deg``, the campaign's drawn
``wind_direction_deg``, ``wrp-eval fly --wind-dir``): meteorological, the compass bearing the wind blows
FROM, degrees clockwise from true north (270 = a westerly, blowing toward the east; WMO-No. 8, "Guide to
Instruments and Methods of Observation", Vol. I, Ch. 5). :func:`wind_velocity` is the one conversion of such
a direction into an ENU or ship-frame velocity vector.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pyproj import Geod

from wrp_eval.errors import InputError

WGS84 = Geod(ellps="WGS84")
EARTH_RADIUS_M = 6_371_000.0   # mean Earth radius (IUGG), of the equirectangular placement only


@dataclass(frozen=True)
class ShipPose:
    """Where the ship frame sits on Earth: origin latitude/longitude (deg, WGS84) and true heading (deg,
    clockwise from north)."""

    lat_deg: float
    lon_deg: float
    heading_deg: float

    @property
    def heading_rad(self) -> float:
        """The true heading in radians (clockwise from north)."""
        return float(np.radians(self.heading_deg))


class PoseLike(Protocol):
    """Anything with a ship's ``lat_deg``, ``lon_deg`` and ``heading_deg`` (e.g. ``ShipParticulars``)."""

    @property
    def lat_deg(self) -> float: ...
    @property
    def lon_deg(self) -> float: ...
    @property
    def heading_deg(self) -> float: ...


# what :func:`ship_pose` takes
ShipLike = ShipPose | PoseLike | Sequence[float]


def ship_pose(ship: ShipLike) -> ShipPose:
    """The :class:`ShipPose` of ``ship``: a ShipPose, anything with ``lat_deg``, ``lon_deg`` and
    ``heading_deg`` (e.g. the ship stage's ``ShipParticulars``), or a ``(lat_deg, lon_deg, heading_deg)``
    sequence. Anything else is an :class:`InputError`."""
    if isinstance(ship, ShipPose):
        return ship
    if hasattr(ship, "lat_deg"):
        posed = cast(PoseLike, ship)
        return ShipPose(float(posed.lat_deg), float(posed.lon_deg), float(posed.heading_deg))
    try:
        lat, lon, heading = (float(v) for v in ship)
    except (TypeError, ValueError):
        raise InputError("ship", "expected ShipParticulars or (lat_deg, lon_deg, heading_deg)") from None
    return ShipPose(lat, lon, heading)


def ship_to_enu(x: float | NDArray[np.float64], y: float | NDArray[np.float64],
                heading_rad: float | NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Ship-frame horizontal components (any broadcastable shapes, m or m/s) -> (east, north) for a true
    heading ``heading_rad`` (clockwise from north)."""
    s, c = np.sin(heading_rad), np.cos(heading_rad)
    return x * s - y * c, x * c + y * s


def enu_to_ship(east: float | NDArray[np.float64], north: float | NDArray[np.float64],
                heading_rad: float | NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Inverse of :func:`ship_to_enu`: (east, north) components (any broadcastable shapes) -> ship (x, y)."""
    s, c = np.sin(heading_rad), np.cos(heading_rad)
    return east * s + north * c, -east * c + north * s


def wind_velocity(speed_mps: float | NDArray[np.float64], direction_from_rad: float | NDArray[np.float64],
                  heading_rad: float | NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """Velocity (..., 3) m/s of a horizontal wind of ``speed_mps`` blowing FROM the compass bearing
    ``direction_from_rad`` (radians clockwise from true north; the edges' degrees through ``np.radians``).

    heading_rad None: ENU (east, north, 0); else the ship frame (x bow, y port, 0) of a ship with that true
    heading. ``speed_mps`` and ``direction_from_rad`` broadcast against each other (e.g. a speed per level and
    a direction per level)."""
    east = -speed_mps * np.sin(direction_from_rad)
    north = -speed_mps * np.cos(direction_from_rad)
    east, north = np.broadcast_arrays(east, north)
    if heading_rad is not None:
        east, north = enu_to_ship(east, north, heading_rad)
    return np.stack([east, north, np.zeros_like(east)], axis=-1)


def enu_to_geographic(east: ArrayLike, north: ArrayLike,
                      pose: ShipPose) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Local (east (n,), north (n,)) metres about the ship -> (lat_deg (n,), lon_deg (n,)) on WGS84, along
    the geodesic from the ship's position (azimuthal equidistant about it)."""
    east = np.asarray(east, dtype=float)
    north = np.asarray(north, dtype=float)
    n = east.shape[0]
    azimuth = np.degrees(np.arctan2(east, north))
    distance = np.hypot(east, north)
    lon, lat, _ = WGS84.fwd(np.full(n, pose.lon_deg), np.full(n, pose.lat_deg), azimuth, distance)
    return np.asarray(lat, dtype=float), np.asarray(lon, dtype=float)


def geographic_to_enu(lat_deg: ArrayLike, lon_deg: ArrayLike,
                      pose: ShipPose) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(lat, lon) degrees (n,) -> local (east (n,), north (n,)) metres about the ship; the exact inverse of
    :func:`enu_to_geographic` (``Geod.inv``)."""
    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float)
    n = lat.shape[0]
    azimuth, _, distance = WGS84.inv(np.full(n, pose.lon_deg), np.full(n, pose.lat_deg), lon, lat)
    az = np.radians(np.asarray(azimuth, dtype=float))
    distance = np.asarray(distance, dtype=float)
    return distance * np.sin(az), distance * np.cos(az)


def geographic_to_enu_equirectangular(lat_deg: ArrayLike, lon_deg: ArrayLike,
                                      pose: ShipPose) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(lat, lon) degrees (any shape) -> local (east, north) metres about the ship on the equirectangular
    plane tangent at its latitude (sphere of radius ``EARTH_RADIUS_M``):
    east = R cos(lat0) (lon - lon0), north = R (lat - lat0).

    Used to place a mesoscale grid around the ship (:mod:`wrp_eval.wind.netcdf`), which measures the grid's
    spacing and rotation by finite differences between the nodes next to the ship. Parallels are straight
    east-west lines here, so a grid whose rows follow parallels (WRF's Mercator) gets exactly no rotation; on
    the geodesic plane of :func:`geographic_to_enu` a parallel bends north away from the ship (by
    d^2 tan(lat) / (2 R): ~3 m at 9 km and 24 deg N), which would tilt such a grid by ~4e-5 rad and change its
    spacing by ~0.2 %: the netCDF tests pin the rotation to < 1e-6 rad, so the placement keeps this plane."""
    lat0 = np.deg2rad(pose.lat_deg)
    east = EARTH_RADIUS_M * np.cos(lat0) * np.deg2rad(wrap_180(np.asarray(lon_deg, dtype=float) - pose.lon_deg))
    north = EARTH_RADIUS_M * np.deg2rad(np.asarray(lat_deg, dtype=float) - pose.lat_deg)
    return east, north


def ship_to_geographic(points: ArrayLike, pose: ShipPose) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Ship-frame points (n, 3) or (n, 2) m -> (lat_deg (n,), lon_deg (n,)) on WGS84. Heights are left to
    the caller."""
    p = np.asarray(points, dtype=float)
    east, north = ship_to_enu(p[:, 0], p[:, 1], pose.heading_rad)
    return enu_to_geographic(east, north, pose)


def geographic_to_ship(lat_deg: ArrayLike, lon_deg: ArrayLike, pose: ShipPose) -> NDArray[np.float64]:
    """(lat, lon) degrees (n,) -> ship-frame (x, y) metres (n, 2); inverse of :func:`ship_to_geographic`."""
    east, north = geographic_to_enu(lat_deg, lon_deg, pose)
    return np.stack(enu_to_ship(east, north, pose.heading_rad), axis=-1)


def yaw_to_compass_deg(yaw_rad: ArrayLike, ship_heading_deg: float) -> NDArray[np.float64]:
    """Ship-frame yaw (rad, CCW from the bow), any shape -> compass bearing (deg, CW from true north) in
    [0, 360)."""
    compass: NDArray[np.float64] = np.mod(ship_heading_deg - np.degrees(np.asarray(yaw_rad, dtype=float)), 360.0)
    return compass


def compass_to_yaw_rad(compass_deg: ArrayLike, ship_heading_deg: float) -> NDArray[np.float64]:
    """Compass bearing (deg), any shape -> ship-frame yaw (rad, CCW from the bow) in (-pi, pi]."""
    yaw_deg = ship_heading_deg - np.asarray(compass_deg, dtype=float)
    return np.radians(wrap_180(yaw_deg))


def wrap_180(angle_deg: ArrayLike) -> NDArray[np.float64]:
    """Angles (deg), any shape, into (-180, 180]."""
    a = np.mod(np.asarray(angle_deg, dtype=float) + 180.0, 360.0) - 180.0
    return np.where(a == -180.0, 180.0, a)
