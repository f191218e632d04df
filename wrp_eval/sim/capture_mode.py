"""How the photos are taken: ``stop`` (fly to the viewpoint, settle, shoot) or ``fly-through`` (shoot when
the estimated position passes the viewpoint, without stopping), the shutter's latency and exposure.

Fly-through reference (batch-first): the reference runs through the viewpoints without stopping, at the
path's cruise speed, slowing for corners and heading changes. Per flight the speed at every viewpoint is
planned once (:func:`vertex_speeds`): at most the cruise speed; at a corner of turn angle theta at most
sqrt(a_lat r) on the arc of radius r = R / tan(theta/2) tangent to both legs at ``corner_radius_m`` R from
the viewpoint (centripetal acceleration v^2 / r = a_lat; R plays the part of PX4's waypoint acceptance
radius NAV_ACC_RAD, the distance at which a mission turns towards the next leg); slow enough on each leg
that the heading turns at the reference yaw rate; and reachable from its neighbours with the acceleration
limit (a forward and a backward pass, the usual velocity planning of a polyline). Between viewpoints the
speed is a trapezoid from v0 to v1 averaged over the jerk window T = a / j of the stop mode (PX4's
MPC_JERK_AUTO; :func:`through_profile`), so the acceleration ramps to 0 at every viewpoint; the first viewpoint
is left from rest (after its photo, taken hovering); the reference stops at the last, whose photo is taken when
the vehicle crosses its plane (often still slowing down) or, failing that, once it has settled there. The
reference's velocity still turns at each viewpoint in one step (a corner is a step in the velocity's
direction, not in the acceleration; the controller rounds it), so the corner speed is also kept to a velocity
step of :data:`CORNER_STEP_M_S`: a larger step tilts the airframe hard just as the shutter opens (blur, and a
heading swing no mission commands).

Trigger (:func:`wrp_eval.sim.phases.passing_views`): a view is shot when the estimated position crosses the
plane through the view's target normal to the bisector of the arriving and leaving legs (a vehicle rounding
the corner crosses it; what position-triggered survey cameras do); a view whose plane is not crossed before
the reference is two views further on is missed (not taken). The crossing is detected at the position-loop
rate; its time is interpolated within the chunk from the estimated speed along the plane's normal, and the
shutter opens ``trigger_latency_s`` later (:func:`shutter_offset`).

Per-view modes (:attr:`wrp_eval.planning.path.FlightPath.capture`, overriding ``mode``): a mission with any view
flown through is flown on the fly-through reference, which comes to rest at the views marked ``stop`` (speed 0 there,
:func:`vertex_speeds`), settles and hovers the dwell before the photo, as a stop-mode view; the views
marked ``fly-through`` are shot passing. What a DJI waypoint mission does per waypoint with its turn mode
(WPML ``waypointTurnMode``: ``toPointAndStopWithDiscontinuityCurvature`` stops,
``toPointAndPassWithContinuityCurvature`` passes; DJI WPML "common element" reference) and PX4 with a hold time
per waypoint (MAV_CMD_NAV_WAYPOINT param1). A path whose every view is marked ``stop`` is flown as the stop mission,
to the bit; in a mixed mission a stop view is approached on the fly-through reference (from its neighbour's
passing speed, the position integral growing in transit as in fly-through), so it is not the stop mission's
approach.
"""

from __future__ import annotations

from typing import Any, Final, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from wrp_eval.compiled import kernel
from wrp_eval.schema import StrictModel

STOP: Final = "stop"
FLY_THROUGH: Final = "fly-through"
SMOOTH_TRANSITION: Final = "smoothTransition"
# Largest step of the reference velocity at a fly-through corner (m/s): the position loop turns a velocity step
# dv into an acceleration demand kv dv (kv = 6 /s, the default gains, controller.py); 0.4 m/s keeps it near
# the reference's own acceleration limit (2.5 m/s^2 / 6 /s = 0.42 m/s). Without it the corners were taken at
# the arc speed sqrt(a R / tan(theta/2)) (2.2 m/s at 90 deg: a 3.2 m/s step, 35 deg of tilt at the shutter):
# calm-air fly-through photos of a 30 m standoff path had blur p95 27 px and heading rates at the shutter up to
# 43 deg/s on legs that command none (README.md, "Capture mode").
CORNER_STEP_M_S = 0.4


