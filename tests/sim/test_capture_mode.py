"""Fly-through capture: the v0 -> v1 speed profile between viewpoints, the planned speed at each viewpoint and the
shutter time of a view whose plane was crossed within the last chunk."""

import numpy as np
import pytest
from pydantic import ValidationError

from wrp_eval.sim.capture_mode import (
    CORNER_STEP_M_S,
    CaptureSection,
    shutter_offset,
    through_profile,
    through_window,
    vertex_speeds,
)
from wrp_eval.sim.phases import YAW_RATE_REF_RAD_S, reference_profile

A = 2.5      # m/s^2, the default reference acceleration


# -- through_profile ---------------------------------------------------------------------------------------
T_JERK = A / 4.0    # s, the jerk window of the default sim section (a / MPC_JERK_AUTO)


@pytest.mark.parametrize("length,v0,v1,v_max", [
    (9.0, 0.0, 0.23, 5.0),       # from rest into a sharp corner
    (6.0, 0.23, 1.4, 5.0),       # corner to corner
    (30.0, 3.0, 3.0, 5.0),       # accelerate, cruise, decelerate
    (1.0, 2.0, 2.0, 5.0),        # short: the window shrinks
])
def test_the_windowed_profile_is_the_box_average_with_zero_acceleration_at_both_ends(length, v0, v1, v_max):
    dt = 1e-4
    tau = np.arange(0.0, 20.0, dt)
    window = through_window(length, v0, v1, A, T_JERK)
    s, v, a, duration = through_profile(length, tau, v0, v1, v_max, A, T_JERK)
    end = float(duration[0])
    inside = tau <= end
    # from the viewpoint at v0 with no acceleration to the next at v1 with none, covering the leg exactly
    assert (s[0], v[0], a[0]) == pytest.approx((0.0, v0, 0.0), abs=1e-9)
    last = through_profile(length, np.nextafter(end, 0.0), v0, v1, v_max, A, T_JERK)   # the profile's own end
    assert last[:3] == pytest.approx((length, v1, 0.0), abs=1e-9)
    assert np.all(np.diff(s[inside]) >= -1e-12) and v[inside].max() <= v_max + 1e-9
    # one trajectory: s' = v, v' = a; the acceleration within +-a, the jerk within 2 a / T
    np.testing.assert_allclose(np.gradient(s[inside], dt)[1:-1], v[inside][1:-1], atol=1e-6)
    np.testing.assert_allclose(np.gradient(v[inside], dt)[1:-1], a[inside][1:-1], atol=2e-3)
    assert np.abs(a).max() <= A + 1e-9
    assert np.abs(np.diff(a[inside])).max() / dt <= 2.0 * A / window * (1.0 + 1e-3)
    # the speed is the plain trapezoid over the leg less (v0 + v1) T / 2, averaged over the last T
    inner = length - 0.5 * (v0 + v1) * window
    grid = np.arange(-window, end, dt)
    raw_v = through_profile(inner, np.maximum(grid, 0.0), v0, v1, v_max, A)[1]
    raw_v = np.where(grid < 0.0, v0, raw_v)
    k = int(round(window / dt))
    box = np.convolve(raw_v, np.ones(k) / k, mode="valid")[1:]         # box[j]: the mean over [tau_j - T, tau_j]
    n = min(len(box), int(inside.sum())) - 2
    np.testing.assert_allclose(v[:n], box[:n], atol=2e-3)


