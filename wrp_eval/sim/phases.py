"""The flight loop's phase functions, once per chunk, for a whole batch of flights at once.

In loop order: :func:`reference` (where each flight's setpoint is, with the leash), :func:`check_failures`,
:func:`no_headway` and :func:`check_returns` / :func:`apply_endings` (with :func:`swap_batteries` and
:func:`resume` for a battery swap), :func:`transitions` (TRANSIT -> SETTLE -> DWELL -> trigger) /
:func:`take_photos` / :func:`apply_transitions`, :func:`setpoints` + :func:`control` (position loop ->
motor thrusts and attitude targets), :func:`tick` (the phase clock). Shapes: ``batch`` flights; the
control functions work on the ``padded`` batch of the MuJoCo models (the flights plus parked fillers).
The pure functions return new arrays; the ``apply_*`` functions, :func:`take_photos` and :func:`tick`
update the :class:`FlightState` in place.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.compiled import as_rows, contiguous, kernel
from wrp_eval.sim.capture_mode import through_profile, through_row
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.controller import PositionController, wrap_angle, wrapped
from wrp_eval.sim.flight_state import (
    AWAY,
    COMPLETED,
    DITCHED,
    DONE,
    DWELL,
    ENDED,
    LOST_ENERGY,
    LOST_HEADWAY,
    LOST_OUTSIDE,
    NON_FINITE,
    RETURNED_BATTERY,
    RETURNED_HEADWAY,
    RETURNED_WIND,
    RETURNED_WIND_AVERAGE,
    SETTLE,
    TIMED_OUT,
    TRANSIT,
    FlightState,
    FlightTargets,
    Segment,
    Shot,
)
from wrp_eval.sim.vehicle import QuadrotorParams

YAW_RATE_REF_RAD_S = np.radians(60.0)  # reference yaw rate when a segment is mostly a rotation


# -- reference speed profile -----------------------------------------------------------------------------
@kernel
def _trapezoid(length: float, tau: float, v_max: float, a_max: float) -> tuple[float, float, float, float, float]:
    """Rest-to-rest trapezoidal speed profile: distance s, speed v, acceleration a and the running integral
    of s, S = int s dt, at time tau s, plus the duration. Before 0: at rest at 0; after: at rest at ``length``."""
    tri = length < v_max ** 2 / a_max
    v_peak = np.sqrt(np.maximum(length, 0.0) * a_max) if tri else v_max
    t_acc = v_peak / a_max
    t_cruise = 0.0 if tri else length / v_max - t_acc
    duration = 2.0 * t_acc + t_cruise
    s_acc = 0.5 * a_max * t_acc ** 2
    big_s_acc = a_max * t_acc ** 3 / 6.0
    big_s_end = big_s_acc + s_acc * t_cruise + 0.5 * v_peak * t_cruise ** 2 + (length * t_acc - big_s_acc)
    after = np.maximum(tau - duration, 0.0)
    moving = tau >= 0.0 and tau < duration
    tau = np.minimum(np.maximum(tau, 0.0), duration)
    t_c = tau - t_acc
    t_dec = duration - tau
    if tau < t_acc:
        s, v, a, big_s = 0.5 * a_max * tau ** 2, a_max * tau, a_max, a_max * tau ** 3 / 6.0
    elif t_dec < t_acc:
        s, v, a = length - 0.5 * a_max * t_dec ** 2, a_max * t_dec, -a_max
        big_s = big_s_end - (length * t_dec - a_max * t_dec ** 3 / 6.0)
    else:
        s, v, a = s_acc + v_peak * t_c, v_peak, 0.0
        big_s = big_s_acc + s_acc * t_c + 0.5 * v_peak * t_c ** 2
    return s, v, a if moving else 0.0, big_s + length * after, duration


@kernel
def profile_row(length: float, tau: float, v_max: float, a_max: float,
                t_jerk: float) -> tuple[float, float, float, float]:
    """(s, v, a, duration) of :func:`reference_profile` for one segment at one time."""
    s1, v1, a1, big1, duration = _trapezoid(length, tau, v_max, a_max)
    if t_jerk <= 0.0:
        return s1, v1, a1, duration
    s0, v0, _, big0, _ = _trapezoid(length, tau - t_jerk, v_max, a_max)
    return (big1 - big0) / t_jerk, (s1 - s0) / t_jerk, (v1 - v0) / t_jerk, duration + t_jerk


@kernel
def _profile_rows(length: NDArray[np.float64], tau: NDArray[np.float64], v_max: NDArray[np.float64], a_max: float,
                  t_jerk: float) -> NDArray[np.float64]:
    out = np.empty((4, length.size))
    for row in range(length.size):
        out[0, row], out[1, row], out[2, row], out[3, row] = profile_row(length[row], tau[row], v_max[row], a_max,
                                                                         t_jerk)
    return out


def reference_profile(length: ArrayLike, tau: ArrayLike, v_max: ArrayLike, a_max: float,
                      t_jerk: float) -> tuple[Any, ...]:
    """Jerk-limited rest-to-rest profile: distance, speed, acceleration (each (n,)) at time tau, and the
    duration (n,); ``length``, ``tau`` and the cruise speed ``v_max`` broadcast, ``a_max`` and ``t_jerk`` are
    numbers.

    The trapezoidal speed profile averaged over a moving window of ``t_jerk`` s: the acceleration then
    ramps over t_jerk instead of jumping, i.e. the jerk is limited to a_max / t_jerk, at most twice that
    on a segment too short to reach a_max (PX4 shapes its auto-mode setpoints with a jerk limit too,
    MPC_JERK_AUTO, default 4 m/s^3). A step in the
    acceleration demand is what the attitude loop cannot follow without lag: with the trapezoid alone the
    vehicle overshot each viewpoint by ~10 cm (README.md). Exact box averages from the closed forms:
    s_j = (S(t) - S(t-T)) / T, v_j = (s(t) - s(t-T)) / T, a_j = (v(t) - v(t-T)) / T.
    """
    length, tau, v_max = np.broadcast_arrays(np.asarray(length, dtype=float), np.asarray(tau, dtype=float),
                                             np.asarray(v_max, dtype=float))
    out = _profile_rows(np.ascontiguousarray(length).reshape(-1), np.ascontiguousarray(tau).reshape(-1),
                        np.ascontiguousarray(v_max).reshape(-1), float(a_max), float(t_jerk))
    return tuple(x.reshape(length.shape)[()] for x in out)     # [()]: a number for numbers


@dataclass(frozen=True)
class Profile:
    """Limits of the reference along a segment: cruise speed m/s, acceleration m/s^2, jerk window s (the
    averaging window a/j of :func:`reference_profile`; 0: plain trapezoid); through: fly-through segments
    (:func:`wrp_eval.sim.capture_mode.through_profile`, from the segment's v0 to its v1) instead of rest to
    rest."""

    cruise_m_s: float
    acceleration_m_s2: float
    jerk_window_s: float
    through: bool = False

    @classmethod
    def of(cls, cruise_m_s: float, sec: SimSection, through: bool | None = None) -> Profile:
        """The profile of ``sec`` at ``cruise_m_s``; ``through``: fly-through segments (None: as
        ``sec.capture.mode`` says; a mission whose path sets per-view modes is flown through when any view is)."""
        a_max = sec.acceleration_m_s2
        return cls(cruise_m_s, a_max, a_max / sec.jerk_m_s3 if sec.jerk_m_s3 else 0.0,
                   sec.capture.mode == "fly-through" if through is None else bool(through))

    def along(self, seg: Segment, tau: np.ndarray) -> tuple[Any, ...]:
        """(s, v, a, duration) (n,) on the segments ``seg`` at ``tau`` (n,) s, in this profile's mode (rest to rest
        at each segment's own cruise ``v_max``, or this profile's where it is 0)."""
        if self.through:
            return through_profile(seg.length, tau, seg.v0, seg.v1, seg.v_max, self.acceleration_m_s2,
                                   self.jerk_window_s)
        return reference_profile(seg.length, tau, np.where(seg.v_max > 0.0, seg.v_max, self.cruise_m_s),
                                 self.acceleration_m_s2, self.jerk_window_s)


def plan_segments(start: np.ndarray, end: np.ndarray, yaw0: np.ndarray, yaw1: np.ndarray,
                  profile: Profile, v0: np.ndarray | None = None, v1: np.ndarray | None = None,
                  v_max: np.ndarray | None = None) -> Segment:
    """Segments from ``start`` to ``end`` (n, 3) m turning from ``yaw0`` to ``yaw1`` (n,) rad, in fly-through
    from speed ``v0`` to ``v1`` with cruise limit ``v_max`` (n,) m/s (None: rest to rest). A segment lasts
    the speed profile's time, or longer where the turn needs it at YAW_RATE_REF_RAD_S."""
    delta = end - start
    length = np.linalg.norm(delta, axis=1)
    direction = delta / np.maximum(length, 1e-12)[:, None]
    dyaw = wrap_angle(yaw1 - yaw0)
    zeros = np.zeros_like(length)
    seg = Segment(start, end, yaw0, dyaw, length, direction, zeros, zeros if v0 is None else v0,
                  zeros if v1 is None else v1, zeros if v_max is None else v_max)
    seg.duration = np.maximum(profile.along(seg, zeros)[3], np.abs(dyaw) / YAW_RATE_REF_RAD_S)
    return seg