class CaptureSection(StrictModel):
    """The ``sim.capture`` section.

    mode: ``stop`` by default: fly to the view, settle, hover ``sim.dwell_s`` (or the path's dwell), shoot -
    what a waypoint inspection mission does: DJI executes waypoint actions once the aircraft "has reached a
    waypoint, has rotated to the new heading" (DJI Mobile SDK, DJIWaypointMissionExecuteState BeginAction),
    and DJI-based ground stations warn that in curved (pass-through) mode most waypoint actions are not
    executed (GoodStation manual, "Patrol (Custom Waypoint)", Turn Mode); close-range industrial inspection
    flies waypoint-by-waypoint (Gyrichidi et al. 2024, Drones 8(10) 549). ``fly-through`` shoots on the
    move, as survey apps do: the paper's tours (5 m/s, 170.8 s for 51 views, Table 1) are flown that way
    (experiments/paper/*.yaml set it). Every exported mission follows this mode (wrp_eval/export).
    heading_mode: how the heading goes from one view's to the next: ``smoothTransition`` (DJI WPML's name),
    interpolated linearly over the leg - the one the simulator flies (phases._reference_rows).
    trigger_latency_s: from the trigger decision to the shutter (assumed 50 ms: consumer camera trigger
    latencies are tens of milliseconds; no DJI figure is published).
    exposure_s: shutter time (1/500 s by default; the Phantom 4 Pro's mechanical shutter reaches 1/2000 s).
    corner_radius_m: where the fly-through reference starts turning before a corner (see the module).
    """

    mode: Literal["stop", "fly-through"] = STOP
    heading_mode: Literal["smoothTransition"] = SMOOTH_TRANSITION
    trigger_latency_s: float = Field(0.05, ge=0.0, le=2.0, description="trigger to shutter delay, s")
    exposure_s: float = Field(1.0 / 500.0, gt=0.0, le=1.0, description="shutter time, s")
    corner_radius_m: float = Field(2.0, gt=0.0, le=50.0, description="fly-through: corner turn starts this far "
                                                                     "from the viewpoint, m")