def test_the_window_shrinks_on_a_leg_too_short_for_it():
    assert through_window(30.0, 3.0, 3.0, A, T_JERK) == T_JERK
    assert 0.0 < through_window(1.5, 3.0, 3.0, A, T_JERK) < T_JERK
    assert through_window(1.5, 3.0, 3.0, A, 0.0) == 0.0
    # end speeds that only just fit the leg leave no room for a window
    assert through_window(3.0, 0.0, np.sqrt(2 * A * 3.0), A, T_JERK) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("length,v0,v1,v_max", [
    (10.0, 2.0, 1.0, 5.0),       # accelerate, cruise, decelerate
    (2.0, 1.0, 1.5, 5.0),        # too short for the cruise speed: a triangle
    (20.0, 5.0, 5.0, 5.0),       # cruise all along
    (3.0, 0.0, np.sqrt(2 * A * 3.0), 8.0),  # the end speed is just reachable: accelerate all along
    (30.0, 0.0, 0.0, 5.0),       # rest to rest
])
def test_through_profile_is_one_consistent_trajectory(length, v0, v1, v_max):
    dt = 1e-4
    n = 200_000
    tau = np.arange(n) * dt
    s, v, a, duration = through_profile(np.full(n, length), tau, np.full(n, v0), np.full(n, v1), np.full(n, v_max), A)
    end = duration[0]
    assert end < tau[-1]
    inside = tau < end
    interior = (tau > dt) & (tau < end - dt)
    # s' = v, v' = a (central differences, away from the ends and the acceleration's jumps)
    assert np.abs(np.gradient(s, dt) - v)[interior].max() < 1e-3
    smooth = np.abs(np.gradient(a, dt)) < 1.0
    assert np.abs(np.gradient(v, dt) - a)[interior & smooth].max() < 1e-6
    # the end conditions and the limits
    assert s[0] == 0.0 and v[0] == pytest.approx(v0)
    assert s[~inside][0] == pytest.approx(length) and v[~inside] == pytest.approx(np.full((~inside).sum(), v1))
    assert v.max() <= max(v_max, v0, v1) + 1e-9 and np.abs(a).max() <= A + 1e-9
    assert np.all(np.diff(s) >= -1e-12)                     # never backwards
    # the integral of the speed is the length: duration = length / mean speed
    assert np.trapezoid(v[inside], tau[inside]) == pytest.approx(length, rel=1e-3)


def test_rest_to_rest_through_profile_is_the_stop_modes_trapezoid():
    tau = np.linspace(0.0, 12.0, 2001)
    length = np.full_like(tau, 17.0)
    zero = np.zeros_like(tau)
    s, v, a, duration = through_profile(length, tau, zero, zero, np.full_like(tau, 5.0), A)
    s_ref, v_ref, a_ref, d_ref = reference_profile(length, tau, 5.0, A, 0.0)
    assert duration == pytest.approx(d_ref) and s == pytest.approx(s_ref) and v == pytest.approx(v_ref)
    moving = tau < duration
    assert a[moving] == pytest.approx(a_ref[moving])


def test_after_its_end_the_through_profile_holds_v1_without_acceleration():
    # the flight loop asks for the reference at phase_time >= duration for one chunk before it chains to the
    # next segment (or settles at the last view): the feed-forward must then be v1 and no acceleration
    n = 3
    args = np.full(n, 10.0), np.zeros(n), np.full(n, 2.0), np.full(n, 1.0), np.full(n, 5.0), A
    tau = through_profile(*args)[3] + [0.05, 1.0, 40.0]      # one chunk, 1 s and 40 s after the end
    s, v, a, _ = through_profile(args[0], tau, *args[2:])
    assert s == pytest.approx(np.full(n, 10.0)) and v == pytest.approx(np.full(n, 1.0))
    assert a == pytest.approx(np.zeros(n))


def test_through_profile_at_cruise_takes_length_over_speed():
    _, _, _, duration = through_profile(np.array([12.0]), np.zeros(1), np.array([4.0]), np.array([4.0]),
                                        np.array([4.0]), A)
    assert duration[0] == pytest.approx(3.0)


# -- vertex_speeds ------------------------------------------------------------------------------------------
def test_a_straight_line_is_flown_at_cruise_through_its_interior_views():
    body = np.stack([np.linspace(0.0, 200.0, 5), np.zeros(5), np.full(5, 20.0)], axis=1)[None]
    speed, leg = vertex_speeds(body, np.zeros((1, 5)), 5.0, A, YAW_RATE_REF_RAD_S, 2.0)
    assert speed.tolist() == [[0.0, 5.0, 5.0, 5.0, 0.0]]
    assert leg.tolist() == [[5.0] * 4]


