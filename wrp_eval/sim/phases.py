"""The flight loop's phase functions, once per chunk, for a whole batch of flights at once.

In loop order: :func:`reference` (where each flight's setpoint is, with the leash), :func:`check_failures`
/ :func:`apply_failures`, :func:`transitions` (TRANSIT -> SETTLE -> DWELL -> trigger) /
:func:`take_photos` / :func:`apply_transitions`, :func:`setpoints` + :func:`control` (position loop ->
motor thrusts and attitude targets), :func:`tick` (the phase clock). Shapes: ``batch`` flights; the
control functions work on the ``padded`` batch of the MuJoCo models (the flights plus parked fillers).
The pure functions return new arrays; the ``apply_*`` functions, :func:`take_photos` and :func:`tick`
update the :class:`FlightState` in place.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from wrp_eval.sim.config import SimSection
from wrp_eval.sim.controller import PositionController, wrap_angle
from wrp_eval.sim.flight_state import (
    DITCHED,
    DONE,
    DWELL,
    FAILED,
    LOST,
    NO_FAILURE,
    NON_FINITE,
    SETTLE,
    STALLED,
    TIMED_OUT,
    TRANSIT,
    FlightState,
    FlightTargets,
    Segment,
)
from wrp_eval.sim.vehicle import QuadrotorParams

YAW_RATE_REF_RAD_S = np.radians(60.0)  # reference yaw rate when a segment is mostly a rotation


# -- reference speed profile -----------------------------------------------------------------------------
def _trapezoid(length, tau, v_max, a_max):
    """Rest-to-rest trapezoidal speed profile: distance s, speed v, acceleration a and the running integral
    of s, S = int s dt (each (n,)) at time tau (n,) s, plus the duration (n,). Before 0: at rest at 0;
    after: at rest at ``length``."""
    tri = length < v_max ** 2 / a_max
    v_peak = np.where(tri, np.sqrt(np.maximum(length, 0.0) * a_max), v_max)
    t_acc = v_peak / a_max
    t_cruise = np.where(tri, 0.0, length / v_max - t_acc)
    duration = 2.0 * t_acc + t_cruise
    s_acc = 0.5 * a_max * t_acc ** 2
    big_s_acc = a_max * t_acc ** 3 / 6.0
    big_s_end = big_s_acc + s_acc * t_cruise + 0.5 * v_peak * t_cruise ** 2 + (length * t_acc - big_s_acc)
    after = np.maximum(tau - duration, 0.0)
    moving = (tau >= 0.0) & (tau < duration)
    tau = np.clip(tau, 0.0, duration)
    t_c = tau - t_acc
    t_dec = duration - tau
    in_acc, in_dec = tau < t_acc, t_dec < t_acc
    s = np.where(in_acc, 0.5 * a_max * tau ** 2,
                 np.where(in_dec, length - 0.5 * a_max * t_dec ** 2, s_acc + v_peak * t_c))
    v = np.where(in_acc, a_max * tau, np.where(in_dec, a_max * t_dec, v_peak))
    a = np.where(moving, np.where(in_acc, a_max, np.where(in_dec, -a_max, 0.0)), 0.0)
    big_s = np.where(in_acc, a_max * tau ** 3 / 6.0,
                     np.where(in_dec, big_s_end - (length * t_dec - a_max * t_dec ** 3 / 6.0),
                              big_s_acc + s_acc * t_c + 0.5 * v_peak * t_c ** 2))
    return s, v, a, big_s + length * after, duration


def reference_profile(length, tau, v_max, a_max, t_jerk):
    """Jerk-limited rest-to-rest profile: distance, speed, acceleration (each (n,)) at time tau, and the
    duration (n,).

    The trapezoidal speed profile averaged over a moving window of ``t_jerk`` s: the acceleration then
    ramps over t_jerk instead of jumping, i.e. the jerk is limited to a_max / t_jerk, at most twice that
    on a segment too short to reach a_max (PX4 shapes its auto-mode setpoints with a jerk limit too,
    MPC_JERK_AUTO, default 4 m/s^3). A step in the
    acceleration demand is what the attitude loop cannot follow without lag: with the trapezoid alone the
    vehicle overshot each viewpoint by ~10 cm (README.md). Exact box averages from the closed forms:
    s_j = (S(t) - S(t-T)) / T, v_j = (s(t) - s(t-T)) / T, a_j = (v(t) - v(t-T)) / T.
    """
    s1, v1, a1, big1, duration = _trapezoid(length, tau, v_max, a_max)
    if t_jerk <= 0.0:
        return s1, v1, a1, duration
    s0, v0, _, big0, _ = _trapezoid(length, tau - t_jerk, v_max, a_max)
    return (big1 - big0) / t_jerk, (s1 - s0) / t_jerk, (v1 - v0) / t_jerk, duration + t_jerk


@dataclass(frozen=True)
class Profile:
    """Limits of the reference along a segment: cruise speed m/s, acceleration m/s^2, jerk window s (the
    averaging window a/j of :func:`reference_profile`; 0: plain trapezoid)."""

    cruise_m_s: float
    acceleration_m_s2: float
    jerk_window_s: float

    @classmethod
    def of(cls, cruise_m_s: float, sec: SimSection) -> Profile:
        a_max = sec.acceleration_m_s2
        return cls(cruise_m_s, a_max, a_max / sec.jerk_m_s3 if sec.jerk_m_s3 else 0.0)

    def at(self, length: np.ndarray, tau: np.ndarray):
        """(s m, v m/s, a m/s^2, duration s), each (n,), on segments of ``length`` (n,) m at ``tau`` (n,) s."""
        return reference_profile(length, tau, self.cruise_m_s, self.acceleration_m_s2, self.jerk_window_s)


def plan_segments(start: np.ndarray, end: np.ndarray, yaw0: np.ndarray, yaw1: np.ndarray,
                  profile: Profile) -> Segment:
    """Segments from ``start`` to ``end`` (n, 3) m turning from ``yaw0`` to ``yaw1`` (n,) rad. A segment
    lasts the speed profile's time, or longer where the turn needs it at YAW_RATE_REF_RAD_S."""
    delta = end - start
    length = np.linalg.norm(delta, axis=1)
    direction = delta / np.maximum(length, 1e-12)[:, None]
    dyaw = wrap_angle(yaw1 - yaw0)
    duration = profile.at(length, np.zeros_like(length))[3]
    return Segment(start, end, yaw0, dyaw, length, direction,
                   np.maximum(duration, np.abs(dyaw) / YAW_RATE_REF_RAD_S))


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