def vertex_speeds(body: np.ndarray, yaw: np.ndarray, cruise_m_s: ArrayLike, accel_m_s2: float,
                  yaw_rate_rad_s: float, corner_radius_m: float, corner_step_m_s: float = CORNER_STEP_M_S,
                  window_s: float = 0.0, stop: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(speed at each viewpoint (batch, n_views), cruise limit of each leg (batch, n_views - 1)) m/s for the
    fly-through reference through the body targets ``body`` (batch, n_views, 3) m with headings ``yaw``
    (batch, n_views) rad, each leg at most ``cruise_m_s`` (a number, or (n_views - 1,) per leg). The first and
    last viewpoints are at rest, and so are the viewpoints of ``stop`` (n_views,) bool (shot stop-and-shoot
    within a fly-through mission; None: none). At a corner of turn angle theta the
    reference's velocity turns in one step of 2 v sin(theta/2), at the viewpoint, where the photo is taken:
    v is kept to ``corner_step_m_s`` / (2 sin(theta/2)) (:data:`CORNER_STEP_M_S`). With the jerk window T =
    ``window_s`` (:func:`through_profile`) a leg of length L from v0 must leave room for it: the trapezoid over
    L - (v0 + v1) T / 2 reaches v1 when v1 <= sqrt((v0 - a T / 2)^2 + 2 a L) - a T / 2 (the usual
    sqrt(v0^2 + 2 a L) at T = 0), in the forward pass and, mirrored, in the backward pass."""
    delta = np.diff(body, axis=1)
    length = np.linalg.norm(delta, axis=2)
    dyaw = np.abs((np.diff(yaw, axis=1) + np.pi) % (2.0 * np.pi) - np.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        turn_cap = np.where(dyaw > 1e-9, length * yaw_rate_rad_s / dyaw, np.inf)
    leg_cap = np.where(length > 1e-6, np.minimum(cruise_m_s, turn_cap), 0.0)
    unit = delta / np.maximum(length, 1e-12)[..., None]
    cos_turn = np.clip((unit[:, :-1] * unit[:, 1:]).sum(axis=2), -1.0, 1.0)
    half_turn = 0.5 * np.arccos(cos_turn)
    with np.errstate(divide="ignore"):
        corner = np.sqrt(accel_m_s2 * corner_radius_m / np.tan(half_turn))
    with np.errstate(divide="ignore"):
        step = corner_step_m_s / (2.0 * np.sin(half_turn))
    speed: NDArray[np.float64] = np.zeros(body.shape[:2])
    speed[:, 1:-1] = np.minimum(np.minimum(np.nan_to_num(corner, nan=0.0, posinf=np.inf), step),
                                np.minimum(leg_cap[:, :-1], leg_cap[:, 1:]))
    if stop is not None:
        speed[:, np.asarray(stop, dtype=bool)] = 0.0
    half = 0.5 * accel_m_s2 * window_s
    for k in range(1, speed.shape[1]):             # over viewpoints (tens), every flight at once
        reach = np.sqrt((speed[:, k - 1] - half) ** 2 + 2.0 * accel_m_s2 * length[:, k - 1]) - half
        speed[:, k] = np.minimum(speed[:, k], reach)
    for k in range(speed.shape[1] - 2, -1, -1):
        reach = np.sqrt((speed[:, k + 1] - half) ** 2 + 2.0 * accel_m_s2 * length[:, k]) - half
        speed[:, k] = np.minimum(speed[:, k], reach)
    return speed, leg_cap


def trigger_planes(body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(arriving leg's unit direction, trigger plane's unit normal), each (batch, n_views, 3), of the viewpoints'
    body targets ``body`` (batch, n_views, 3): the normal bisects the arriving and the leaving leg (the corner's
    mitre); at the last view, a U-turn or a zero-length leg it is the arriving leg's direction (view 0: the
    leaving leg's; it is photographed hovering)."""
    legs = np.diff(body, axis=1)
    unit = legs / np.maximum(np.linalg.norm(legs, axis=2, keepdims=True), 1e-12)
    arriving = np.concatenate([unit[:, :1], unit], axis=1)
    leaving = np.concatenate([unit, np.zeros_like(unit[:, :1])], axis=1)
    mitre = arriving + leaving
    norm = np.linalg.norm(mitre, axis=2, keepdims=True)
    return arriving, np.where(norm > 1e-6, mitre / np.maximum(norm, 1e-12), arriving)


@kernel
def _through_shape(length: float, v0: float, v1: float, v_max: float,
                   accel: float) -> tuple[float, float, float, float]:
    """(peak speed m/s, acceleration, cruise and deceleration times s) of the trapezoid of :func:`through_profile`
    (no window) from v0 to v1 over ``length``; it lasts their sum."""
    v_peak = np.minimum(v_max, np.sqrt(np.maximum(accel * length + 0.5 * (v0 ** 2 + v1 ** 2), 0.0)))
    v_peak = np.maximum(v_peak, np.maximum(v0, v1))
    t_acc = (v_peak - v0) / accel
    t_dec = (v_peak - v1) / accel
    s_acc = 0.5 * (v_peak + v0) * t_acc
    s_dec = 0.5 * (v_peak + v1) * t_dec
    t_cruise = np.maximum(length - s_acc - s_dec, 0.0) / v_peak if v_peak > 1e-9 else 0.0
    return v_peak, t_acc, t_cruise, t_dec


@kernel
def _through_at(tau: float, v0: float, v1: float, accel: float, v_peak: float, t_acc: float, t_cruise: float,
                t_dec: float) -> tuple[float, float, float, float]:
    """(s, v, a, S = int_0^tau s dt) at time ``tau`` (any real) on the trapezoid of :func:`_through_shape`,
    extended at v0 before 0 and at v1 after its end."""
    duration = t_acc + t_cruise + t_dec
    s_acc = 0.5 * (v_peak + v0) * t_acc
    big_acc = 0.5 * v0 * t_acc ** 2 + accel * t_acc ** 3 / 6.0
    s_cruise_end = s_acc + v_peak * t_cruise
    big_cruise_end = big_acc + s_acc * t_cruise + 0.5 * v_peak * t_cruise ** 2
    if tau < 0.0:
        return v0 * tau, v0, 0.0, 0.5 * v0 * tau ** 2
    if tau < t_acc:
        return (v0 * tau + 0.5 * accel * tau ** 2, v0 + accel * tau, accel,
                0.5 * v0 * tau ** 2 + accel * tau ** 3 / 6.0)
    if tau < t_acc + t_cruise:
        t_c = tau - t_acc
        return s_acc + v_peak * t_c, v_peak, 0.0, big_acc + s_acc * t_c + 0.5 * v_peak * t_c ** 2
    if tau > duration:
        s_end = s_cruise_end + v_peak * t_dec - 0.5 * accel * t_dec ** 2
        big_end = big_cruise_end + s_cruise_end * t_dec + 0.5 * v_peak * t_dec ** 2 - accel * t_dec ** 3 / 6.0
        t_e = tau - duration
        return s_end + v1 * t_e, v1, 0.0, big_end + s_end * t_e + 0.5 * v1 * t_e ** 2
    t_d = tau - t_acc - t_cruise          # also at the end, and for a NaN time (s and v NaN)
    return (s_cruise_end + v_peak * t_d - 0.5 * accel * t_d ** 2, v_peak - accel * t_d, -accel if t_dec > 0.0 else 0.0,
            big_cruise_end + s_cruise_end * t_d + 0.5 * v_peak * t_d ** 2 - accel * t_d ** 3 / 6.0)


@kernel
def through_window(length: float, v0: float, v1: float, accel: float, window_s: float) -> float:
    """The jerk window (s) a fly-through segment can take: ``window_s``, or less where the leg is too short for
    it at its end speeds (the window adds (v0 + v1) T / 2 to the distance the trapezoid covers, and the
    trapezoid over what is left must still reach v1: 2 a (L - (v0 + v1) T / 2) >= |v1^2 - v0^2|)."""
    if window_s <= 0.0 or v0 + v1 <= 0.0:
        whole: float = np.maximum(window_s, 0.0)
        return whole
    room = np.maximum(2.0 * accel * length - np.abs(v1 ** 2 - v0 ** 2), 0.0) / (accel * (v0 + v1))
    window: float = np.minimum(window_s, room)
    return window


@kernel
def through_row(length: float, tau: float, v0: float, v1: float, v_max: float,
                accel: float, window_s: float = 0.0) -> tuple[float, float, float, float]:
    """(s, v, a, duration) of :func:`through_profile` for one segment at one time."""
    window = through_window(length, v0, v1, accel, window_s)
    if window <= 1e-9:
        v_peak, t_acc, t_cruise, t_dec = _through_shape(length, v0, v1, v_max, accel)
        duration = t_acc + t_cruise + t_dec
        s, v, a, _ = _through_at(np.minimum(np.maximum(tau, 0.0), duration), v0, v1, accel, v_peak, t_acc, t_cruise,
                                 t_dec)
        return np.minimum(s, length), v, a if tau < duration else 0.0, duration
    # the trapezoid over the length the window leaves, averaged over [tau - T, tau] (exact, from S = int s),
    # shifted by v0 T / 2 so that the segment starts at its viewpoint
    v_peak, t_acc, t_cruise, t_dec = _through_shape(length - 0.5 * (v0 + v1) * window, v0, v1, v_max, accel)
    duration = t_acc + t_cruise + t_dec + window
    if tau >= duration:
        return length, v1, 0.0, duration
    tau = np.maximum(tau, 0.0)
    s1, w1, _, big1 = _through_at(tau, v0, v1, accel, v_peak, t_acc, t_cruise, t_dec)
    s0, w0, _, big0 = _through_at(tau - window, v0, v1, accel, v_peak, t_acc, t_cruise, t_dec)
    s = (big1 - big0) / window + 0.5 * v0 * window
    return np.minimum(s, length), (s1 - s0) / window, (w1 - w0) / window, duration


@kernel
def _through_rows(length: NDArray[np.float64], tau: NDArray[np.float64], v0: NDArray[np.float64],
                  v1: NDArray[np.float64], v_max: NDArray[np.float64], accel: float,
                  window_s: float) -> NDArray[np.float64]:
    out = np.empty((4, length.size))
    for row in range(length.size):
        out[0, row], out[1, row], out[2, row], out[3, row] = through_row(length[row], tau[row], v0[row], v1[row],
                                                                         v_max[row], accel, window_s)
    return out


def through_profile(length: ArrayLike, tau: ArrayLike, v0: ArrayLike, v1: ArrayLike, v_max: ArrayLike,
                    accel: float, window_s: float = 0.0) -> tuple[Any, ...]:
    """Speed profile from v0 to v1 over ``length`` (each (n,)) with acceleration ``accel`` and cruise at most
    ``v_max``: (distance s, speed v, acceleration a, duration) (n,) at time ``tau`` (n,) s. The end speeds
    must be reachable (:func:`vertex_speeds` makes them so). After the duration: at the end, at speed v1.
    ``accel``: a number (m/s^2); the others broadcast.

    ``window_s`` T > 0 (the jerk window a / j of :class:`wrp_eval.sim.phases.Profile`): the trapezoid over
    L - (v0 + v1) T / 2, averaged over a moving window of T, so the acceleration ramps from 0 at the segment's
    start to 0 at its end (jerk at most a / T where the ramps and the cruise outlast T, 2 a / T otherwise;
    PX4 limits its auto-mode jerk, MPC_JERK_AUTO): a corner is then
    a step in the velocity's direction only, not also in the acceleration. The segment lasts T longer and
    still covers L from v0 to v1; where the leg is too short for T at its end speeds the window shrinks
    (:func:`through_window`). T = 0: the plain trapezoid, the acceleration stepping at the viewpoints."""
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (length, tau, v0, v1, v_max)))
    length, tau, v0, v1, v_max = (np.ascontiguousarray(x).reshape(-1) for x in arrays)
    s, v, a, duration = _through_rows(length, tau, v0, v1, v_max, float(accel), float(window_s))
    return tuple(x.reshape(arrays[0].shape)[()] for x in (s, v, a, duration))     # [()]: a number for numbers


def shutter_offset(past_m: np.ndarray, speed_along_m_s: np.ndarray, chunk_s: float, latency_s: float) -> np.ndarray:
    """(n,) s from now to the shutter of views whose plane was crossed ``past_m`` (n,) m ago at ``speed_along_m_s``
    (n,): the crossing time interpolated within the last chunk, plus the trigger latency."""
    since: NDArray[np.float64] = np.clip(past_m / np.maximum(speed_along_m_s, 1e-3), 0.0, chunk_s)
    return latency_s - since