def test_a_right_angle_corner_is_taken_at_the_arc_speed():
    # the arc tangent to both legs R from the corner has radius r = R / tan(theta / 2) (tangent length of a
    # circular curve, T = r tan(theta / 2)); the speed with centripetal acceleration a is sqrt(a r)
    radius = 2.0
    body = np.array([[[0.0, 0.0, 20.0], [100.0, 0.0, 20.0], [100.0, 100.0, 20.0]]])
    # (the velocity-step cap lifted: this test is about the arc alone)
    speed, _ = vertex_speeds(body, np.zeros((1, 3)), 20.0, A, YAW_RATE_REF_RAD_S, radius, np.inf)
    assert speed[0, 1] == pytest.approx(np.sqrt(A * radius / np.tan(np.radians(45.0))))
    # a sharper turn (120 deg) is slower, a gentler one (30 deg) faster
    turns = np.radians([120.0, 30.0])
    third = 100.0 * np.stack([1.0 + np.cos(turns), np.sin(turns), np.zeros(2)], axis=1) + [0.0, 0.0, 20.0]
    bodies = np.stack([np.tile(body[0, :2], (2, 1, 1))[i].tolist() + [third[i].tolist()] for i in range(2)])
    speed2, _ = vertex_speeds(bodies, np.zeros((2, 3)), 20.0, A, YAW_RATE_REF_RAD_S, radius, np.inf)
    assert speed2[:, 1] == pytest.approx(np.sqrt(A * radius / np.tan(turns / 2.0)))
    assert speed2[0, 1] < speed[0, 1] < speed2[1, 1]


def test_a_corner_is_taken_no_faster_than_its_velocity_step_allows():
    # the reference's velocity turns by theta in one step of 2 v sin(theta / 2) at the viewpoint: at most
    # CORNER_STEP_M_S, below the arc speed at every turn but the gentlest
    turns = np.radians([90.0, 30.0, 4.0, 0.0])
    body = np.stack([np.tile([[0.0, 0.0, 20.0], [100.0, 0.0, 20.0]], (4, 1, 1))[i].tolist()
                     + [[100.0 + 100.0 * np.cos(t), 100.0 * np.sin(t), 20.0]] for i, t in enumerate(turns)])
    speed, _ = vertex_speeds(body, np.zeros((4, 3)), 5.0, A, YAW_RATE_REF_RAD_S, 2.0)
    step = 2.0 * speed[:, 1] * np.sin(turns / 2.0)
    assert step[:2] == pytest.approx([CORNER_STEP_M_S] * 2)
    assert speed[2:, 1] == pytest.approx([5.0, 5.0])        # a 4 deg kink: a 0.35 m/s step at 5 m/s; straight: cruise
    assert step[2] < CORNER_STEP_M_S


def test_a_heading_change_caps_the_legs_speed_at_the_reference_yaw_rate():
    body = np.array([[[0.0, 0.0, 20.0], [10.0, 0.0, 20.0], [14.0, 0.0, 20.0], [24.0, 0.0, 20.0]]])
    yaw = np.array([[0.0, 0.0, np.pi / 2, np.pi / 2]])        # turn 90 deg on the 4 m middle leg
    speed, leg = vertex_speeds(body, yaw, 5.0, A, YAW_RATE_REF_RAD_S, 2.0)
    cap = 4.0 * YAW_RATE_REF_RAD_S / (np.pi / 2)              # the leg lasts the turn at 60 deg/s: 1.5 s
    assert cap < 5.0 and leg[0] == pytest.approx([5.0, cap, 5.0])
    assert speed[0] == pytest.approx([0.0, cap, cap, 0.0])
    # flown at its cap the middle leg lasts at least the turn's time
    duration = through_profile(np.array([4.0]), np.zeros(1), speed[:, 1], speed[:, 2], leg[:, 1], A)[3]
    assert duration[0] >= (np.pi / 2) / YAW_RATE_REF_RAD_S - 1e-9


