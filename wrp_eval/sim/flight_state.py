"""Per-flight state of a batch of path flights: the values the flight loop's phase functions read and update.

Everything is batch-first: row i is flight i of the batch (``batch`` flights of one path of ``n_views``
viewpoints). The MuJoCo side (body poses, controls) is not here: it lives in the rollout buffers of
:mod:`wrp_eval.sim.flight`; this module holds what the flight logic keeps between chunks.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from wrp_eval.sim.captures import CaptureSet
from wrp_eval.sim.controller import wrap_angle
from wrp_eval.sim.results import Trajectory

# flight phases: fly the segment, wait to be within the tolerances, hold still, then the photo (trigger)
TRANSIT, SETTLE, DWELL, DONE, FAILED = 0, 1, 2, 3, 4

# failure causes, in the order they are reported when several hold at once (0: not failed)
NO_FAILURE, NON_FINITE, DITCHED, STALLED, LOST, TIMED_OUT = 0, 1, 2, 3, 4, 5


@dataclass(frozen=True)
class FlightTargets:
    """Where each flight of a batch is sent.

    plan_position (n_views, 3) m, plan_yaw (n_views,) rad, plan_pitch (n_views,) rad: the unperturbed
    plan's camera poses (capture offsets are measured against them). yaw (batch, n_views) rad: the
    commanded heading per flight (plan + view offsets); body (batch, n_views, 3) m: where the centre of
    mass must be for the camera to sit on the commanded viewpoint at level attitude.
    """

    plan_position: np.ndarray
    plan_yaw: np.ndarray
    plan_pitch: np.ndarray
    yaw: np.ndarray
    body: np.ndarray

    @property
    def batch(self) -> int:
        return int(self.body.shape[0])

    @property
    def n_views(self) -> int:
        return int(self.body.shape[1])

    @classmethod
    def from_path(cls, path, batch: int, view_offsets: np.ndarray | None,
                  camera_offset_m) -> FlightTargets:
        """Targets of ``batch`` flights of ``path``; ``view_offsets`` (batch, n_views, 4) (dx, dy, dz m,
        dyaw rad) shift each flight's viewpoints; ``camera_offset_m`` (3,) the camera in the body frame."""
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
        return cls(plan_pos, plan_yaw, plan_pitch, cmd_yaw, body)


@dataclass(slots=True)
class Segment:
    """The straight segment each flight's reference runs along, batch-first (n = batch, or the rows being
    replaced): start, end (n, 3) m of the centre of mass; yaw0 (n,) rad heading at the start; dyaw (n,) rad
    turn to the end (wrapped); length (n,) m; direction (n, 3) unit vector (zero on a zero-length segment);
    duration (n,) s of the reference along it."""

    start: np.ndarray
    end: np.ndarray
    yaw0: np.ndarray
    dyaw: np.ndarray
    length: np.ndarray
    direction: np.ndarray
    duration: np.ndarray

    @classmethod
    def at_rest(cls, position: np.ndarray, yaw: np.ndarray) -> Segment:
        """Zero-length segments at ``position`` (n, 3) m with heading ``yaw`` (n,) rad."""
        n = len(yaw)
        return cls(position.copy(), position.copy(), yaw.copy(), np.zeros(n), np.zeros(n), np.zeros((n, 3)),
                   np.zeros(n))

    def assign(self, rows: np.ndarray, other: Segment) -> None:
        """Replace rows ``rows`` (m,) int of every array by ``other``'s m rows, in place."""
        for f in fields(self):
            getattr(self, f.name)[rows] = getattr(other, f.name)


