"""The flight loop's phase functions on small hand-built batches (no MuJoCo)."""

import numpy as np
import pytest

from wrp_eval.sim.capture_mode import through_profile, trigger_planes
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.controller import GAIN_PRESETS, PositionController
from wrp_eval.sim.flight_state import (
    AWAY,
    COMPLETED,
    DITCHED,
    DONE,
    DWELL,
    ENDED,
    FAILURES,
    LOST_ENERGY,
    LOST_HEADWAY,
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
    Shot,
)
from wrp_eval.sim.phases import (
    YAW_RATE_REF_RAD_S,
    Profile,
    Reference,
    advance,
    apply_endings,
    apply_transitions,
    check_failures,
    check_returns,
    control,
    no_headway,
    outcome_reasons,
    parked_pose,
    passing_views,
    plan_segments,
    reference,
    reference_profile,
    resume,
    setpoints,
    swap_batteries,
    take_photos,
    tick,
    transitions,
)
from wrp_eval.sim.vehicle import PHANTOM4

from .conftest import make_path

SEC = SimSection()
THROUGH_SEC = SimSection(capture={"mode": "fly-through"})
STOP_SEC = SimSection(capture={"mode": "stop"})
DT = SEC.timestep_s * SEC.chunk_steps
PROFILE = Profile.of(5.0, STOP_SEC)
THROUGH = Profile.of(5.0, THROUGH_SEC)
# three viewpoints at 20 m: 10 m east, then 10 m north, turning a quarter each time
VIEWS = np.array([[0.0, 0.0, 20.0], [10.0, 0.0, 20.0], [10.0, 10.0, 20.0]])
YAWS = np.array([0.0, np.pi / 2, np.pi])


def _targets(batch: int, through: bool = False) -> FlightTargets:
    """Targets of ``batch`` flights of VIEWS, the body targets on the viewpoints (a camera at the centre); in
    fly-through at rest at the ends, 2 m/s at the corner, legs at most 5 m/s."""
    targets = FlightTargets(VIEWS, YAWS, np.full(3, -0.3), np.tile(YAWS, (batch, 1)), np.tile(VIEWS, (batch, 1, 1)),
                            np.full(3, np.nan))
    if through:
        targets = targets.flown_through(np.tile([0.0, 2.0, 0.0], (batch, 1)), np.full((batch, 2), 5.0),
                                        *trigger_planes(targets.body))
    return targets


def _in_transit(batch: int, phase_time: float = 0.0, through: bool = False):
    """``batch`` flights on the first segment (view 0 -> view 1), ``phase_time`` s into it; photo 0 taken."""
    targets = _targets(batch, through)
    state = FlightState.start(targets)
    state.phase[:] = DWELL
    advance(state, targets, np.arange(batch), THROUGH if through else PROFILE)
    state.photo[:] = 1
    state.phase_time[:] = phase_time
    return targets, state


def _shot(position, yaw, time: float) -> Shot:
    """m photos at ``position`` (m, 3), ``yaw`` (m,) at ``time`` s, recorded as true (a perfect navigation)."""
    position = np.asarray(position, dtype=float)
    m = len(position)
    yaw = np.asarray(yaw, dtype=float)
    return Shot(np.full(m, time), position, yaw, np.full(m, -0.3), np.zeros(m), np.zeros(m, dtype=bool), position,
                yaw, np.zeros(m), np.ones(m), np.zeros((m, 4)))


# -- reference ----------------------------------------------------------------------------------------------
def test_reference_at_tau_zero_is_the_segment_start_at_rest():
    _, state = _in_transit(2)
    ref = reference(state, VIEWS[[0, 0]], PROFILE, SEC.leash_m)
    assert np.array_equal(ref.position, VIEWS[[0, 0]])
    assert np.allclose(ref.velocity, 0.0) and np.allclose(ref.acceleration, 0.0)
    assert np.allclose(ref.yaw, 0.0)
    assert not ref.held.any() and np.allclose(ref.distance_sq, 0.0)