# -- reference --------------------------------------------------------------------------------------------
class Reference(NamedTuple):
    """Setpoints of a batch: position, velocity, acceleration (batch, 3) m, m/s, m/s^2; yaw (batch,) rad;
    distance_sq (batch,) m^2 from the vehicle to the reference position; held (batch,) bool: in transit
    and beyond the leash, so the reference waits."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    yaw: np.ndarray
    distance_sq: np.ndarray
    held: np.ndarray


@kernel
def _reference_rows(transit: NDArray[np.bool_], phase_time: NDArray[np.float64], start: NDArray[np.float64],
                    end: NDArray[np.float64], yaw0: NDArray[np.float64], dyaw: NDArray[np.float64],
                    length: NDArray[np.float64], direction: NDArray[np.float64], duration: NDArray[np.float64],
                    v0: NDArray[np.float64], v1: NDArray[np.float64], v_max: NDArray[np.float64],
                    position: NDArray[np.float64], through: bool, cruise_m_s: float, a_max: float, t_jerk: float,
                    leash_m: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                                             NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """The arrays of :class:`Reference` (:func:`reference`), row by row."""
    n = transit.size
    ref_pos, ref_vel, ref_acc = np.empty((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    yaw, dist2, held = np.empty(n), np.empty(n), np.zeros(n, np.bool_)
    for row in range(n):
        if through:
            s, v, a, _ = through_row(length[row], phase_time[row], v0[row], v1[row], v_max[row], a_max, t_jerk)
        else:       # the leg's own cruise (0: the profile's)
            s, v, a, _ = profile_row(length[row], phase_time[row], v_max[row] if v_max[row] > 0.0 else cruise_m_s,
                                     a_max, t_jerk)
        d2 = 0.0
        for d in range(3):
            ref_pos[row, d] = start[row, d] + direction[row, d] * s if transit[row] else end[row, d]
            d2 += (position[row, d] - ref_pos[row, d]) ** 2
        dist2[row] = d2
        # Leash: a vehicle held back by a head wind is not "lost"; its reference waits for it (what a waypoint
        # autopilot does: it flies towards the next waypoint as fast as it can).
        held[row] = transit[row] and d2 > leash_m ** 2
        if transit[row] and not held[row]:
            for d in range(3):
                ref_vel[row, d] = direction[row, d] * v
                ref_acc[row, d] = direction[row, d] * a
        frac = 1.0
        if transit[row]:
            frac = np.minimum(np.maximum(phase_time[row] / np.maximum(duration[row], 1e-9), 0.0), 1.0)
        yaw[row] = yaw0[row] + dyaw[row] * frac
    return ref_pos, ref_vel, ref_acc, yaw, dist2, held


def reference(state: FlightState, position: np.ndarray, profile: Profile, leash_m: float) -> Reference:
    """Each flight's reference at its phase time: along the segment in TRANSIT, at the segment's end
    otherwise. ``position`` (batch, 3) m: the vehicles' centres of mass as the navigation estimates them."""
    seg = state.segment
    return Reference(*_reference_rows(state.phase == TRANSIT, state.phase_time, seg.start, seg.end, seg.yaw0,
                                      seg.dyaw, seg.length, seg.direction, seg.duration, seg.v0, seg.v1, seg.v_max,
                                      position, profile.through, float(profile.cruise_m_s),
                                      float(profile.acceleration_m_s2), float(profile.jerk_window_s), float(leash_m)))