def test_vertex_speeds_are_reachable_with_the_acceleration_limit():
    rng = np.random.default_rng(8)
    batch, n = 6, 12
    body = np.cumsum(rng.normal(0.0, 6.0, (batch, n, 3)), axis=1)
    body[:, 3] = body[:, 2]                                   # a zero-length leg: stop there
    yaw = rng.uniform(-np.pi, np.pi, (batch, n))
    speed, leg = vertex_speeds(body, yaw, 5.0, A, YAW_RATE_REF_RAD_S, 2.0)
    length = np.linalg.norm(np.diff(body, axis=1), axis=2)
    assert np.all(speed[:, [0, -1]] == 0.0) and np.all(speed[:, 2:4] == 0.0)
    assert np.all(speed[:, 1:] ** 2 <= speed[:, :-1] ** 2 + 2 * A * length + 1e-9)     # forward
    assert np.all(speed[:, :-1] ** 2 <= speed[:, 1:] ** 2 + 2 * A * length + 1e-9)     # backward
    assert np.all(speed[:, 1:-1] <= np.minimum(leg[:, :-1], leg[:, 1:]) + 1e-12) and np.all(leg <= 5.0)
    # every leg then takes at least its heading change's time at the reference yaw rate
    dyaw = np.abs((np.diff(yaw, axis=1) + np.pi) % (2 * np.pi) - np.pi)
    duration = through_profile(length.ravel(), np.zeros(length.size), speed[:, :-1].ravel(), speed[:, 1:].ravel(),
                               leg.ravel(), A)[3].reshape(length.shape)
    moving = length > 1e-6
    assert np.all(duration[moving] >= dyaw[moving] / YAW_RATE_REF_RAD_S - 1e-9)
    # flights are planned independently: row 2 alone is row 2 of the batch
    alone, _ = vertex_speeds(body[2:3], yaw[2:3], 5.0, A, YAW_RATE_REF_RAD_S, 2.0)
    assert np.array_equal(alone[0], speed[2])
    # with the jerk window every leg keeps room for the whole window (it does not have to shrink)
    windowed, leg = vertex_speeds(body, yaw, 5.0, A, YAW_RATE_REF_RAD_S, 2.0, window_s=T_JERK)
    assert np.all(windowed <= speed + 1e-12)
    room = np.array([through_window(length[i, k], windowed[i, k], windowed[i, k + 1], A, T_JERK)
                     for i in range(batch) for k in range(n - 1) if moving[i, k]])
    assert np.all(room >= T_JERK - 1e-9)


# -- trigger and shutter ------------------------------------------------------------------------------------
def test_the_shutter_opens_the_latency_after_the_interpolated_crossing():
    chunk, latency = 0.05, 0.05
    speed = np.array([5.0, 2.0, 5.0, 0.0])
    past = np.array([0.1, 0.0, 1.0, 0.3])
    offset = shutter_offset(past, speed, chunk, latency)
    # crossed 0.02 s ago; just now; longer ago than a chunk (clipped to it); not moving along (a whole chunk)
    assert offset == pytest.approx([0.03, 0.05, 0.0, 0.0])
    # at constant speed the shutter is latency x speed past the plane, wherever the chunk boundary fell
    x_now = np.array([0.0, 0.04, 0.11, 0.2499])
    at_shutter = x_now + 5.0 * shutter_offset(x_now, np.full(4, 5.0), chunk, latency)
    assert at_shutter == pytest.approx(np.full(4, 5.0 * latency))


def test_the_capture_section_rejects_bad_values():
    assert CaptureSection().mode == "stop" and CaptureSection().heading_mode == "smoothTransition"
    with pytest.raises(ValidationError, match="exposure_s"):
        CaptureSection(exposure_s=0.0)
    with pytest.raises(ValidationError, match="mode"):
        CaptureSection(mode="hover")
    with pytest.raises(ValidationError, match="trigger_latency_s"):
        CaptureSection(trigger_latency_s=-0.01)


# -- in flight: no photo during a heading change faster than the mission commands ------------------------------
# The tolerance (deg/s) on the camera's heading rate at the shutter over the faster of the two legs' commanded
# rates (dyaw / leg time) around the view: the reference still turns its velocity in one step at a corner
# (capped at CORNER_STEP_M_S; the acceleration is jerk-limited to 0 there), a tilt of 10-20 deg that swings the
# airframe's heading by 1-3 deg; measured up to 6.7 deg/s on this path. Before the jerk window the acceleration
# stepped too (from braking to accelerating: 33 deg of tilt at a 125 deg corner, 12.8 deg/s); before the corner
# velocity-step cap, corners taken at the arc speed swung it by up to 43 deg/s where the mission commands none.
RATE_TOLERANCE_DEG_S = 12.0