def test_reference_moves_along_the_segment_and_ends_at_its_end():
    _, state = _in_transit(2)
    duration = state.segment.duration[0]
    state.phase_time[:] = [0.5 * duration, duration + 1.0]
    ref = reference(state, VIEWS[[0, 0]], PROFILE, leash_m=100.0)
    # the middle of the (symmetric) rest-to-rest profile is halfway along, at its top speed, half turned
    assert ref.position[0] == pytest.approx([5.0, 0.0, 20.0])
    assert 4.0 < ref.velocity[0, 0] <= 5.0 and ref.velocity[0, 1:].tolist() == [0.0, 0.0]
    assert ref.acceleration[0] == pytest.approx([0.0, 0.0, 0.0], abs=1e-9)
    assert ref.yaw[0] == pytest.approx(np.pi / 4)
    assert ref.position[1] == pytest.approx(VIEWS[1]) and ref.yaw[1] == pytest.approx(np.pi / 2)
    assert np.allclose(ref.velocity[1], 0.0)


def test_outside_transit_the_reference_waits_at_the_segments_end():
    _, state = _in_transit(1, phase_time=0.3)
    state.phase[:] = SETTLE
    ref = reference(state, VIEWS[[0]], PROFILE, SEC.leash_m)
    assert np.array_equal(ref.position, VIEWS[[1]])
    assert np.array_equal(ref.velocity, np.zeros((1, 3))) and ref.yaw[0] == pytest.approx(np.pi / 2)
    assert not ref.held.any()     # the leash holds only a moving reference


def test_the_leash_holds_the_reference_and_its_clock():
    _, state = _in_transit(2, phase_time=1.0)
    behind = np.array([[-3.0, 0.0, 20.0], [0.0, 0.0, 20.0]])   # flight 0 blown 3 m back
    ref = reference(state, behind, PROFILE, leash_m=2.0)
    assert ref.held.tolist() == [True, False]
    assert np.array_equal(ref.velocity[0], np.zeros(3)) and ref.velocity[1, 0] > 0.0
    tick(state, ref, DT)
    assert state.phase_time.tolist() == [1.0, 1.0 + DT]


def test_segment_duration_covers_a_pure_rotation_at_the_reference_yaw_rate():
    start = np.zeros((2, 3))
    end = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]])
    seg = plan_segments(start, end, np.array([0.0, 0.0]), np.array([np.pi - 0.1 + 2 * np.pi, 0.0]), PROFILE)
    assert seg.length.tolist() == [0.0, 5.0]
    assert np.array_equal(seg.direction, [[0.0, 0.0, 0.0], [0.6, 0.8, 0.0]])
    assert seg.dyaw[0] == pytest.approx(np.pi - 0.1)             # wrapped: the short way round
    assert seg.duration[0] == pytest.approx((np.pi - 0.1) / YAW_RATE_REF_RAD_S)
    assert seg.duration[1] == pytest.approx(reference_profile(5.0, 0.0, PROFILE.cruise_m_s,
                                                              PROFILE.acceleration_m_s2, PROFILE.jerk_window_s)[3])


# -- fly-through profile ------------------------------------------------------------------------------------
def test_the_profile_follows_the_capture_mode():
    assert THROUGH.through and not PROFILE.through
    assert PROFILE.jerk_window_s == pytest.approx(SEC.acceleration_m_s2 / SEC.jerk_m_s3)     # T = a / j
    assert Profile.of(5.0, STOP_SEC.model_copy(update={"jerk_m_s3": None})).jerk_window_s == 0.0
    assert SEC.capture.mode == "stop"                             # the default (issue 26: inspection missions stop)