# -- how flights end ----------------------------------------------------------------------------------------
@kernel
def _failure_rows(phase: NDArray[np.int_], position: NDArray[np.float64], velocity: NDArray[np.float64],
                  out_of_time: NDArray[np.bool_]) -> NDArray[np.int64]:
    """(batch,) outcome codes of :func:`check_failures`, row by row."""
    n = phase.size
    cause = np.full(n, COMPLETED, np.int64)
    for row in range(n):
        if phase[row] >= DONE:
            continue
        # one non-finite component makes the row's sum non-finite (summed as numpy sums a row: left to right)
        total = (position[row, 0] + position[row, 1] + position[row, 2]) + (
            velocity[row, 0] + velocity[row, 1] + velocity[row, 2])
        if not np.isfinite(total):
            cause[row] = NON_FINITE
        elif position[row, 2] < 0.0:
            cause[row] = DITCHED
        elif out_of_time[row]:
            cause[row] = TIMED_OUT
    return cause


def check_failures(state: FlightState, position: np.ndarray, velocity: np.ndarray,
                   out_of_time: NDArray[np.bool_] | bool) -> np.ndarray:
    """(batch,) outcome codes of flights failing now (COMPLETED elsewhere): non-finite state, below the sea
    surface (ditched), or still flying when ``out_of_time`` ((batch,) bool or one bool for all: the sortie has
    run past the simulator's limit). ``position``, ``velocity`` (batch, 3): true."""
    n = len(state.phase)
    return _failure_rows(state.phase, as_rows("position", position, (n, 3)), as_rows("velocity", velocity, (n, 3)),
                         contiguous(as_rows("out_of_time", out_of_time, (n,), np.bool_), np.bool_))


