"""Per-sortie geographic missions built from a ship-frame :class:`FlightPath`, with the safety checks.

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
from wrp_eval.planning.path import FlightPath
from wrp_eval.ship.nofly import above_min_altitude, inside_no_fly_box, leg_flyable
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import Proxy
from wrp_eval.sim.capture_mode import FLY_THROUGH, STOP, CaptureSection


@dataclass(frozen=True)
class FlightStyle:
    """How the aircraft flies the waypoints and shoots: what the simulator flies, written into every format.

    mode: the mission's ``stop`` (fly to the waypoint, hover ``hold_s``, shoot) or ``fly-through`` (shoot
    passing the waypoint, no hold; the turn starts ``pass_radius_m`` before it, the simulator's
    ``corner_radius_m``), for every waypoint whose path gives no mode of its own
    (:attr:`wrp_eval.planning.path.FlightPath.capture`); heading_mode: ``smoothTransition`` (the heading
    interpolated over each leg); hold_s: hover per photo at a stop waypoint (0 when none stops); speed_m_s:
    cruise speed.
    """

    mode: str = STOP
    heading_mode: str = "smoothTransition"
    hold_s: float = 0.0
    speed_m_s: float = 5.0
    pass_radius_m: float = 0.0

    @classmethod
    def of(cls, path: FlightPath, capture: CaptureSection = CaptureSection(),
           dwell_s: float | None = None) -> FlightStyle:
        """The style the simulator flies ``path`` with under ``sim.capture`` and ``sim.dwell_s`` (None: the
        path's dwell), at the path's cruise speed (wrp_eval/sim/flight.py: the same choices)."""
        stops = path.stops(capture.mode)
        hold = float(path.dwell_s if dwell_s is None else dwell_s) if stops.any() else 0.0
        return cls(capture.mode, capture.heading_mode, hold, float(path.speed_m_s),
                   0.0 if stops.all() else float(capture.corner_radius_m))


@dataclass(frozen=True)
class GeoMission:
    """One sortie as geographic waypoints (k waypoints, each a photo).

    index (k,) viewpoint indices in the path; lat_deg, lon_deg (k,) WGS84; alt_rel_m (k,) above home;
    heading_deg (k,) compass heading of the aircraft/camera, [0, 360); gimbal_pitch_deg (k,) (negative
    looks down); style: how it is flown and shot (:class:`FlightStyle`: mode, heading mode, hold, speed);
    home_*: take-off point (deg, m above the sea); takeoff_alt_rel_m: climb height before the first waypoint
    (clears the no-fly box); fence_lat_lon (4, 2): corners of the no-fly box outline (lat, lon),
    counter-clockwise seen from above; view_id (k,) int: the plan's viewpoint of each waypoint (the path's
    ``view_ids()``: ``index`` unless the tour flies its viewpoints in another order), what photos are named by;
    stop (k,) bool: the waypoints flown stop-and-shoot (the others are shot passing), the path's per-view modes
    over the style's mode (:meth:`wrp_eval.planning.path.FlightPath.stops`); leg_speed_m_s (k,) m/s: the cruise
    speed of the leg leaving each waypoint (the path's :meth:`~wrp_eval.planning.path.FlightPath.leg_speeds`; the
    style's speed after the sortie's last waypoint).
    """

    sortie: int
    index: np.ndarray
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    alt_rel_m: np.ndarray
    heading_deg: np.ndarray
    gimbal_pitch_deg: np.ndarray
    style: FlightStyle
    home_lat_deg: float
    home_lon_deg: float
    home_alt_m: float
    takeoff_alt_rel_m: float
    fence_lat_lon: np.ndarray
    view_id: np.ndarray
    stop: np.ndarray
    leg_speed_m_s: np.ndarray

    def __len__(self) -> int:
        return int(self.index.shape[0])

    @property
    def hold_s(self) -> np.ndarray:
        """(k,) s: the hover before each photo (the style's hold at a stop waypoint, 0 where it is passed)."""
        hold: np.ndarray = np.where(self.stop, self.style.hold_s, 0.0)
        return hold

    @property
    def pass_radius_m(self) -> np.ndarray:
        """(k,) m: where the turn starts before each waypoint (the style's pass radius where it is passed, 0 at a
        stop waypoint)."""
        radius: np.ndarray = np.where(self.stop, 0.0, self.style.pass_radius_m)
        return radius

    @property
    def speed_m_s(self) -> float:
        return self.style.speed_m_s


@dataclass(frozen=True)
class ReadMission:
    """What a reader recovers from an exported file (k waypoints, as in :class:`GeoMission`).

    turn_mode: ``stop`` | ``fly-through`` as the file commands it for every waypoint, ``mixed`` where some stop
    and some are passed (``stop`` (k,) bool says which stop); heading_mode: the heading mode the file names
    (None where the format cannot carry one); hold_s (k,) hover per waypoint; speed_m_s: cruise speed;
    pass_radius_m: where the turn starts before a passed waypoint (0 when every waypoint stops); leg_speed_m_s
    (k,) m/s: the speed the file sets for the leg leaving each waypoint (at the last, what it leaves set)."""

    lat_deg: np.ndarray
    lon_deg: np.ndarray
    alt_rel_m: np.ndarray
    heading_deg: np.ndarray
    gimbal_pitch_deg: np.ndarray
    photos: int
    home_lat_lon: tuple[float, float] | None = None
    turn_mode: str | None = None
    heading_mode: str | None = None
    hold_s: np.ndarray | None = None
    speed_m_s: float | None = None
    pass_radius_m: float | None = None
    stop: np.ndarray | None = None
    leg_speed_m_s: np.ndarray | None = None


def turn_mode_of(stop: np.ndarray) -> str | None:
    """The :attr:`ReadMission.turn_mode` of waypoints whose ``stop`` (k,) bool a reader recovered (None: none)."""
    if not stop.size:
        return None
    return STOP if stop.all() else FLY_THROUGH if not stop.any() else "mixed"


def home_point(particulars: ShipParticulars, section: ExportSection) -> np.ndarray:
    """(3,) take-off point in the ship frame: ``section.home_m`` or the main deck amidships."""
    if section.home_m is not None:
        return np.asarray(section.home_m, dtype=float)
    return np.array([0.0, 0.0, particulars.freeboard_m])


def check_exportable(path: FlightPath, proxy: Proxy, section: ExportSection, source: str) -> None:
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


def build_missions(path: FlightPath, particulars: ShipParticulars, proxy: Proxy, section: ExportSection,
                   source: str = "path", style: FlightStyle | None = None) -> list[GeoMission]:
    """One :class:`GeoMission` per sortie, in sortie order (raises InputError for an unsafe path). ``style``:
    how it is flown (None: the simulator's defaults, :meth:`FlightStyle.of`)."""
    check_exportable(path, proxy, section, source)
    style = FlightStyle.of(path) if style is None else style
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
    leaving = np.append(path.leg_speeds(), style.speed_m_s)      # the leg leaving each view; none after the last
    for sortie in np.unique(path.sortie):
        idx = np.flatnonzero(path.sortie == sortie)
        legs = np.append(leaving[idx[:-1]], style.speed_m_s)
        missions.append(GeoMission(
            int(sortie), idx, lat[idx], lon[idx], alt_rel[idx], heading[idx], pitch[idx],
            style, float(home_lat), float(home_lon), float(home[2]),
            takeoff, np.stack([fence_lat, fence_lon], axis=1), path.view_ids()[idx], path.stops(style.mode)[idx],
            legs))
    return missions