def test_no_fly_through_photo_turns_faster_than_the_mission_commands():
    from pathlib import Path

    from wrp_eval.config import ExperimentConfig
    from wrp_eval.experiment import ExperimentContext
    from wrp_eval.sim.config import SimSection
    from wrp_eval.sim.flight import FlightSimulator
    from wrp_eval.sim.flight_state import FlightTargets
    from wrp_eval.sim.onboard import ShipInScene
    from wrp_eval.sim.simple_wind import ConstantWind
    from wrp_eval.sim.vehicle import PHANTOM4

    # the planner's close-range path (30 m from the paper's ship, 145 views) flown once in calm air with a perfect
    # navigation (the heading noise of a real one, ~10 deg/s even hovering, is not what this checks)
    ctx = ExperimentContext(ExperimentConfig.model_validate({"planning": {"distance_m": 30.0}}), Path("."), "test")
    path = ctx.planned.path
    sec = SimSection(drones_per_model=1, threads=1, capture={"mode": "fly-through"}, navigation={"preset": "ideal"},
                     record_interval_s=SimSection().timestep_s * SimSection().chunk_steps)
    box = ctx.flight_proxy.bounds
    with FlightSimulator(sec) as sim:
        res = sim.fly(path, ConstantWind([0.0, 0.0, 0.0]), 1, ship=ShipInScene(box, wind_speed_10m_m_s=0.0))
    assert res.taken.all()
    # the heading rate each leg commands: its heading change over its duration (phases.plan_segments)
    targets = FlightTargets.from_path(path, 1, None, PHANTOM4.camera_offset_m, np.full(len(path.yaw), np.nan))
    window = sec.acceleration_m_s2 / sec.jerk_m_s3
    speed, leg = vertex_speeds(targets.body, targets.yaw, path.speed_m_s, sec.acceleration_m_s2, YAW_RATE_REF_RAD_S,
                               sec.capture.corner_radius_m, window_s=window)
    length = np.linalg.norm(np.diff(targets.body[0], axis=0), axis=1)
    dyaw = np.abs((np.diff(targets.yaw[0]) + np.pi) % (2.0 * np.pi) - np.pi)
    duration = np.maximum(through_profile(length, np.zeros_like(length), speed[0, :-1], speed[0, 1:], leg[0],
                                          sec.acceleration_m_s2, window)[3], dyaw / YAW_RATE_REF_RAD_S)
    commanded = dyaw / duration
    allowed = np.degrees(np.maximum(np.r_[0.0, commanded], np.r_[commanded, 0.0]))
    # the airframe's heading rate (the gimbal's yaw follows it) at each shutter, from the per-chunk record
    trajectory = res.trajectory
    rate = np.gradient(np.unwrap(trajectory.yaw[0]), trajectory.time)
    at_shutter = np.degrees(np.abs(np.interp(res.capture_time_s[0], trajectory.time, rate)))
    # nadir views (pitch -90 deg): their heading is a free choice of the planner, not measured here
    measured = np.degrees(path.pitch) > -85.0
    excess = (at_shutter - allowed)[measured]
    assert measured.sum() > 100
    assert excess.max() <= RATE_TOLERANCE_DEG_S, (np.flatnonzero(measured)[excess.argmax()], excess.max())