def reference(state: FlightState, position: np.ndarray, profile: Profile, leash_m: float) -> Reference:
    """Each flight's reference at its phase time: along the segment in TRANSIT, at the segment's end
    otherwise. ``position`` (batch, 3) m: the vehicles' centres of mass."""
    seg = state.segment
    s, v, a, _ = profile.at(seg.length, state.phase_time)
    transit = state.phase == TRANSIT
    ref_pos = np.where(transit[:, None], seg.start + seg.direction * s[:, None], seg.end)
    # Leash: a vehicle held back by a head wind is not "lost"; its reference waits for it (what a waypoint
    # autopilot does: it flies towards the next waypoint as fast as it can).
    err = position - ref_pos
    dist2 = np.einsum("ij,ij->i", err, err)
    held = transit & (dist2 > leash_m ** 2)
    moving = transit & ~held
    ref_vel = np.where(moving[:, None], seg.direction * v[:, None], 0.0)
    ref_acc = np.where(moving[:, None], seg.direction * a[:, None], 0.0)
    frac = np.where(transit, np.clip(state.phase_time / np.maximum(seg.duration, 1e-9), 0.0, 1.0), 1.0)
    return Reference(ref_pos, ref_vel, ref_acc, seg.yaw0 + seg.dyaw * frac, dist2, held)


# -- failures ---------------------------------------------------------------------------------------------
class Failures(NamedTuple):
    """lost_time, held_time (batch,) s: the timers after this chunk; cause (batch,) int: the cause code of
    flights failing now (NO_FAILURE elsewhere)."""

    lost_time: np.ndarray
    held_time: np.ndarray
    cause: np.ndarray