@kernel
def _headway_rows(phase: NDArray[np.int_], index: NDArray[np.int_], end: NDArray[np.float64],
                  position: NDArray[np.float64], progress_m: NDArray[np.float64], progress_time: NDArray[np.float64],
                  progress_view: NDArray[np.int_], t: float, timeout_s: float, step_m: float,
                  leash_m: float) -> NDArray[np.bool_]:
    """(batch,) bool of :func:`no_headway`, row by row; the progress record is updated in place."""
    n = phase.size
    stuck = np.zeros(n, np.bool_)
    for row in range(n):
        distance = np.sqrt((position[row, 0] - end[row, 0]) ** 2 + (position[row, 1] - end[row, 1]) ** 2
                           + (position[row, 2] - end[row, 2]) ** 2)
        if index[row] != progress_view[row] or distance < progress_m[row] - step_m:
            progress_m[row], progress_time[row] = distance, t
        progress_view[row] = index[row]
        stuck[row] = phase[row] < DONE and t - progress_time[row] >= timeout_s and distance > leash_m
    return stuck


def no_headway(state: FlightState, position: np.ndarray, t: float, timeout_s: float, progress_m: float,
               leash_m: float) -> np.ndarray:
    """(batch,) bool: flights that have not come ``progress_m`` closer to their waypoint (the current segment's
    end) for ``timeout_s`` s and are more than ``leash_m`` from it (a vehicle holding at its viewpoint makes no
    progress and needs none). Updates the state's progress record (a new waypoint starts a new record).
    ``position`` (batch, 3) m: as the navigation estimates it."""
    n = len(state.phase)
    return _headway_rows(state.phase, state.index, state.segment.end, as_rows("position", position, (n, 3)),
                         state.progress_m, state.progress_time, state.progress_view, float(t), float(timeout_s),
                         float(progress_m), float(leash_m))


@kernel
def _return_rows(phase: NDArray[np.int_], battery_due: NDArray[np.bool_], px4_wind: NDArray[np.bool_],
                 operator_wind: NDArray[np.bool_], stuck: NDArray[np.bool_],
                 home_reachable: NDArray[np.bool_]) -> NDArray[np.int64]:
    """(batch,) outcome codes of :func:`check_returns`, row by row."""
    n = phase.size
    cause = np.zeros(n, np.int64)
    for row in range(n):
        if phase[row] >= DONE:
            continue
        if battery_due[row]:    # due home on energy, but against a wind it cannot beat: lost
            cause[row] = RETURNED_BATTERY if home_reachable[row] else LOST_ENERGY
        elif px4_wind[row]:
            cause[row] = RETURNED_WIND
        elif operator_wind[row]:
            cause[row] = RETURNED_WIND_AVERAGE
        elif stuck[row]:
            cause[row] = RETURNED_HEADWAY if home_reachable[row] else LOST_HEADWAY
    return cause


def check_returns(state: FlightState, battery_due: np.ndarray, px4_wind: np.ndarray, operator_wind: np.ndarray,
                  stuck: np.ndarray, home_reachable: np.ndarray) -> np.ndarray:
    """(batch,) outcome codes of flights the autopilot sends home now (COMPLETED elsewhere), each (batch,) bool:
    the battery at its reserve plus the energy home; the PX4-style wind limit; the operator's average-wind
    policy; no headway (``stuck``). A flight due home on energy or without headway whose home is not
    ``home_reachable`` (no ground speed towards it at the top airspeed, or not the energy) is lost."""
    flags = [np.asarray(v, dtype=np.bool_) for v in (battery_due, px4_wind, operator_wind, stuck, home_reachable)]
    if any(f.shape != state.phase.shape for f in flags):     # the kernel does not check its indices
        raise ValueError(f"check_returns needs ({len(state.phase)},) flags, got {[f.shape for f in flags]}")
    return _return_rows(state.phase, *flags)


