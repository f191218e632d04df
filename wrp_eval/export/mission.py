"""Per-sortie geographic missions built from a ship-frame :class:`Path`, with the safety checks.

Altitude reference (every format): metres above the take-off/home point on the ship,
``alt_rel = z - home_z`` (z is the height above the sea surface). QGroundControl's plannedHomePosition and
the DJI reference take-off point carry the home's height above the sea, taken as mean sea level (tide and
the ship's heave are ignored).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.errors import InputError
from wrp_eval.export.config import ExportSection
from wrp_eval.frames import ship_pose, ship_to_geographic, yaw_to_compass_deg
from wrp_eval.planning.path import Path
from wrp_eval.ship.nofly import above_min_altitude, inside_no_fly_box, leg_flyable
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import Proxy


@dataclass(frozen=True)
class GeoMission:
    """One sortie as geographic waypoints (k waypoints, each a photo).

    index (k,) viewpoint indices in the path; lat_deg, lon_deg (k,) WGS84; alt_rel_m (k,) above home;
    heading_deg (k,) compass heading of the aircraft/camera, [0, 360); gimbal_pitch_deg (k,) (negative
    looks down); hold_s: hover time per photo; speed_m_s: cruise speed; home_*: take-off point (deg, m above
    the sea); takeoff_alt_rel_m: climb height before the first waypoint (clears the no-fly box);
    fence_lat_lon (4, 2): corners of the no-fly box outline (lat, lon), counter-clockwise seen from above.
    """

    sortie: int
    index: np.ndarray
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    alt_rel_m: np.ndarray
    heading_deg: np.ndarray
    gimbal_pitch_deg: np.ndarray
    hold_s: float
    speed_m_s: float
    home_lat_deg: float
    home_lon_deg: float
    home_alt_m: float
    takeoff_alt_rel_m: float
    fence_lat_lon: np.ndarray

    def __len__(self) -> int:
        return int(self.index.shape[0])


@dataclass(frozen=True)
class ReadMission:
    """What a reader recovers from an exported file (k waypoints, as in :class:`GeoMission`)."""

    lat_deg: np.ndarray
    lon_deg: np.ndarray
    alt_rel_m: np.ndarray
    heading_deg: np.ndarray
    gimbal_pitch_deg: np.ndarray
    photos: int
    home_lat_lon: tuple[float, float] | None = None


def home_point(particulars: ShipParticulars, section: ExportSection) -> np.ndarray:
    """(3,) take-off point in the ship frame: ``section.home_m`` or the main deck amidships."""
    if section.home_m is not None:
        return np.asarray(section.home_m, dtype=float)
    return np.array([0.0, 0.0, particulars.freeboard_m])


def check_exportable(path: Path, proxy: Proxy, section: ExportSection, source: str) -> None:
    """Refuse (InputError) a path with a waypoint below the minimum altitude, inside the no-fly zone, a
    straight leg between two waypoints of a sortie through the no-fly zone, or a pitch beyond the gimbal's
    range. Altitude and no-fly box are the ship stage's one geometry (:mod:`wrp_eval.ship.nofly`), the
    planner's: what it plans, export accepts."""
    z = path.positions[:, 2]
    box = proxy.no_fly_bounds()
    low = np.flatnonzero(~above_min_altitude(path.positions, section.min_altitude_m))
    if low.size:
        i = int(low[0])
        raise InputError(source, f"{low.size} viewpoint(s) below the minimum altitude {section.min_altitude_m:g} m "
                                 f"above the sea (export.min_altitude_m), first #{i} at z={z[i]:.2f} m")
    inside = np.flatnonzero(inside_no_fly_box(path.positions, box))
    if inside.size:
        i = int(inside[0])
        x, y, zz = path.positions[i]
        raise InputError(source, f"{inside.size} viewpoint(s) inside the ship's no-fly zone "
                                 f"(margin {proxy.no_fly_margin_m:g} m), first #{i} at "
                                 f"({x:.2f}, {y:.2f}, {zz:.2f}) m in the ship frame")
    # the aircraft flies straight between the photos of a sortie: no leg may cut through the no-fly box
    same_sortie = np.asarray(path.sortie)[1:] == np.asarray(path.sortie)[:-1]
    crossing = np.flatnonzero(same_sortie & ~leg_flyable(path.positions[:-1], path.positions[1:], box,
                                                         section.min_altitude_m))
    if crossing.size:
        i = int(crossing[0])
        raise InputError(source, f"{crossing.size} straight leg(s) between viewpoints cross the ship's no-fly zone "
                                 f"(margin {proxy.no_fly_margin_m:g} m), first #{i} -> #{i + 1}")
    pitch = np.degrees(path.pitch)
    lo, hi = section.gimbal_pitch_range_deg
    bad = np.flatnonzero((pitch < lo - 1e-9) | (pitch > hi + 1e-9))
    if bad.size:
        i = int(bad[0])
        raise InputError(source, f"{bad.size} viewpoint(s) outside the gimbal pitch range [{lo:g}, {hi:g}] deg "
                                 f"(export.gimbal_pitch_range_deg), first #{i} at {pitch[i]:.2f} deg")


def build_missions(path: Path, particulars: ShipParticulars, proxy: Proxy, section: ExportSection,
                   source: str = "path") -> list[GeoMission]:
    """One :class:`GeoMission` per sortie, in sortie order (raises InputError for an unsafe path)."""
    check_exportable(path, proxy, section, source)
    pose = ship_pose(particulars)
    home = home_point(particulars, section)
    lat, lon = ship_to_geographic(path.positions, pose)
    heading = yaw_to_compass_deg(path.yaw, pose.heading_deg)
    pitch = np.degrees(path.pitch)
    alt_rel = path.positions[:, 2] - home[2]
    (home_lat,), (home_lon,) = ship_to_geographic(home[None], pose)
    lo, hi = proxy.no_fly_bounds()
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    fence_lat, fence_lon = ship_to_geographic(corners, pose)
    takeoff = max(float(hi[2] - home[2]), float(section.min_altitude_m))
    missions = []
    for sortie in np.unique(path.sortie):
        idx = np.flatnonzero(path.sortie == sortie)
        missions.append(GeoMission(
            int(sortie), idx, lat[idx], lon[idx], alt_rel[idx], heading[idx], pitch[idx],
            float(path.dwell_s), float(path.speed_m_s), float(home_lat), float(home_lon), float(home[2]),
            takeoff, np.stack([fence_lat, fence_lon], axis=1)))
    return missions