def check_failures(state: FlightState, position: np.ndarray, velocity: np.ndarray, ref: Reference,
                   dt_s: float, sec: SimSection, out_of_time: bool) -> Failures:
    """Flights failing now: lost (beyond ``fail_distance_m`` for longer than ``fail_time_s``), stalled
    (held by the leash for longer than ``stall_time_s``), ditched (below the sea surface), non-finite
    state, or still flying when ``out_of_time``. ``position``, ``velocity`` (batch, 3); ``dt_s`` the chunk."""
    active = state.flying
    lost_time = np.where(active & (ref.distance_sq > sec.fail_distance_m ** 2), state.lost_time + dt_s, 0.0)
    held_time = np.where(ref.held, state.held_time + dt_s, 0.0)
    bad = ~np.isfinite(position.sum(axis=1) + velocity.sum(axis=1))
    ditched = position[:, 2] < 0.0
    stalled = held_time > sec.stall_time_s
    lost = lost_time > sec.fail_time_s
    newly = active & (lost | stalled | ditched | bad)
    if out_of_time:
        newly |= active
    cause = np.full(len(newly), NO_FAILURE)
    if newly.any():     # rare: np.select alone would cost a fifth of this function every chunk
        first = np.select([bad, ditched, stalled, lost], [NON_FINITE, DITCHED, STALLED, LOST], TIMED_OUT)
        cause[newly] = first[newly]
    return Failures(lost_time, held_time, cause)


def apply_failures(state: FlightState, failures: Failures, t: float) -> None:
    """Take the timers, and mark the failing flights FAILED at ``t`` s with their cause."""
    state.lost_time, state.held_time = failures.lost_time, failures.held_time
    newly = failures.cause != NO_FAILURE
    if not newly.any():
        return
    state.failure = np.where(newly, failures.cause, state.failure)
    state.flight_time = np.where(newly, t, state.flight_time)
    state.phase = np.where(newly, FAILED, state.phase)


def failure_reason(cause: int, t: float, view: int, sec: SimSection) -> str:
    """The text of a failure of cause ``cause`` at ``t`` s before viewpoint ``view`` ("" for NO_FAILURE)."""
    if cause == NON_FINITE:
        return f"non-finite state at t={t:.2f}s"
    if cause == DITCHED:
        return f"ditched (below sea level) at t={t:.2f}s"
    if cause == STALLED:
        return (f"no headway: > {sec.leash_m:g} m behind the reference for "
                f"> {sec.stall_time_s:g} s at t={t:.2f}s (before view {view})")
    if cause == LOST:
        return (f"lost position: > {sec.fail_distance_m:g} m from the reference for "
                f"> {sec.fail_time_s:g} s at t={t:.2f}s (before view {view})")
    if cause == TIMED_OUT:
        return f"not finished within max_flight_time_s={sec.max_flight_time_s:g}"
    return ""


def failure_reasons(state: FlightState, sec: SimSection) -> tuple[str, ...]:
    """(batch,) texts of the flights' failures ("" for a completed flight)."""
    return tuple(failure_reason(c, t, v, sec) for c, t, v in
                 zip(state.failure.tolist(), state.flight_time.tolist(), state.index.tolist()))


# -- phase transitions and the photo trigger ---------------------------------------------------------------
class Transitions(NamedTuple):
    """(batch,) bool each: the segment's reference has arrived (TRANSIT -> SETTLE); within the tolerances
    or out of settle time (SETTLE -> DWELL); dwelt long enough (DWELL -> photo)."""

    to_settle: np.ndarray
    to_dwell: np.ndarray
    trigger: np.ndarray


def transitions(state: FlightState, position: np.ndarray, velocity: np.ndarray, yaw: np.ndarray,
                targets: FlightTargets, sec: SimSection, dwell_s: float) -> Transitions:
    """The vectorised state machine's moves this chunk; ``position``, ``velocity`` (batch, 3), ``yaw`` (batch,)
    rad of the vehicles."""
    phase, phase_time = state.phase, state.phase_time
    to_settle = (phase == TRANSIT) & (phase_time >= state.segment.duration)
    yaw_err = wrap_angle(yaw - targets.yaw[np.arange(len(phase)), state.index])
    settled = ((((position - state.segment.end) ** 2).sum(axis=1) < sec.settle_position_m ** 2)
               & ((velocity ** 2).sum(axis=1) < sec.settle_speed_m_s ** 2)
               & (np.abs(yaw_err) < np.radians(sec.settle_yaw_deg)))
    to_dwell = (phase == SETTLE) & (settled | (phase_time >= sec.settle_timeout_s))
    # 1e-9: the dwell is a whole number of chunks, summed in floating point
    trigger = (phase == DWELL) & (phase_time >= dwell_s - 1e-9)
    return Transitions(to_settle, to_dwell, trigger)


