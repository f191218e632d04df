"""Per-flight state of a batch of path flights: the values the flight loop's phase functions read and update.

Everything is batch-first: row i is flight i of the batch (``batch`` flights of one path of ``n_views``
viewpoints). The MuJoCo side (body poses, controls) is not here: it lives in the rollout buffers of
:mod:`wrp_eval.sim.flight`; this module holds what the flight logic keeps between chunks.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.camera import Camera
from wrp_eval.planning.path import FlightPath
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.sim.controller import wrap_angle
from wrp_eval.sim.results import Trajectory

# flight phases: fly the segment, wait to be within the tolerances, hold still, then the photo (trigger);
# DONE after the last photo; ENDED: crashed, lost or gone home for good (parked, no further photos); AWAY:
# home for a battery swap between two sorties (parked until it resumes at its breakpoint)
TRANSIT, SETTLE, DWELL, DONE, ENDED, AWAY = 0, 1, 2, 3, 4, 5

# how a mission ends (sim/mission.py has the rules and their sources), in the order they are reported when
# several hold at once. A real autopilot keeps trying against the wind (the leash holds the reference); it
# turns home on its energy (after its last sortie), on a wind limit when one is set, or when it makes no
# headway (the views not reached are not taken: not a failure). Crashes, a vehicle that can neither make
# headway nor get home, one blown out of the wind field, and the simulator's time limit are failures.
(COMPLETED, NON_FINITE, DITCHED, TIMED_OUT, RETURNED_BATTERY, RETURNED_WIND, RETURNED_WIND_AVERAGE,
 RETURNED_HEADWAY, LOST_HEADWAY, LOST_OUTSIDE, LOST_ENERGY) = range(11)
FAILURES = (NON_FINITE, DITCHED, TIMED_OUT, LOST_HEADWAY, LOST_OUTSIDE, LOST_ENERGY)
# one word per outcome for tables and records
OUTCOME_NAMES = ("completed", "non-finite", "ditched", "timed out", "returned: battery", "returned: wind limit",
                 "returned: wind policy", "returned: no headway", "lost: no headway", "lost: left the wind field",
                 "lost: battery, no way home")


@dataclass(frozen=True)
class FlightTargets:
    """Where each flight of a batch is sent.

    plan_position (n_views, 3) m, plan_yaw (n_views,) rad, plan_pitch (n_views,) rad: the unperturbed
    plan's camera poses (capture offsets are measured against them). yaw (batch, n_views) rad: the
    commanded heading per flight (plan + view offsets); body (batch, n_views, 3) m: where the centre of
    mass must be for the camera to sit on the commanded viewpoint at level attitude. depth (n_views,) m: the
    planned distance along each view's optical axis to the ship (NaN: unknown), for the blur in pixels.
    vertex_speed (batch, n_views) and leg_speed (batch, n_views - 1) m/s: the fly-through reference's speed
    at each viewpoint and cruise limit of each leg; arriving and trigger_normal (batch, n_views, 3): the
    arriving leg's direction and the trigger plane's normal at each viewpoint (None in stop mode); stop
    (n_views,) bool: the views shot at rest after the settle and the dwell (the path's per-view capture modes,
    :meth:`wrp_eval.planning.path.FlightPath.stops`; in fly-through the reference stops at them; None: none);
    leg_cruise (n_views - 1,) m/s: the cruise speed of each leg (the path's
    :meth:`~wrp_eval.planning.path.FlightPath.leg_speeds`; None: the profile's cruise on every leg). home_view: the
    view (in flying order) of the plan's first viewpoint: the flights' home (a tour flown the other way round
    keeps the home it was planned from; the autopilot's home is where it took off, MAVLink HOME_POSITION "set
    automatically by the system during the takeoff", ArduPilot RTL "the point where the plane armed", and the
    take-off deck is not modelled: the plan starts next to it).
    """

    plan_position: np.ndarray
    plan_yaw: np.ndarray
    plan_pitch: np.ndarray
    yaw: np.ndarray
    body: np.ndarray
    depth: np.ndarray
    vertex_speed: np.ndarray | None = None
    leg_speed: np.ndarray | None = None
    arriving: np.ndarray | None = None
    trigger_normal: np.ndarray | None = None
    stop: np.ndarray | None = None
    leg_cruise: np.ndarray | None = None
    home_view: int = 0

    @property
    def home(self) -> np.ndarray:
        """(batch, 3) m: the flights' home, the centre of mass at the plan's first viewpoint."""
        home: np.ndarray = self.body[:, self.home_view]
        return home

    @property
    def batch(self) -> int:
        return int(self.body.shape[0])

    @property
    def n_views(self) -> int:
        return int(self.body.shape[1])

    @classmethod
    def from_path(cls, path: FlightPath, batch: int, view_offsets: np.ndarray | None, camera_offset_m: ArrayLike,
                  depth_m: np.ndarray | None = None) -> FlightTargets:
        """Targets of ``batch`` flights of ``path``; ``view_offsets`` (batch, n_views, 4) (dx, dy, dz m,
        dyaw rad) shift each flight's viewpoints; ``camera_offset_m`` (3,) the camera in the body frame;
        ``depth_m`` (n_views,) the planned distance to the ship along each optical axis (None: unknown)."""
        n_views = len(path)
        plan_pos = np.asarray(path.positions, dtype=float)
        plan_yaw = np.asarray(path.yaw, dtype=float)
        plan_pitch = np.asarray(path.pitch, dtype=float)
        cmd_pos = np.broadcast_to(plan_pos, (batch, n_views, 3)).copy()
        cmd_yaw = np.broadcast_to(plan_yaw, (batch, n_views)).copy()
        if view_offsets is not None:
            view_offsets = np.asarray(view_offsets, dtype=float)
            if view_offsets.shape != (batch, n_views, 4):
                raise ValueError(f"view_offsets must have shape {(batch, n_views, 4)}, got {view_offsets.shape}")
            cmd_pos += view_offsets[..., :3]
            cmd_yaw += view_offsets[..., 3]
        # the camera (not the centre of mass) goes to the viewpoint: subtract the level body's camera offset
        cam = np.asarray(camera_offset_m)
        cy, sy = np.cos(cmd_yaw), np.sin(cmd_yaw)
        body = cmd_pos - np.stack([cy * cam[0] - sy * cam[1], sy * cam[0] + cy * cam[1],
                                   np.full_like(cy, cam[2])], axis=-1)
        depth = np.full(n_views, np.nan) if depth_m is None else np.asarray(depth_m, dtype=float)
        return cls(plan_pos, plan_yaw, plan_pitch, cmd_yaw, body, depth, leg_cruise=path.leg_speeds(),
                   home_view=int(np.argmin(path.view_ids())))

    def flown_through(self, vertex_speed: np.ndarray, leg_speed: np.ndarray, arriving: np.ndarray,
                      trigger_normal: np.ndarray, stop: np.ndarray | None = None) -> FlightTargets:
        """These targets with the fly-through reference's speeds, trigger planes and stops (n_views,) bool."""
        return replace(self, vertex_speed=vertex_speed, leg_speed=leg_speed, arriving=arriving,
                       trigger_normal=trigger_normal,
                       stop=np.zeros(self.n_views, dtype=bool) if stop is None else np.asarray(stop, dtype=bool))


@dataclass(slots=True)
class Segment:
    """The straight segment each flight's reference runs along, batch-first (n = batch, or the rows being
    replaced): start, end (n, 3) m of the centre of mass; yaw0 (n,) rad heading at the start; dyaw (n,) rad
    turn to the end (wrapped); length (n,) m; direction (n, 3) unit vector (zero on a zero-length segment);
    duration (n,) s of the reference along it; v0, v1, v_max (n,) m/s: the fly-through reference's speed at
    the start, at the end and its cruise limit (in stop mode, where segments run rest to rest, v0 = v1 = 0 and
    v_max the leg's cruise speed; 0: the profile's cruise)."""

    start: np.ndarray
    end: np.ndarray
    yaw0: np.ndarray
    dyaw: np.ndarray
    length: np.ndarray
    direction: np.ndarray
    duration: np.ndarray
    v0: np.ndarray
    v1: np.ndarray
    v_max: np.ndarray

    @classmethod
    def at_rest(cls, position: np.ndarray, yaw: np.ndarray) -> Segment:
        """Zero-length segments at ``position`` (n, 3) m with heading ``yaw`` (n,) rad."""
        n = len(yaw)
        return cls(position.copy(), position.copy(), yaw.copy(), np.zeros(n), np.zeros(n), np.zeros((n, 3)),
                   np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n))

    def assign(self, rows: np.ndarray, other: Segment) -> None:
        """Replace rows ``rows`` (m,) int of every array by ``other``'s m rows, in place."""
        for f in fields(self):
            getattr(self, f.name)[rows] = getattr(other, f.name)