def apply_endings(state: FlightState, cause: np.ndarray, t: float) -> None:
    """Mark the flights with a cause (not COMPLETED) ENDED at ``t`` s with it."""
    newly = cause != COMPLETED
    if not newly.any():
        return
    state.outcome = np.where(newly, cause, state.outcome)
    state.flight_time = np.where(newly, t, state.flight_time)
    state.phase = np.where(newly, ENDED, state.phase)


def swap_batteries(state: FlightState, cause: np.ndarray, max_sorties: int) -> tuple[NDArray[np.intp], np.ndarray]:
    """Flights sent home on energy with sorties left go AWAY for a battery swap instead of ending: their cause
    becomes COMPLETED (the mission goes on). A sortie that took no view ends the mission instead (the battery
    is spent getting to the breakpoint and back: another one would do the same; an operator stops there).
    Returns (rows (m,) int of those flights, the causes left)."""
    home = cause == RETURNED_BATTERY
    if not home.any():      # the usual chunk: no copies
        return np.empty(0, dtype=int), cause
    swap = home & (state.sortie < max_sorties) & (state.sortie_views > 0)
    rows = np.flatnonzero(swap)
    state.phase[rows] = AWAY
    return rows, np.where(swap, COMPLETED, cause)


def resume(state: FlightState, targets: FlightTargets, rows: np.ndarray, position: np.ndarray, yaw: np.ndarray,
           t: float, profile: Profile) -> None:
    """Flights ``rows`` (m,) int start their next sortie at ``t`` s, hovering at their breakpoint ``position``
    (m, 3) m with heading ``yaw`` (m,) rad: the reference flies from there to the viewpoint it was flying to
    (from rest; in fly-through on to that viewpoint's planned speed), the way a resumed mission does."""
    if not rows.size:
        return
    k = state.index[rows]
    speeds = {}
    if profile.through:
        if targets.vertex_speed is None or targets.leg_speed is None:
            raise ValueError("fly-through targets without their speeds (FlightTargets.flown_through)")
        speeds = dict(v0=np.zeros(rows.size), v1=targets.vertex_speed[rows, k],
                      v_max=targets.leg_speed[rows, np.maximum(k - 1, 0)])
    elif targets.leg_cruise is not None and targets.leg_cruise.size:
        speeds = dict(v_max=targets.leg_cruise[np.maximum(k - 1, 0)])
    state.segment.assign(rows, plan_segments(position, targets.body[rows, k], yaw, targets.yaw[rows, k], profile,
                                             **speeds))
    state.phase[rows] = TRANSIT
    state.phase_time[rows] = 0.0
    state.sortie[rows] += 1
    state.sortie_views[rows] = 0
    state.sortie_start[rows] = t
    state.resume_at[rows] = np.inf
    state.progress_m[rows] = np.inf
    state.progress_time[rows] = t


def outcome_reason(cause: int, t: float, view: int, sec: SimSection) -> str:
    """The text of outcome ``cause`` at ``t`` s before viewpoint ``view`` ("" for COMPLETED)."""
    m = sec.mission
    texts = {
        NON_FINITE: f"non-finite state at t={t:.2f}s",
        DITCHED: f"ditched (below sea level) at t={t:.2f}s",
        TIMED_OUT: f"a sortie not finished within max_flight_time_s={sec.max_flight_time_s:g}",
        RETURNED_BATTERY: (f"returned home: battery at its reserve ({sec.battery.reserve:g}) plus the energy home at "
                           f"t={t:.2f}s (before view {view}); the mission ends (max_sorties {m.max_sorties} flown, or "
                           "the sortie took no view)"),
        LOST_ENERGY: (f"lost: battery at its reserve plus the energy home at t={t:.2f}s (before view {view}) and no "
                      f"way home at {m.return_airspeed_m_s:g} m/s airspeed"),
        RETURNED_WIND: (f"returned home: wind estimate over the PX4-style limit {m.px4_wind_limit_m_s or 0:g} m/s at "
                        f"t={t:.2f}s (before view {view})"),
        RETURNED_WIND_AVERAGE: (f"returned home: {m.operator_wind_average_s:g} s average wind over the operator's "
                                f"limit {m.operator_wind_limit_m_s or 0:g} m/s at t={t:.2f}s (before view {view})"),
        RETURNED_HEADWAY: (f"returned home: no headway towards view {view} for {m.headway_timeout_s:g} s at "
                           f"t={t:.2f}s"),
        LOST_HEADWAY: (f"lost: no headway towards view {view} and no way home at {m.return_airspeed_m_s:g} m/s "
                       f"airspeed at t={t:.2f}s"),
        LOST_OUTSIDE: f"lost: left the wind field at t={t:.2f}s (before view {view})",
    }
    return texts.get(cause, "")