# -- per-view capture modes: a fly-through mission that stops where the path says -------------------------------
def test_a_fly_through_mission_stops_and_dwells_only_at_the_views_its_path_marks_stop():
    from tests.sim.conftest import make_path
    from wrp_eval.sim.config import SimSection
    from wrp_eval.sim.flight import FlightSimulator
    from wrp_eval.sim.simple_wind import ConstantWind

    path = make_path(n=6, spacing_m=10.0, dwell_s=1.5)
    dt = SimSection().timestep_s * SimSection().chunk_steps
    through_sec = SimSection(drones_per_model=1, threads=1, capture={"mode": "fly-through"},
                             navigation={"preset": "ideal"}, record_interval_s=dt)
    stop_sec = through_sec.model_copy(update={"capture": CaptureSection(mode="stop")})
    stop = np.array([False, False, True, False, True, False])
    calm = ConstantWind([0.0, 0.0, 0.0])
    with FlightSimulator(through_sec) as sim:
        through = sim.fly(path, calm, 1)
        mixed = sim.fly(path.with_stops(stop, "fly-through"), calm, 1)
        all_stop = sim.fly(path.with_stops(np.ones(6, bool), "fly-through"), calm, 1)
    with FlightSimulator(stop_sec) as sim:
        stopped = sim.fly(path, calm, 1)
        # the path's modes override the mission's: fly-through views within a stop mission
        mixed_in_stop = sim.fly(path.with_stops(stop, "stop"), calm, 1)
    assert through.taken.all() and mixed.taken.all() and all_stop.taken.all()
    # every view marked stop: the stop mission itself, to the bit
    np.testing.assert_array_equal(all_stop.capture_time_s, stopped.capture_time_s)
    np.testing.assert_array_equal(all_stop.offsets, stopped.offsets)
    np.testing.assert_array_equal(mixed_in_stop.capture_time_s, mixed.capture_time_s)
    # the vehicle's speed at each shutter: at rest at the stop views, on the move through the others
    tr = mixed.trajectory
    speed = np.linalg.norm(np.gradient(tr.position[0], tr.time, axis=0), axis=1)
    at_shutter = np.interp(mixed.capture_time_s[0], tr.time, speed)
    assert at_shutter[stop].max() < 0.05
    assert at_shutter[[1, 3]].min() > 0.5
    # a stop costs its settle and dwell: the mixed mission lies between the pure ones
    end = [float(r.capture_time_s[0, -1]) for r in (through, mixed, stopped)]
    assert end[0] + 2 * 1.5 < end[1] < end[2]
    # the views before a stop are shot passing, as in the pure fly-through mission
    np.testing.assert_allclose(mixed.capture_time_s[0, :2], through.capture_time_s[0, :2], atol=1e-9)


# -- speed per leg ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["stop", "fly-through"])
def test_each_leg_is_flown_at_its_own_cruise_speed(mode):
    from dataclasses import replace

    from tests.sim.conftest import make_path
    from wrp_eval.sim.config import SimSection
    from wrp_eval.sim.flight import FlightSimulator
    from wrp_eval.sim.simple_wind import ConstantWind

    # a straight line of long legs (no corners: the cruise limit is the leg's own speed)
    base = make_path(n=4, spacing_m=40.0)
    path = replace(base, positions=base.positions * [1.0, 0.0, 0.0] + [0.0, 0.0, 20.0], yaw=np.zeros(4))
    dt = SimSection().timestep_s * SimSection().chunk_steps
    sec = SimSection(drones_per_model=1, threads=1, capture={"mode": mode}, navigation={"preset": "ideal"},
                     record_interval_s=dt)
    calm = ConstantWind([0.0, 0.0, 0.0])
    slow = path.with_leg_speeds(np.array([5.0, 2.0, 5.0]))
    with FlightSimulator(sec) as sim:
        plain = sim.fly(path, calm, 1)
        spelled = sim.fly(replace(path, leg_speed_m_s=np.full(3, path.speed_m_s)), calm, 1)
        slowed = sim.fly(slow, calm, 1)
    # every leg at the path's own speed, spelt out: the same flight to the bit
    np.testing.assert_array_equal(spelled.capture_time_s, plain.capture_time_s)
    np.testing.assert_array_equal(spelled.trajectory.position, plain.trajectory.position)
    assert slowed.taken.all()
    tr = slowed.trajectory
    speed = np.linalg.norm(np.gradient(tr.position[0], tr.time, axis=0), axis=1)
    x = tr.position[0, :, 0]
    for leg, cruise in enumerate((5.0, 2.0, 5.0)):
        inside = (x > 40.0 * leg + 10.0) & (x < 40.0 * leg + 30.0)      # the leg's middle, at cruise
        assert speed[inside].max() == pytest.approx(cruise, rel=0.05), leg
    # the slow leg takes about 40 / 2 - 40 / 5 = 12 s longer; the others as before, but for (fly-through) slowing
    # to the slow leg's 2 m/s at their shared view (5 -> 2 m/s at 2.5 m/s^2: ~0.4 s, ~0.56 s with the jerk window)
    legs = np.diff(slowed.capture_time_s[0]) - np.diff(plain.capture_time_s[0])
    assert legs[1] == pytest.approx(12.0, abs=1.5) and np.abs(legs[[0, 2]]).max() < 0.6