class Shot(NamedTuple):
    """Photos being taken, m rows: time (m,) s of the shutter; position (m, 3) m, yaw, pitch, roll (m,) rad:
    the true camera pose in the ship's frame at the shutter; saturated (m,) bool: gimbal at a stop;
    estimated_position (m, 3) m and estimated_yaw (m,) rad: what the navigation recorded (the image's
    position prior); blur_px (m,); charge (m,) battery fraction; ship_motion (m, 4): heave m, roll, pitch,
    yaw rad of the ship at the shutter."""

    time: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    roll: np.ndarray
    saturated: np.ndarray
    estimated_position: np.ndarray
    estimated_yaw: np.ndarray
    blur_px: np.ndarray
    charge: np.ndarray
    ship_motion: np.ndarray


def _nan(*shape: int) -> np.ndarray:
    return np.full(shape, np.nan)


# per-view width of the Shot fields that are vectors (the rest: one value per view)
_SHOT_WIDTH = {"position": 3, "estimated_position": 3, "ship_motion": 4}


@dataclass(slots=True)
class CaptureLog:
    """The photos of a batch of flights; NaN (False) where not (yet) taken.

    shots: a :class:`Shot` of (batch, n_views, ...) arrays, its fields also read directly (``log.time``,
    ``log.position`` ...); offsets (batch, n_views, 4): (dx, dy, dz m, dyaw rad) of the true pose against the
    plan; estimated_offsets (batch, n_views, 4): the same for the navigation's record; taken (batch, n_views)
    bool.
    """

    shots: Shot
    offsets: np.ndarray
    estimated_offsets: np.ndarray
    taken: np.ndarray

    @classmethod
    def empty(cls, batch: int, n_views: int) -> CaptureLog:
        def blank(name: str) -> np.ndarray:
            if name == "saturated":
                return np.zeros((batch, n_views), dtype=bool)
            width = _SHOT_WIDTH.get(name)
            return _nan(batch, n_views, *((width,) if width else ()))
        return cls(Shot(*(blank(name) for name in Shot._fields)), _nan(batch, n_views, 4), _nan(batch, n_views, 4),
                   np.zeros((batch, n_views), dtype=bool))

    def __getattr__(self, name: str) -> np.ndarray:
        if name in Shot._fields:                 # only called for what is not a field of the log itself
            value: np.ndarray = getattr(self.shots, name)
            return value
        raise AttributeError(name)

    def record(self, rows: np.ndarray, views: np.ndarray, shot: Shot, targets: FlightTargets) -> None:
        """Store photo ``views`` (m,) int of flights ``rows`` (m,) int; offsets are against the unperturbed
        plan."""
        for stored, taken in zip(self.shots, shot, strict=True):
            stored[rows, views] = taken
        self.offsets[rows, views, :3] = shot.position - targets.plan_position[views]
        self.offsets[rows, views, 3] = wrap_angle(shot.yaw - targets.plan_yaw[views])
        self.estimated_offsets[rows, views, :3] = shot.estimated_position - targets.plan_position[views]
        self.estimated_offsets[rows, views, 3] = wrap_angle(shot.estimated_yaw - targets.plan_yaw[views])
        self.taken[rows, views] = True

    def capture_sets(self, camera: Camera, view_id: np.ndarray | None = None) -> tuple[CaptureSet, ...]:
        """One :class:`CaptureSet` per flight, holding only the views it took; ``view_id`` (n_views,) int: the
        path's :attr:`~wrp_eval.planning.path.FlightPath.view_id` (None: in plan order)."""
        return tuple(CaptureSet(self.position[i, taken], self.yaw[i, taken], self.pitch[i, taken],
                                np.flatnonzero(taken), camera, roll=self.roll[i, taken],
                                prior_positions=self.estimated_position[i, taken], blur_px=self.blur_px[i, taken],
                                view_id=None if view_id is None else np.asarray(view_id)[taken])
                     for i, taken in enumerate(self.taken))