def outcome_reasons(state: FlightState, sec: SimSection) -> tuple[str, ...]:
    """(batch,) texts of the flights' outcomes ("" for a completed flight)."""
    return tuple(outcome_reason(c, t, v, sec) for c, t, v in
                 zip(state.outcome.tolist(), state.flight_time.tolist(), state.photo.tolist(), strict=True))


# -- phase transitions and the photo trigger ---------------------------------------------------------------
class Transitions(NamedTuple):
    """(batch,) bool each: the segment's reference has arrived at a stop (TRANSIT -> SETTLE); within the
    tolerances or out of settle time (SETTLE -> DWELL); dwelt long enough (DWELL -> photo); fly-through: the
    reference has passed a viewpoint without stopping (on to the next segment); overrun (batch,) s: how far
    the phase clock ran past the segment's end (the chained segment starts that far in)."""

    to_settle: np.ndarray
    to_dwell: np.ndarray
    trigger: np.ndarray
    chain: np.ndarray
    overrun: np.ndarray


@kernel
def _transition_rows(phase: NDArray[np.int_], phase_time: NDArray[np.float64], index: NDArray[np.int_],
                     duration: NDArray[np.float64], end: NDArray[np.float64], target_yaw: NDArray[np.float64],
                     position: NDArray[np.float64], velocity: NDArray[np.float64], yaw: NDArray[np.float64],
                     n_views: int, through: bool, stop: NDArray[np.bool_], settle_position_m: float,
                     settle_speed_m_s: float, settle_yaw_rad: float, settle_timeout_s: float,
                     dwell_s: NDArray[np.float64],
                     ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_]]:
    """(to_settle, to_dwell, trigger, chain) (n,) bool of :func:`transitions`, row by row."""
    n = phase.size
    to_settle, to_dwell = np.zeros(n, np.bool_), np.zeros(n, np.bool_)
    trigger, chain = np.zeros(n, np.bool_), np.zeros(n, np.bool_)
    for row in range(n):
        arrived = phase[row] == TRANSIT and phase_time[row] >= duration[row]
        chain[row] = arrived and through and index[row] < n_views - 1 and not stop[index[row]]
        to_settle[row] = arrived and not chain[row]
        if phase[row] == SETTLE:
            yaw_err = wrapped(yaw[row] - target_yaw[row, index[row]])
            off = (position[row, 0] - end[row, 0]) ** 2 + (position[row, 1] - end[row, 1]) ** 2 \
                + (position[row, 2] - end[row, 2]) ** 2
            speed2 = velocity[row, 0] ** 2 + velocity[row, 1] ** 2 + velocity[row, 2] ** 2
            settled = off < settle_position_m ** 2 and speed2 < settle_speed_m_s ** 2 and abs(yaw_err) < settle_yaw_rad
            to_dwell[row] = settled or phase_time[row] >= settle_timeout_s
        # 1e-9: the dwell is a whole number of chunks, summed in floating point
        trigger[row] = phase[row] == DWELL and phase_time[row] >= dwell_s[index[row]] - 1e-9
    return to_settle, to_dwell, trigger, chain


def transitions(state: FlightState, position: np.ndarray, velocity: np.ndarray, yaw: np.ndarray,
                targets: FlightTargets, sec: SimSection, dwell_s: ArrayLike, through: bool) -> Transitions:
    """The vectorised state machine's moves this chunk, on the navigation's estimate: ``position``,
    ``velocity`` (batch, 3), ``yaw`` (batch,) rad; ``dwell_s``: the hover before each photo taken at rest, s
    (a number, or (n_views,) per view). In fly-through (``through``) the reference stops only at the last
    viewpoint and at the views of ``targets.stop``."""
    seg = state.segment
    stop = targets.stop if targets.stop is not None else np.zeros(targets.n_views, dtype=bool)
    dwell = contiguous(as_rows("dwell_s", dwell_s, (targets.n_views,)))     # the flight's own array: no copy
    moves = _transition_rows(state.phase, state.phase_time, state.index, seg.duration, seg.end, targets.yaw,
                             position, velocity, yaw, targets.n_views, bool(through), stop,
                             float(sec.settle_position_m), float(sec.settle_speed_m_s),
                             float(np.radians(sec.settle_yaw_deg)), float(sec.settle_timeout_s), dwell)
    return Transitions(*moves, state.phase_time - seg.duration)