def test_fly_through_segments_run_from_v0_to_v1():
    start, end = np.zeros((2, 3)), np.array([[12.0, 0.0, 0.0], [0.0, 0.0, 3.0]])
    v0, v1, v_max = np.array([2.0, 0.0]), np.array([4.0, 1.0]), np.array([5.0, 5.0])
    seg = plan_segments(start, end, np.zeros(2), np.zeros(2), THROUGH, v0, v1, v_max)
    assert seg.v0.tolist() == [2.0, 0.0] and seg.v1.tolist() == [4.0, 1.0] and seg.v_max.tolist() == [5.0, 5.0]
    expected = through_profile(seg.length, np.zeros(2), v0, v1, v_max, SEC.acceleration_m_s2, THROUGH.jerk_window_s)[3]
    assert seg.duration == pytest.approx(expected)
    # the reference starts at v0 along the segment (no rest at the start) and arrives at v1
    state = FlightState.start(_targets(2, through=True))
    state.segment.assign(np.arange(2), seg)
    state.phase[:] = TRANSIT
    ref = reference(state, start, THROUGH, leash_m=100.0)
    assert ref.velocity == pytest.approx(np.array([[2.0, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    state.phase_time[:] = seg.duration - 1e-9
    ref = reference(state, end, THROUGH, leash_m=100.0)
    assert ref.position == pytest.approx(end, abs=1e-6)
    assert ref.velocity == pytest.approx(np.array([[4.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), abs=1e-6)


# -- how flights end ------------------------------------------------------------------------------------------
def test_failure_causes_and_their_precedence():
    state = FlightState.start(_targets(5))
    state.phase[4] = DONE
    pos = np.tile(VIEWS[0], (5, 1))
    vel = np.zeros((5, 3))
    pos[:2, 2] = -0.1                   # 0 and 1 under water ...
    pos[0, 1] = np.nan                  # ... 0 also non-finite
    vel[2, 0] = np.inf                  # 2: a non-finite velocity
    pos[4, 2] = -1.0                    # 4 is done: it no longer fails
    cause = check_failures(state, pos, vel, out_of_time=False)
    assert cause.tolist() == [NON_FINITE, DITCHED, NON_FINITE, COMPLETED, COMPLETED]
    apply_endings(state, cause, 2.0)
    assert state.phase.tolist() == [ENDED, ENDED, ENDED, SETTLE, DONE]
    assert state.failed.tolist() == [True, True, True, False, False]
    reasons = outcome_reasons(state, SEC)
    assert reasons[:2] == ("non-finite state at t=2.00s", "ditched (below sea level) at t=2.00s")
    assert reasons[3:] == ("", "")


def test_flights_still_flying_at_the_time_limit_fail():
    state = FlightState.start(_targets(3))
    state.phase[1] = DONE
    pos = np.tile(VIEWS[0], (3, 1))
    pos[2, 2] = -1.0
    cause = check_failures(state, pos, np.zeros((3, 3)), out_of_time=True)
    assert cause.tolist() == [TIMED_OUT, COMPLETED, DITCHED]
    apply_endings(state, cause, 12.0)
    assert outcome_reasons(state, SEC) == (f"a sortie not finished within max_flight_time_s={SEC.max_flight_time_s:g}",
                                           "", "ditched (below sea level) at t=12.00s")
    assert state.flight_time.tolist() == [12.0, 0.0, 12.0]


def test_the_time_limit_can_be_per_flight():
    state = FlightState.start(_targets(4))
    state.phase[3] = DONE
    pos = np.tile(VIEWS[0], (4, 1))
    cause = check_failures(state, pos, np.zeros((4, 3)), out_of_time=np.array([False, True, False, True]))
    assert cause.tolist() == [COMPLETED, TIMED_OUT, COMPLETED, COMPLETED]
    with pytest.raises(ValueError, match="out_of_time"):
        check_failures(state, pos, np.zeros((4, 3)), out_of_time=np.ones(3, dtype=bool))


def test_the_autopilot_returns_home_on_its_battery_wind_limit_or_headway_without_failing():
    sec = SimSection(mission={"px4_wind_limit_m_s": 12.0, "operator_wind_limit_m_s": 10.0})
    state = FlightState.start(_targets(7))
    state.photo[:] = [1, 1, 2, 0, 0, 3, 3]
    state.phase[4] = ENDED                      # already ended: no new outcome
    state.outcome[4] = DITCHED
    battery = np.array([True, False, True, False, True, False, False])
    px4 = np.array([False, True, True, False, True, False, False])
    operator = np.array([False, True, False, False, False, False, False])
    stuck = np.array([False, False, False, False, True, True, True])
    reachable = np.array([True, True, True, True, True, True, False])
    cause = check_returns(state, battery, px4, operator, stuck, reachable)
    assert cause.tolist() == [RETURNED_BATTERY, RETURNED_WIND, RETURNED_BATTERY, COMPLETED, COMPLETED,
                              RETURNED_HEADWAY, LOST_HEADWAY]
    apply_endings(state, cause, 4.5)
    assert state.outcome.tolist() == [RETURNED_BATTERY, RETURNED_WIND, RETURNED_BATTERY, COMPLETED, DITCHED,
                                      RETURNED_HEADWAY, LOST_HEADWAY]
    assert state.phase.tolist() == [ENDED, ENDED, ENDED, SETTLE, ENDED, ENDED, ENDED]
    assert state.flight_time.tolist() == [4.5, 4.5, 4.5, 0.0, 0.0, 4.5, 4.5]
    assert state.failed.tolist() == [False, False, False, False, True, False, True]     # lost = failed
    reasons = outcome_reasons(state, sec)
    assert "battery" in reasons[0] and f"({sec.battery.reserve:g})" in reasons[0]
    assert "t=4.50s" in reasons[0] and "(before view 1)" in reasons[0]
    assert "PX4-style limit 12 m/s" in reasons[1] and "before view 1" in reasons[1]
    assert reasons[2].startswith("returned home: battery") and "(before view 2)" in reasons[2] and reasons[3] == ""
    assert "no headway towards view 3" in reasons[5] and reasons[6].startswith("lost: no headway")
    operator_only = check_returns(FlightState.start(_targets(1)), *(np.array([v]) for v in
                                                                    (False, False, True, False, True)))
    assert operator_only.tolist() == [RETURNED_WIND_AVERAGE]
    # due home on energy against a wind it cannot beat: lost, not a return (and so no battery swap)
    no_way_home = check_returns(FlightState.start(_targets(1)), *(np.array([v]) for v in
                                                                  (True, False, False, False, False)))
    assert no_way_home.tolist() == [LOST_ENERGY] and LOST_ENERGY in FAILURES


def test_no_headway_needs_the_timeout_without_progress_beyond_the_leash():
    state = FlightState.start(_targets(3))
    state.phase[:] = TRANSIT
    state.segment.end[:] = [[100.0, 0.0, 20.0]] * 3
    timeout, progress, leash = 30.0, 1.0, 2.0
    # row 0 makes progress, row 1 is held 10 m short, row 2 hovers at its waypoint (within the leash)
    for t in np.arange(0.0, 31.0, 1.0):
        pos = np.array([[50.0 + t, 0.0, 20.0], [90.0, 0.0, 20.0], [99.0, 0.0, 20.0]])
        stuck = no_headway(state, pos, float(t), timeout, progress, leash)
        if t < timeout:
            assert not stuck.any()
    assert stuck.tolist() == [False, True, False]
    state.index[1] = 1                   # a new waypoint starts a new record
    assert not no_headway(state, pos, 31.0, timeout, progress, leash).any()


def test_a_battery_return_with_sorties_left_is_a_swap_and_the_resume_flies_from_the_breakpoint():
    targets = _targets(4)
    state = FlightState.start(targets)
    state.index[:] = 1
    state.photo[:] = 1
    state.sortie[:] = [1, 3, 2, 2]
    state.sortie_views[:] = [1, 1, 1, 0]            # flight 3's second sortie took no view
    cause = np.array([RETURNED_BATTERY, RETURNED_BATTERY, COMPLETED, RETURNED_BATTERY])
    away, left = swap_batteries(state, cause, max_sorties=3)
    assert away.tolist() == [0] and left.tolist() == [COMPLETED, RETURNED_BATTERY, COMPLETED, RETURNED_BATTERY]
    assert state.phase[0] == AWAY and not state.flying[0] and state.active[0]
    breakpoint_ = np.array([[5.0, 1.0, 20.0]])
    profile = Profile(5.0, 2.5, 0.0)
    resume(state, targets, away, breakpoint_, np.array([0.3]), 400.0, profile)
    assert state.phase[0] == TRANSIT and state.sortie[0] == 2 and state.sortie_start[0] == 400.0
    np.testing.assert_array_equal(state.segment.start[0], breakpoint_[0])
    np.testing.assert_array_equal(state.segment.end[0], targets.body[0, 1])
    assert state.segment.yaw0[0] == 0.3 and state.phase_time[0] == 0.0


def test_no_cause_changes_nothing():
    state = FlightState.start(_targets(2))
    apply_endings(state, np.full(2, COMPLETED), 3.0)
    assert state.phase.tolist() == [SETTLE, SETTLE] and state.flight_time.tolist() == [0.0, 0.0]
    assert state.outcome.tolist() == [COMPLETED, COMPLETED]


# -- transitions and the trigger ----------------------------------------------------------------------------
def test_within_the_tolerances_settle_turns_to_dwell():
    targets = _targets(5)
    state = FlightState.start(targets)          # settling at view 0 (yaw 0)
    state.phase_time[:] = 1.0
    pos = np.tile(VIEWS[0], (5, 1))
    vel = np.zeros((5, 3))
    yaw = np.zeros(5)
    pos[1, 0] += SEC.settle_position_m * 1.1    # too far
    vel[2, 2] = SEC.settle_speed_m_s * 1.1      # too fast
    yaw[3] = np.radians(SEC.settle_yaw_deg) * 1.1   # turned too far
    pos[4, 0] += SEC.settle_position_m * 0.9    # within every tolerance
    vel[4, 0] = SEC.settle_speed_m_s * 0.9
    yaw[4] = -np.radians(SEC.settle_yaw_deg) * 0.9
    moves = transitions(state, pos, vel, yaw, targets, SEC, dwell_s=1.0, through=False)
    assert moves.to_dwell.tolist() == [True, False, False, False, True]
    assert not moves.to_settle.any() and not moves.trigger.any() and not moves.chain.any()
    apply_transitions(state, moves)
    assert state.phase.tolist() == [DWELL, SETTLE, SETTLE, SETTLE, DWELL]
    assert state.phase_time.tolist() == [0.0, 1.0, 1.0, 1.0, 0.0]


def test_settle_times_out_and_transit_ends_with_its_reference():
    targets = _targets(2)
    state = FlightState.start(targets)
    state.phase_time[:] = SEC.settle_timeout_s
    far = np.tile(VIEWS[0] + [3.0, 0.0, 0.0], (2, 1))
    moves = transitions(state, far, np.zeros((2, 3)), np.zeros(2), targets, SEC, dwell_s=1.0, through=False)
    assert moves.to_dwell.all()                 # the photo is taken anyway
    _, state = _in_transit(2)
    state.phase_time[:] = state.segment.duration - [DT, 0.0]
    moves = transitions(state, far, np.zeros((2, 3)), np.zeros(2), targets, SEC, dwell_s=1.0, through=False)
    assert moves.to_settle.tolist() == [False, True] and not moves.to_dwell.any() and not moves.chain.any()


def test_fly_through_chains_through_interior_views_and_stops_at_the_last():
    targets, state = _in_transit(3, through=True)
    state.index[2] = 2                          # flight 2 flies the last segment
    state.phase_time[:] = state.segment.duration - [DT, 0.0, 0.0]
    far = np.tile(VIEWS[0], (3, 1))             # wherever the vehicles are: the reference does not wait
    moves = transitions(state, far, np.zeros((3, 3)), np.zeros(3), targets, SEC, dwell_s=0.0, through=True)
    assert moves.chain.tolist() == [False, True, False] and moves.to_settle.tolist() == [False, False, True]
    advance(state, targets, np.flatnonzero(moves.trigger | moves.chain), THROUGH)
    apply_transitions(state, moves)
    assert state.phase.tolist() == [TRANSIT, TRANSIT, SETTLE] and state.index.tolist() == [1, 2, 2]
    assert state.phase_time[1:].tolist() == [0.0, 0.0] and state.phase_time[0] > 0.0
    # flight 1's new segment leaves the corner at its planned 2 m/s and stops at the last view
    assert (state.segment.v0[1], state.segment.v1[1], state.segment.v_max[1]) == (2.0, 0.0, 5.0)
    assert np.array_equal(state.segment.start[1], VIEWS[1]) and np.array_equal(state.segment.end[1], VIEWS[2])
    assert state.photo.tolist() == [1, 1, 1]    # chaining takes no photo


def test_the_trigger_fires_after_the_dwell():
    targets = _targets(3)
    state = FlightState.start(targets)
    state.phase[:] = [DWELL, DWELL, SETTLE]
    state.phase_time[:] = [1.0 - 1e-12, 1.0 - 0.05, 1.0]
    moves = transitions(state, VIEWS[[0, 0, 0]], np.zeros((3, 3)), np.zeros(3), targets, SEC, dwell_s=1.0,
                        through=False)
    assert moves.trigger.tolist() == [True, False, False]


def test_a_view_is_passed_when_the_estimate_crosses_its_mitre_plane():
    targets, state = _in_transit(6, through=True)
    # view 1 (10, 0, 20) is a right-angle corner (east, then north): its plane is normal to the bisector of the
    # two legs, (1, 1, 0) / sqrt(2), so a vehicle cutting the corner crosses it too
    pos = np.array([[10.3, 0.2, 21.0], [9.9, 0.0, 20.0], [9.0, 2.0, 20.0], [10.5, 0.0, 20.0],
                    [10.5, 0.0, 20.0], [10.5, 0.0, 20.0]])
    state.photo[3] = 0                          # view 0 is photographed hovering, never on the move
    state.photo[4] = 2                          # already photographed view 1; its reference not yet at view 2
    state.phase[5] = ENDED
    rows, past, normal, skipped = passing_views(state, pos, targets, 2.0)
    assert rows.tolist() == [0, 2] and past == pytest.approx(np.array([0.5, 1.0]) / np.sqrt(2.0))
    assert normal == pytest.approx(np.tile([1.0, 1.0, 0.0], (2, 1)) / np.sqrt(2.0))
    assert skipped.size == 0
    # the last view (10, 10, 20), reached from the south: the plane y = 10, normal to the arriving leg
    state.index[:] = 2
    state.photo[:] = 2
    pos[:, 1] = [10.0, 9.0, 11.0, 10.0, 10.0, 10.0]
    rows, past, normal, skipped = passing_views(state, pos, targets, 2.0)
    assert rows.tolist() == [0, 2, 3, 4] and past == pytest.approx([0.0, 1.0, 0.0, 0.0])
    assert normal == pytest.approx(np.tile([0.0, 1.0, 0.0], (4, 1)))
    state.photo[:] = 3                          # every view taken
    assert passing_views(state, pos, targets, 2.0)[0].size == 0


def test_on_a_hairpin_a_vehicle_off_the_track_is_not_past_the_view_long_before_it():
    # view 1 at (10, 0, 20), reached going east, left turning back by 170 deg: the mitre plane runs almost along
    # the arriving leg, so a vehicle 1 m off the track at view 0 is "past" it by ~0.6 m, 10 m short of the view
    back = np.radians(170.0)
    views = np.array([[0.0, 0.0, 20.0], [10.0, 0.0, 20.0], [10.0 + 10 * np.cos(back), 10 * np.sin(back), 20.0]])
    targets = FlightTargets(views, np.zeros(3), np.full(3, -0.3), np.zeros((2, 3)), np.tile(views, (2, 1, 1)),
                            np.full(3, np.nan))
    targets = targets.flown_through(np.zeros((2, 3)), np.full((2, 2), 5.0), *trigger_planes(targets.body))
    state = FlightState.start(targets)
    state.phase[:] = TRANSIT
    state.index[:] = 1
    state.photo[:] = 1
    pos = np.array([[0.0, 1.0, 20.0], [9.0, 1.0, 20.0]])          # 10 m short, and 1 m short of the view
    rows, past, _, _ = passing_views(state, pos, targets, 2.0)
    assert past.size == 1 and rows.tolist() == [1]
    # without the reach gate the plane alone would fire the photo 10 m early
    assert passing_views(state, pos, targets, np.inf)[0].tolist() == [0, 1]


def test_a_chained_segment_starts_as_far_in_as_the_clock_ran_past_the_last_one():
    targets = _targets(3)
    state = FlightState.start(targets)
    state.phase[:] = TRANSIT
    state.segment.duration[:] = 2.0
    state.phase_time[:] = [2.03, 1.5, 2.0]
    moves = transitions(state, targets.body[:, 0], np.zeros((3, 3)), targets.yaw[:, 0], targets, SEC, 0.0, True)
    assert moves.chain.tolist() == [True, False, True]
    apply_transitions(state, moves)
    assert state.phase_time == pytest.approx([0.03, 1.5, 0.0])


def test_in_fly_through_the_integral_grows_in_transit_too():
    ref = Reference(np.zeros((2, 3)), np.zeros((2, 3)), np.zeros((2, 3)), np.zeros(2), np.zeros(2),
                    np.zeros(2, dtype=bool))
    phase = np.array([TRANSIT, SETTLE])
    assert setpoints(ref, phase, np.zeros((0, 3)), np.zeros(2)).integrate.tolist() == [False, True]
    assert setpoints(ref, phase, np.zeros((0, 3)), np.zeros(2), through=True).integrate.tolist() == [True, True]


def test_a_view_not_passed_before_the_reference_is_two_views_on_is_skipped():
    views = np.stack([10.0 * np.arange(4), np.zeros(4), np.full(4, 20.0)], axis=1)
    targets = FlightTargets(views, np.zeros(4), np.full(4, -0.3), np.zeros((3, 4)), np.tile(views, (3, 1, 1)),
                            np.full(4, np.nan))
    targets = targets.flown_through(np.zeros((3, 4)), np.full((3, 3), 5.0), *trigger_planes(targets.body))
    state = FlightState.start(targets)
    state.phase[:] = TRANSIT
    state.photo[:] = 1
    state.index[:] = [2, 3, 3]
    pos = np.array([[5.0, 0.0, 20.0], [5.0, 0.0, 20.0], [10.0, 0.0, 20.0]])    # short of view 1 but the last
    rows, _, _, skipped = passing_views(state, pos, targets, 2.0)
    assert rows.tolist() == [2] and skipped.tolist() == [1]


def test_take_photos_records_the_next_view_and_moves_the_photo_on():
    targets = _targets(3)
    state = FlightState.start(targets)
    state.phase[:] = DWELL
    state.index[2] = state.photo[2] = 2         # flight 2 is at the last view
    pos = np.array([[0.1, -0.2, 20.3], [10.0, 10.0, 20.0]])
    take_photos(state, targets, np.array([0, 2]), _shot(pos, [0.02, np.pi], 7.5))
    cap = state.captures
    assert cap.offsets[0, 0] == pytest.approx([0.1, -0.2, 0.3, 0.02])
    assert cap.offsets[2, 2] == pytest.approx([0.0, 0.0, 0.0, 0.0], abs=1e-12)
    assert cap.taken.tolist() == [[True, False, False], [False, False, False], [False, False, True]]
    assert cap.time[0, 0] == 7.5 and np.isnan(cap.time[1]).all()
    assert np.isnan(cap.offsets[1]).all()            # flight 1 took nothing
    assert state.flight_time.tolist() == [7.5, 0.0, 7.5] and state.photo.tolist() == [1, 0, 3]
    assert state.phase.tolist() == [DWELL] * 3       # the phase is advance()'s business
    take_photos(state, targets, np.array([], dtype=int), _shot(np.zeros((0, 3)), [], 9.0))
    assert state.flight_time.tolist() == [7.5, 0.0, 7.5]
    sets = cap.capture_sets(None)
    assert [len(s) for s in sets] == [1, 0, 1] and sets[2].planned_index.tolist() == [2]


def test_advance_starts_the_next_segment_or_ends_at_the_last_view():
    targets = _targets(3)
    state = FlightState.start(targets)
    state.phase[:] = DWELL
    state.index[2] = 2
    advance(state, targets, np.array([0, 2]), PROFILE)
    # flight 0 now flies from view 0's body target to view 1's; flight 2 is done; flight 1 untouched
    assert state.phase.tolist() == [TRANSIT, DWELL, DONE] and state.index.tolist() == [1, 0, 2]
    assert np.array_equal(state.segment.start[0], VIEWS[0]) and np.array_equal(state.segment.end[0], VIEWS[1])
    assert state.segment.length[0] == 10.0 and state.segment.dyaw[0] == pytest.approx(np.pi / 2)
    assert state.segment.v0[0] == state.segment.v1[0] == 0.0               # stop mode: rest to rest
    assert np.array_equal(state.segment.end[1], VIEWS[0]) and state.segment.length[1] == 0.0
    assert state.flying.tolist() == [True, True, False]


# -- control ------------------------------------------------------------------------------------------------
def test_setpoints_pad_the_fillers_integrate_only_at_rest_and_correct_the_heading():
    _, state = _in_transit(2)
    state.phase[1] = DWELL
    ref = reference(state, VIEWS[[0, 1]], PROFILE, SEC.leash_m)
    sp = setpoints(ref, state.phase, np.array([[0.0, 0.0, 70.0], [1.0, 0.0, 70.0]]), np.array([0.1, -0.2]))
    assert sp.position.shape == (4, 3) and np.array_equal(sp.position[2:, 2], [70.0, 70.0])
    assert np.array_equal(sp.velocity[2:], np.zeros((2, 3))) and np.array_equal(sp.yaw[2:], [0.0, 0.0])
    assert sp.integrate.tolist() == [False, True, True, True]
    # a compass reading 0.1 rad too far left: the airframe is turned 0.1 rad right of the reference
    assert sp.yaw[:2] == pytest.approx(ref.yaw - [0.1, -0.2])
    unpadded = setpoints(ref, state.phase, np.zeros((0, 3)), np.zeros(2))
    assert unpadded.position is ref.position and np.array_equal(unpadded.yaw, ref.yaw)


def test_control_holds_a_level_hover_at_the_reference_with_the_weight():
    controller = PositionController(PHANTOM4, GAIN_PRESETS["default"], 2)
    _, state = _in_transit(2)
    state.phase[:] = DWELL
    ref = reference(state, VIEWS[[1, 1]], PROFILE, SEC.leash_m)
    rot = np.tile(np.eye(3), (2, 1, 1))
    hover = setpoints(ref, state.phase, np.zeros((0, 3)), np.zeros(2))
    motors, quat = control(controller, VIEWS[[1, 1]], np.zeros((2, 3)), rot, hover, DT, PHANTOM4)
    assert motors == pytest.approx(np.full((2, 4), PHANTOM4.weight_n / 4.0))
    # level, heading the segment's end yaw (pi/2)
    assert quat == pytest.approx(np.tile([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)], (2, 1)))
    # a vehicle 1 m below its reference climbs: more thrust, capped at the motors' maximum
    motors, _ = control(controller, VIEWS[[1, 1]] - [0.0, 0.0, 1.0], np.zeros((2, 3)), rot, hover, DT, PHANTOM4)
    assert np.all(motors > PHANTOM4.weight_n / 4.0) and np.all(motors <= PHANTOM4.max_thrust_per_motor_n)


def test_ended_flights_are_parked_where_they_are_above_the_sea():
    park = np.array([[0.0, 0.0, 30.0, 1.0, 0.0, 0.0, 0.0], [5.0, 5.0, 30.0, 0.0, 0.0, 0.0, 1.0]])
    qpos = parked_pose(np.array([[3.0, 4.0, -2.0], [np.nan, 1.0, 10.0]]), park)
    assert np.array_equal(qpos[0], [3.0, 4.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    assert np.array_equal(qpos[1], [5.0, 1.0, 10.0, 0.0, 0.0, 0.0, 1.0])


# -- targets ------------------------------------------------------------------------------------------------
def test_targets_put_the_camera_on_the_commanded_viewpoint():
    path = make_path(3)
    offsets = np.zeros((2, 3, 4))
    offsets[1, :, 2] = 1.0
    offsets[1, :, 3] = 0.5
    targets = FlightTargets.from_path(path, 2, offsets, PHANTOM4.camera_offset_m)
    yaw = path.yaw + offsets[..., 3]
    cam = np.asarray(PHANTOM4.camera_offset_m)
    camera = targets.body + np.stack([np.cos(yaw) * cam[0], np.sin(yaw) * cam[0], np.full_like(yaw, cam[2])], -1)
    assert np.allclose(camera, path.positions + offsets[..., :3])
    assert np.array_equal(targets.yaw, yaw) and np.array_equal(targets.plan_yaw, path.yaw)
    with pytest.raises(ValueError, match="view_offsets must have shape"):
        FlightTargets.from_path(path, 2, np.zeros((2, 2, 4)), PHANTOM4.camera_offset_m)