TRAJECTORY_FIELDS = ("position", "reference", "yaw", "tilt", "thrust", "wind", "drag", "power", "charge")


@dataclass(slots=True)
class TrajectoryLog:
    """Down-sampled records, one row per record time; see :class:`Trajectory` for the fields' units."""

    time: list[float] = field(default_factory=list)
    rows: dict[str, list[np.ndarray]] = field(default_factory=lambda: {k: [] for k in TRAJECTORY_FIELDS})

    def append(self, t: float, **values: np.ndarray) -> None:
        """Record time ``t`` s and one (batch, ...) array per :data:`TRAJECTORY_FIELDS` name (copied: the
        caller's buffers change afterwards)."""
        self.time.append(t)
        for name in TRAJECTORY_FIELDS:
            self.rows[name].append(np.array(values[name]))

    def trajectory(self) -> Trajectory:
        """time (T,) and every field batch-first (batch, T, ...)."""
        return Trajectory(np.asarray(self.time), *(np.stack(self.rows[k], axis=1) for k in TRAJECTORY_FIELDS))


@dataclass(slots=True)
class FlightState:
    """What the flight logic carries from chunk to chunk, for a batch of flights.

    phase (batch,) int: TRANSIT / SETTLE / DWELL / DONE / ENDED. index (batch,) int: the viewpoint the
    reference is flying to. photo (batch,) int: the next viewpoint to photograph (= index in stop mode; in
    fly-through the vehicle may still be short of a view the reference has passed). phase_time (batch,) s
    in the current phase (it stands still while the leash holds the reference back). segment: the
    reference's current segment. outcome (batch,) int: COMPLETED (also while flying) ... LOST_ENERGY.
    flight_time (batch,) s: time of the last photo or of the end (mission time: the swaps included).
    captures: the photos taken so far. sortie (batch,) int: the sortie flying (1 ..); sortie_start (batch,) s:
    when it started; resume_at (batch,) s: when an AWAY flight resumes; view_sortie (batch, n_views) int: the
    sortie that took each view (0: not taken); sortie_views (batch,) int: the views the current sortie took;
    progress_m (batch,) m and progress_time (batch,) s: the
    closest the vehicle has come to its waypoint on this leg, and when; progress_view (batch,) int: the leg's
    waypoint.
    """

    phase: np.ndarray
    index: np.ndarray
    photo: np.ndarray
    phase_time: np.ndarray
    segment: Segment
    outcome: np.ndarray
    flight_time: np.ndarray
    captures: CaptureLog
    sortie: np.ndarray
    sortie_start: np.ndarray
    resume_at: np.ndarray
    view_sortie: np.ndarray
    sortie_views: np.ndarray
    progress_m: np.ndarray
    progress_time: np.ndarray
    progress_view: np.ndarray

    @classmethod
    def start(cls, targets: FlightTargets, t: float = 0.0) -> FlightState:
        """Every flight hovering at its first viewpoint at ``t`` s, settling there before the first photo."""
        batch = targets.batch
        return cls(np.full(batch, SETTLE), np.zeros(batch, dtype=int), np.zeros(batch, dtype=int), np.zeros(batch),
                   Segment.at_rest(targets.body[:, 0], targets.yaw[:, 0]), np.full(batch, COMPLETED),
                   np.zeros(batch), CaptureLog.empty(batch, targets.n_views), np.ones(batch, dtype=int),
                   np.full(batch, float(t)), np.full(batch, np.inf), np.zeros((batch, targets.n_views), dtype=int),
                   np.zeros(batch, dtype=int), np.full(batch, np.inf), np.full(batch, float(t)),
                   np.zeros(batch, dtype=int))

    @property
    def flying(self) -> NDArray[np.bool_]:
        """(batch,) bool: neither done, ended nor away for a battery swap."""
        return self.phase < DONE

    @property
    def active(self) -> NDArray[np.bool_]:
        """(batch,) bool: flying or away between two sorties (the mission is not over)."""
        active: NDArray[np.bool_] = self.flying | (self.phase == AWAY)
        return active

    @property
    def failed(self) -> np.ndarray:
        """(batch,) bool: crashed or out of the simulator's time."""
        return np.isin(self.outcome, FAILURES)