@dataclass(slots=True)
class CaptureLog:
    """The photos of a batch of flights, (batch, n_views, ...); NaN (False) where not (yet) taken.

    position (batch, n_views, 3) m and yaw (batch, n_views) rad of the camera; pitch (batch, n_views) rad the
    gimbal achieved; residual_roll (batch, n_views) rad the gimbal could not compensate; saturated
    (batch, n_views) bool; offsets (batch, n_views, 4): (dx, dy, dz m, dyaw rad) against the plan;
    taken (batch, n_views) bool; time (batch, n_views) s.
    """

    position: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    residual_roll: np.ndarray
    saturated: np.ndarray
    offsets: np.ndarray
    taken: np.ndarray
    time: np.ndarray

    @classmethod
    def empty(cls, batch: int, n_views: int) -> CaptureLog:
        return cls(np.full((batch, n_views, 3), np.nan), np.full((batch, n_views), np.nan),
                   np.full((batch, n_views), np.nan), np.full((batch, n_views), np.nan),
                   np.zeros((batch, n_views), dtype=bool), np.full((batch, n_views, 4), np.nan),
                   np.zeros((batch, n_views), dtype=bool), np.full((batch, n_views), np.nan))

    def record(self, rows: np.ndarray, views: np.ndarray, pose, targets: FlightTargets, t: float) -> None:
        """Store photo ``views`` (m,) int of flights ``rows`` (m,) int taken at ``t`` s; ``pose`` is a
        :class:`wrp_eval.sim.phases.CapturePose` of m rows. Offsets are against the unperturbed plan."""
        self.position[rows, views] = pose.position
        self.yaw[rows, views] = pose.yaw
        self.pitch[rows, views] = pose.pitch
        self.residual_roll[rows, views] = pose.residual_roll
        self.saturated[rows, views] = pose.saturated
        self.offsets[rows, views, :3] = pose.position - targets.plan_position[views]
        self.offsets[rows, views, 3] = wrap_angle(pose.yaw - targets.plan_yaw[views])
        self.taken[rows, views] = True
        self.time[rows, views] = t

    def capture_sets(self, camera) -> tuple[CaptureSet, ...]:
        """One :class:`CaptureSet` per flight, holding only the views it took."""
        return tuple(CaptureSet(self.position[i, taken], self.yaw[i, taken], self.pitch[i, taken],
                                np.flatnonzero(taken), camera) for i, taken in enumerate(self.taken))


TRAJECTORY_FIELDS = ("position", "reference", "yaw", "tilt", "thrust", "wind", "drag")


@dataclass(slots=True)
class TrajectoryLog:
    """Down-sampled records, one row per record time; see :class:`Trajectory` for the fields' units."""

    time: list = field(default_factory=list)
    rows: dict = field(default_factory=lambda: {k: [] for k in TRAJECTORY_FIELDS})

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

    phase (batch,) int: TRANSIT / SETTLE / DWELL / DONE / FAILED. index (batch,) int: the viewpoint being
    flown to (or photographed). phase_time (batch,) s in the current phase (it stands still while the
    leash holds the reference back). segment: the reference's current segment. lost_time (batch,) s
    farther than the fail distance from the reference; held_time (batch,) s held back by the leash.
    failure (batch,) int: cause code (NO_FAILURE ... TIMED_OUT). flight_time (batch,) s: time of the last
    photo or of the failure. captures: the photos taken so far.
    """

    phase: np.ndarray
    index: np.ndarray
    phase_time: np.ndarray
    segment: Segment
    lost_time: np.ndarray
    held_time: np.ndarray
    failure: np.ndarray
    flight_time: np.ndarray
    captures: CaptureLog

    @classmethod
    def start(cls, targets: FlightTargets) -> FlightState:
        """Every flight hovering at its first viewpoint, settling there before the first photo."""
        batch = targets.batch
        return cls(np.full(batch, SETTLE), np.zeros(batch, dtype=int), np.zeros(batch),
                   Segment.at_rest(targets.body[:, 0], targets.yaw[:, 0]), np.zeros(batch), np.zeros(batch),
                   np.full(batch, NO_FAILURE), np.zeros(batch), CaptureLog.empty(batch, targets.n_views))

    @property
    def flying(self) -> np.ndarray:
        """(batch,) bool: neither done nor failed."""
        return self.phase < DONE