class CapturePose(NamedTuple):
    """Camera at a photo, (n, ...): position (n, 3) m, yaw (n,) rad (the airframe's), pitch (n,) rad the
    gimbal achieved, residual_roll (n,) rad beyond the gimbal's roll range, saturated (n,) bool."""

    position: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    residual_roll: np.ndarray
    saturated: np.ndarray


def capture_pose(position: np.ndarray, rot: np.ndarray, yaw: np.ndarray, wanted_pitch: np.ndarray,
                 params: QuadrotorParams) -> CapturePose:
    """Where the camera really is: body ``position`` (n, 3) m, attitude ``rot`` (n, 3, 3) world from body,
    heading ``yaw`` (n,) rad, planned gimbal pitch ``wanted_pitch`` (n,) rad."""
    lo_pitch, hi_pitch = params.gimbal_pitch_range_rad
    lo_roll, hi_roll = params.gimbal_roll_range_rad
    cam_pos = position + rot @ np.asarray(params.camera_offset_m)
    # gimbal: joint angle = wanted world pitch - elevation of the nose, within its range
    nose_elev = np.arcsin(np.clip(rot[:, 2, 0], -1, 1))
    pitch = np.clip(wanted_pitch - nose_elev, lo_pitch, hi_pitch) + nose_elev
    roll = np.arcsin(np.clip(rot[:, 2, 1], -1, 1))
    residual = roll - np.clip(roll, lo_roll, hi_roll)
    saturated = (np.abs(pitch - wanted_pitch) > 1e-9) | (residual != 0.0)
    return CapturePose(cam_pos, yaw, pitch, residual, saturated)


def take_photos(state: FlightState, targets: FlightTargets, rows: np.ndarray, position: np.ndarray,
                rot: np.ndarray, yaw: np.ndarray, t: float, profile: Profile, params: QuadrotorParams) -> None:
    """Flights ``rows`` (m,) int take their current view at ``t`` s from the true state (``position``
    (batch, 3) m, ``rot`` (>= batch, 3, 3), ``yaw`` (batch,) rad); then they are DONE after the last view,
    or start the segment to the next one."""
    if not rows.size:
        return
    view = state.index[rows]
    pose = capture_pose(position[rows], rot[rows], yaw[rows], targets.plan_pitch[view], params)
    state.captures.record(rows, view, pose, targets, t)
    state.flight_time[rows] = t
    last = view == targets.n_views - 1
    state.phase[rows[last]] = DONE
    nxt = rows[~last]
    if nxt.size:
        k1 = state.index[nxt] + 1
        state.segment.assign(nxt, plan_segments(state.segment.end[nxt], targets.body[nxt, k1],
                                                targets.yaw[nxt, k1 - 1], targets.yaw[nxt, k1], profile))
        state.index[nxt] = k1
        state.phase[nxt] = TRANSIT


def apply_transitions(state: FlightState, moves: Transitions) -> None:
    """Move the flights to SETTLE / DWELL and restart the phase clock of every flight that moved (the
    triggered ones included: :func:`take_photos` set their new phase)."""
    state.phase = np.where(moves.to_settle, SETTLE, state.phase)
    state.phase = np.where(moves.to_dwell, DWELL, state.phase)
    state.phase_time = np.where(moves.trigger | moves.to_settle | moves.to_dwell, 0.0, state.phase_time)


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


def setpoints(ref: Reference, phase: np.ndarray, filler_position: np.ndarray) -> Setpoint:
    """The flights' reference followed by the fillers' (hover at ``filler_position`` (padded - batch, 3) m,
    heading 0). The integral grows only while the reference is at rest (conditional integration, README.md)."""
    integrate = phase != TRANSIT
    n = len(filler_position)
    if not n:     # the usual case, a batch filling its models: no copies
        return Setpoint(ref.position, ref.velocity, ref.acceleration, ref.yaw, integrate)
    zeros = np.zeros((n, 3))
    return Setpoint(np.concatenate([ref.position, filler_position]), np.concatenate([ref.velocity, zeros]),
                    np.concatenate([ref.acceleration, zeros]), np.concatenate([ref.yaw, np.zeros(n)]),
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