@kernel
def _passing_rows(phase: NDArray[np.int_], photo: NDArray[np.int_], index: NDArray[np.int_],
                  position: NDArray[np.float64], body: NDArray[np.float64], trigger_normal: NDArray[np.float64],
                  arriving: NDArray[np.float64], stop: NDArray[np.bool_], reach_m: float,
                  ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:
    """(hit, skipped (n,) bool, past (n,) m, the plane's normal (n, 3)) of :func:`passing_views`, row by row."""
    n, n_views = phase.size, body.shape[1]
    hit, skipped, past, normal = np.zeros(n, np.bool_), np.zeros(n, np.bool_), np.zeros(n), np.empty((n, 3))
    for row in range(n):
        view = min(photo[row], n_views - 1)
        candidate = (phase[row] < DONE and photo[row] >= 1 and photo[row] < n_views and photo[row] <= index[row]
                     and not stop[view])
        along = 0.0
        for d in range(3):
            rel = position[row, d] - body[row, view, d]
            normal[row, d] = trigger_normal[row, view, d]
            past[row] += rel * normal[row, d]
            along += rel * arriving[row, view, d]
        hit[row] = candidate and past[row] >= 0.0 and along >= -reach_m
        skipped[row] = candidate and not hit[row] and index[row] >= photo[row] + 2
    return hit, skipped, past, normal


def passing_views(state: FlightState, position: np.ndarray, targets: FlightTargets, reach_m: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Fly-through trigger: (rows (m,) int, distance past the view's plane (m,) m, the plane's unit normal
    (m, 3), skipped rows (k,) int).

    A flight's next view (1 .. last, the reference at or past it) is passed when its estimated ``position``
    (batch, 3) crosses the view's plane: through the view's target, normal to the bisector of the arriving and
    the leaving leg (the mitre of the corner: a vehicle rounding the corner crosses it; at the last view, or a
    U-turn, normal to the arriving leg), and is at most ``reach_m`` short of the view along the arriving leg
    (on a hairpin the mitre plane runs almost along the leg: without this a vehicle off the track would be
    "past" it long before the view). A view whose plane the vehicle has not crossed by the time the
    reference is two views further on is skipped: a missed trigger, the photo is not taken. A view of
    ``targets.stop`` is not shot passing: the flight stops there and shoots after the dwell."""
    if targets.trigger_normal is None or targets.arriving is None or targets.stop is None:
        raise ValueError("fly-through targets without their trigger planes (FlightTargets.flown_through)")
    hit, skipped, past, normal = _passing_rows(state.phase, state.photo, state.index, position, targets.body,
                                               targets.trigger_normal, targets.arriving, targets.stop,
                                               float(reach_m))
    hits = np.flatnonzero(hit)
    return hits, past[hits], normal[hits], np.flatnonzero(skipped)


def take_photos(state: FlightState, targets: FlightTargets, rows: np.ndarray, shot: Shot | None) -> None:
    """Flights ``rows`` (m,) int take their next photo (``state.photo``), the :class:`Shot` of m rows (None
    when there are none)."""
    if not rows.size:
        return
    if shot is None:
        raise ValueError(f"no shot for the photos of {rows.size} flights")
    view = state.photo[rows]
    state.captures.record(rows, view, shot, targets)
    state.view_sortie[rows, view] = state.sortie[rows]
    state.sortie_views[rows] += 1
    state.flight_time[rows] = shot.time
    state.photo[rows] = view + 1


def advance(state: FlightState, targets: FlightTargets, rows: np.ndarray, profile: Profile) -> None:
    """Flights ``rows`` (m,) int are DONE after the last viewpoint, or start the segment to the next one."""
    if not rows.size:
        return
    last = state.index[rows] == targets.n_views - 1
    state.phase[rows[last]] = DONE
    nxt = rows[~last]
    if not nxt.size:
        return
    k1 = state.index[nxt] + 1
    speeds = {}
    if profile.through:
        if targets.vertex_speed is None or targets.leg_speed is None:
            raise ValueError("fly-through targets without their speeds (FlightTargets.flown_through)")
        speeds = dict(v0=targets.vertex_speed[nxt, k1 - 1], v1=targets.vertex_speed[nxt, k1],
                      v_max=targets.leg_speed[nxt, k1 - 1])
    elif targets.leg_cruise is not None:
        speeds = dict(v_max=targets.leg_cruise[k1 - 1])
    state.segment.assign(nxt, plan_segments(state.segment.end[nxt], targets.body[nxt, k1],
                                            targets.yaw[nxt, k1 - 1], targets.yaw[nxt, k1], profile, **speeds))
    state.index[nxt] = k1
    state.phase[nxt] = TRANSIT


def apply_transitions(state: FlightState, moves: Transitions) -> None:
    """Move the flights to SETTLE / DWELL and restart the phase clock of every flight that moved (the
    triggered and chained ones included: :func:`advance` set their new phase)."""
    state.phase = np.where(moves.to_settle, SETTLE, state.phase)
    state.phase = np.where(moves.to_dwell, DWELL, state.phase)
    restart = np.where(moves.chain, np.maximum(moves.overrun, 0.0), 0.0)
    state.phase_time = np.where(moves.trigger | moves.to_settle | moves.to_dwell | moves.chain, restart,
                                state.phase_time)


def tick(state: FlightState, ref: Reference, dt_s: float) -> None:
    """Advance the phase clock by the chunk ``dt_s``, except where the leash holds the reference."""
    state.phase_time = state.phase_time + np.where(ref.held, 0.0, dt_s)


# -- control ----------------------------------------------------------------------------------------------
class Setpoint(NamedTuple):
    """The position loop's input for the padded batch: position, velocity, acceleration (padded, 3);
    yaw (padded,) rad; integrate (padded,) bool, where the position-error integral may grow."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    yaw: np.ndarray
    integrate: np.ndarray


def setpoints(ref: Reference, phase: np.ndarray, filler_position: np.ndarray, yaw_error: np.ndarray,
              through: bool = False) -> Setpoint:
    """The flights' reference followed by the fillers' (hover at ``filler_position`` (padded - batch, 3) m,
    heading 0). In stop mode the integral grows only while the reference is at rest (conditional integration,
    README.md); in fly-through (``through``) the reference never rests, and the integral is what holds the
    track against a steady wind (without it the drag leaves F / (m k_p): 3 / 13 / 29 cm at 4 / 8 / 12 m/s of
    relative air), so it grows all the time (within its clamp).
    ``yaw_error`` (batch,) rad: the navigation's heading error; the attitude loop turns the airframe to where
    its estimated heading is the reference's, i.e. the true heading is the reference minus the error."""
    integrate = np.ones(len(phase), dtype=bool) if through else phase != TRANSIT
    yaw = ref.yaw - yaw_error
    n = len(filler_position)
    if not n:     # the usual case, a batch filling its models: no copies
        return Setpoint(ref.position, ref.velocity, ref.acceleration, yaw, integrate)
    zeros = np.zeros((n, 3))
    return Setpoint(np.concatenate([ref.position, filler_position]), np.concatenate([ref.velocity, zeros]),
                    np.concatenate([ref.acceleration, zeros]), np.concatenate([yaw, np.zeros(n)]),
                    np.concatenate([integrate, np.ones(n, dtype=bool)]))


def control(controller: PositionController, position: np.ndarray, velocity: np.ndarray, rot: np.ndarray,
            setpoint: Setpoint, dt_s: float, params: QuadrotorParams) -> tuple[np.ndarray, np.ndarray]:
    """Position loop for the padded batch: (motor thrusts (padded, 4) N, attitude target quaternions
    (padded, 4) (w, x, y, z)) from the vehicles' ``position``, ``velocity`` (padded, 3) and ``rot``
    (padded, 3, 3). The thrust is shared equally by the motors; the attitude loop runs inside MuJoCo."""
    sp = setpoint
    thrust, quat = controller(position, velocity, rot[:, :, 2], sp.position, sp.velocity, sp.acceleration,
                              sp.yaw, dt_s, sp.integrate)
    motors = np.repeat(np.minimum(thrust / 4.0, params.max_thrust_per_motor_n)[:, None], 4, axis=1)
    return motors, quat


def parked_pose(position: np.ndarray, park: np.ndarray) -> np.ndarray:
    """Free-joint poses (n, 7) that hold failed flights still: where they are (their ``park`` (n, 7) pose
    where the position is not finite), at least 1 m above the sea, level at the park orientation."""
    qpos = park.copy()
    qpos[:, :3] = np.where(np.isfinite(position), position, park[:, :3])
    qpos[:, 2] = np.maximum(qpos[:, 2], 1.0)
    return qpos
