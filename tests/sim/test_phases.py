"""The flight loop's phase functions on small hand-built batches (no MuJoCo)."""

import numpy as np
import pytest

from wrp_eval.sim.config import SimSection
from wrp_eval.sim.controller import GAIN_PRESETS, PositionController
from wrp_eval.sim.flight_state import (DITCHED, DONE, DWELL, FAILED, LOST, NO_FAILURE, NON_FINITE, SETTLE,
                                       STALLED, TIMED_OUT, TRANSIT, FlightState, FlightTargets)
from wrp_eval.sim.phases import (YAW_RATE_REF_RAD_S, Profile, apply_failures, apply_transitions,
                                 capture_pose, check_failures, control, failure_reasons, parked_pose,
                                 plan_segments, reference, setpoints, take_photos, tick, transitions)
from wrp_eval.sim.vehicle import PHANTOM4

from .conftest import make_path

SEC = SimSection()
DT = SEC.timestep_s * SEC.chunk_steps
PROFILE = Profile.of(5.0, SEC)
# three viewpoints at 20 m: 10 m east, then 10 m north, turning a quarter each time
VIEWS = np.array([[0.0, 0.0, 20.0], [10.0, 0.0, 20.0], [10.0, 10.0, 20.0]])
YAWS = np.array([0.0, np.pi / 2, np.pi])


def _targets(batch: int) -> FlightTargets:
    """Targets of ``batch`` flights of VIEWS, the body targets on the viewpoints (a camera at the centre)."""
    return FlightTargets(VIEWS, YAWS, np.full(3, -0.3), np.tile(YAWS, (batch, 1)), np.tile(VIEWS, (batch, 1, 1)))


def _in_transit(batch: int, phase_time: float = 0.0):
    """``batch`` flights on the first segment (view 0 -> view 1), ``phase_time`` s into it."""
    targets = _targets(batch)
    state = FlightState.start(targets)
    rows = np.arange(batch)
    state.segment.assign(rows, plan_segments(targets.body[:, 0], targets.body[:, 1], targets.yaw[:, 0],
                                             targets.yaw[:, 1], PROFILE))
    state.index[:] = 1
    state.phase[:] = TRANSIT
    state.phase_time[:] = phase_time
    return targets, state


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
    assert seg.duration[1] == pytest.approx(PROFILE.at(np.array([5.0]), np.zeros(1))[3][0])


# -- failures -----------------------------------------------------------------------------------------------
def _far(state, distance_m):
    """Vehicle positions ``distance_m`` (batch,) m east of their references, and the reference there."""
    at = reference(state, np.zeros((len(state.phase), 3)), PROFILE, SEC.leash_m).position
    pos = at + np.asarray(distance_m)[:, None] * [1.0, 0.0, 0.0]
    return pos, reference(state, pos, PROFILE, SEC.leash_m)


def test_beyond_fail_distance_for_longer_than_fail_time_is_lost():
    state = FlightState.start(_targets(3))
    state.lost_time[:] = [SEC.fail_time_s, SEC.fail_time_s - 2 * DT, SEC.fail_time_s]
    # flights 0 and 1 are beyond the fail distance, 1 not yet for long enough; 2 is back within it
    d = SEC.fail_distance_m
    pos, ref = _far(state, [d + 0.5, d + 0.5, d - 0.5])
    fails = check_failures(state, pos, np.zeros((3, 3)), ref, DT, SEC, out_of_time=False)
    assert fails.cause.tolist() == [LOST, NO_FAILURE, NO_FAILURE]
    assert fails.lost_time == pytest.approx([SEC.fail_time_s + DT, SEC.fail_time_s - DT, 0.0])
    apply_failures(state, fails, 4.5)
    assert state.phase.tolist() == [FAILED, SETTLE, SETTLE]
    assert state.failure.tolist() == [LOST, NO_FAILURE, NO_FAILURE]
    assert state.flight_time.tolist() == [4.5, 0.0, 0.0]
    assert failure_reasons(state, SEC) == (
        "lost position: > 5 m from the reference for > 3 s at t=4.50s (before view 0)", "", "")


def test_failure_causes_and_their_precedence():
    state = FlightState.start(_targets(5))
    state.phase[4] = DONE
    state.held_time[:] = SEC.stall_time_s
    state.lost_time[:] = SEC.fail_time_s
    pos, ref = _far(state, np.full(5, SEC.fail_distance_m + 1.0))    # every flight lost ...
    pos[:2, 2] = -0.1                                                # ... 0 and 1 also under water
    pos[0, 1] = np.nan                                               # ... 0 also non-finite
    ref = ref._replace(held=np.array([True, True, True, False, True]))   # ... all but 3 stalled
    fails = check_failures(state, pos, np.zeros((5, 3)), ref, DT, SEC, out_of_time=False)
    # a finished flight does not fail; otherwise non-finite > ditched > stalled > lost
    assert fails.cause.tolist() == [NON_FINITE, DITCHED, STALLED, LOST, NO_FAILURE]
    assert fails.held_time.tolist() == [SEC.stall_time_s + DT] * 3 + [0.0, SEC.stall_time_s + DT]
    apply_failures(state, fails, 2.0)
    reasons = failure_reasons(state, SEC)
    assert reasons[0] == "non-finite state at t=2.00s"
    assert reasons[2] == "no headway: > 2 m behind the reference for > 20 s at t=2.00s (before view 0)"
    assert reasons[4] == "" and state.phase[4] == DONE


def test_flights_still_flying_at_the_time_limit_fail():
    targets = _targets(3)
    state = FlightState.start(targets)
    state.phase[1] = DONE
    pos, ref = _far(state, np.zeros(3))
    pos[2, 2] = -1.0
    fails = check_failures(state, pos, np.zeros((3, 3)), ref, DT, SEC, out_of_time=True)
    assert fails.cause.tolist() == [TIMED_OUT, NO_FAILURE, DITCHED]
    apply_failures(state, fails, 12.0)
    assert failure_reasons(state, SEC) == (f"not finished within max_flight_time_s={SEC.max_flight_time_s:g}",
                                           "", "ditched (below sea level) at t=12.00s")


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
    moves = transitions(state, pos, vel, yaw, targets, SEC, dwell_s=1.0)
    assert moves.to_dwell.tolist() == [True, False, False, False, True]
    assert not moves.to_settle.any() and not moves.trigger.any()
    apply_transitions(state, moves)
    assert state.phase.tolist() == [DWELL, SETTLE, SETTLE, SETTLE, DWELL]
    assert state.phase_time.tolist() == [0.0, 1.0, 1.0, 1.0, 0.0]


def test_settle_times_out_and_transit_ends_with_its_reference():
    targets = _targets(2)
    state = FlightState.start(targets)
    state.phase_time[:] = SEC.settle_timeout_s
    far = np.tile(VIEWS[0] + [3.0, 0.0, 0.0], (2, 1))
    moves = transitions(state, far, np.zeros((2, 3)), np.zeros(2), targets, SEC, dwell_s=1.0)
    assert moves.to_dwell.all()                 # the photo is taken anyway
    _, state = _in_transit(2)
    state.phase_time[:] = state.segment.duration - [DT, 0.0]
    moves = transitions(state, far, np.zeros((2, 3)), np.zeros(2), targets, SEC, dwell_s=1.0)
    assert moves.to_settle.tolist() == [False, True] and not moves.to_dwell.any()


def test_the_trigger_fires_after_the_dwell():
    targets = _targets(3)
    state = FlightState.start(targets)
    state.phase[:] = [DWELL, DWELL, SETTLE]
    state.phase_time[:] = [1.0 - 1e-12, 1.0 - 0.05, 1.0]
    moves = transitions(state, VIEWS[[0, 0, 0]], np.zeros((3, 3)), np.zeros(3), targets, SEC, dwell_s=1.0)
    assert moves.trigger.tolist() == [True, False, False]


def _tilted(pitch_rad: float, roll_rad: float, yaw_rad: float) -> np.ndarray:
    """(3, 3) world-from-body rotation Rz(yaw) Ry(pitch) Rx(roll)."""
    cz, sz, cy, sy, cx, sx = (np.cos(yaw_rad), np.sin(yaw_rad), np.cos(pitch_rad), np.sin(pitch_rad),
                              np.cos(roll_rad), np.sin(roll_rad))
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    return rz @ ry @ rx


def test_capture_pose_is_the_true_camera_and_the_gimbal_compensates_within_its_range():
    # flight 0: nose down 10 deg, so the gimbal joint lifts by 10 deg; flight 1: rolled 40 deg, 5 beyond the
    # gimbal; flight 2 asks for +45 deg pitch, 15 above the gimbal's reach
    rot = np.stack([_tilted(np.radians(10.0), 0.0, 0.3), _tilted(0.0, np.radians(40.0), 0.0), np.eye(3)])
    pos = np.array([[1.0, 2.0, 20.0], [0.0, 0.0, 20.0], [5.0, 5.0, 5.0]])
    wanted = np.radians([-30.0, -30.0, 45.0])
    pose = capture_pose(pos, rot, np.array([0.3, 0.0, 0.0]), wanted, PHANTOM4)
    cam = np.asarray(PHANTOM4.camera_offset_m)
    assert np.allclose(pose.position, pos + np.einsum("nij,j->ni", rot, cam))
    assert pose.position[0, 2] < pos[0, 2] + cam[2]        # the tilted nose lowers the camera
    assert np.degrees(pose.pitch) == pytest.approx([-30.0, -30.0, 30.0])
    assert np.degrees(pose.residual_roll) == pytest.approx([0.0, 5.0, 0.0])
    assert pose.saturated.tolist() == [False, True, True]
    assert np.array_equal(pose.yaw, [0.3, 0.0, 0.0])


def test_take_photos_records_the_true_pose_and_starts_the_next_segment():
    targets = _targets(3)
    state = FlightState.start(targets)
    state.phase[:] = DWELL
    state.index[2] = 2                              # flight 2 is at the last view
    pos = np.array([[0.1, -0.2, 20.3], [9.0, 9.0, 9.0], [10.0, 10.0, 20.0]])
    rot = np.stack([_tilted(0.05, 0.0, 0.02), np.eye(3), np.eye(3)])
    yaw = np.array([0.02, 0.0, np.pi])
    take_photos(state, targets, np.array([0, 2]), pos, rot, yaw, 7.5, PROFILE, PHANTOM4)
    cap = state.captures
    expected = capture_pose(pos[[0]], rot[[0]], yaw[[0]], targets.plan_pitch[[0]], PHANTOM4)
    assert np.array_equal(cap.position[0, 0], expected.position[0])
    assert np.allclose(cap.offsets[0, 0], [*(expected.position[0] - VIEWS[0]), 0.02])
    assert cap.taken.tolist() == [[True, False, False], [False, False, False], [False, False, True]]
    assert cap.time[0, 0] == 7.5 and np.isnan(cap.time[1]).all()
    assert np.isnan(cap.offsets[1]).all()            # flight 1 took nothing
    assert state.flight_time.tolist() == [7.5, 0.0, 7.5]
    # flight 0 now flies from view 0's body target to view 1's; flight 2 is done; flight 1 untouched
    assert state.phase.tolist() == [TRANSIT, DWELL, DONE] and state.index.tolist() == [1, 0, 2]
    assert np.array_equal(state.segment.start[0], VIEWS[0]) and np.array_equal(state.segment.end[0], VIEWS[1])
    assert state.segment.length[0] == 10.0 and state.segment.dyaw[0] == pytest.approx(np.pi / 2)
    assert np.array_equal(state.segment.end[1], VIEWS[0]) and state.segment.length[1] == 0.0
    sets = cap.capture_sets(None)
    assert [len(s) for s in sets] == [1, 0, 1] and sets[2].planned_index.tolist() == [2]


# -- control ------------------------------------------------------------------------------------------------
def test_setpoints_pad_the_fillers_and_integrate_only_at_rest():
    _, state = _in_transit(2)
    state.phase[1] = DWELL
    ref = reference(state, VIEWS[[0, 1]], PROFILE, SEC.leash_m)
    sp = setpoints(ref, state.phase, np.array([[0.0, 0.0, 70.0], [1.0, 0.0, 70.0]]))
    assert sp.position.shape == (4, 3) and np.array_equal(sp.position[2:, 2], [70.0, 70.0])
    assert np.array_equal(sp.velocity[2:], np.zeros((2, 3))) and np.array_equal(sp.yaw[2:], [0.0, 0.0])
    assert sp.integrate.tolist() == [False, True, True, True]


def test_control_holds_a_level_hover_at_the_reference_with_the_weight():
    controller = PositionController(PHANTOM4, GAIN_PRESETS["default"], 2)
    _, state = _in_transit(2)
    state.phase[:] = DWELL
    ref = reference(state, VIEWS[[1, 1]], PROFILE, SEC.leash_m)
    rot = np.tile(np.eye(3), (2, 1, 1))
    motors, quat = control(controller, VIEWS[[1, 1]], np.zeros((2, 3)), rot, setpoints(ref, state.phase,
                                                                                     np.zeros((0, 3))),
                           DT, PHANTOM4)
    assert motors == pytest.approx(np.full((2, 4), PHANTOM4.weight_n / 4.0))
    # level, heading the segment's end yaw (pi/2)
    assert quat == pytest.approx(np.tile([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)], (2, 1)))
    # a vehicle 1 m below its reference climbs: more thrust, capped at the motors' maximum
    motors, _ = control(controller, VIEWS[[1, 1]] - [0.0, 0.0, 1.0], np.zeros((2, 3)), rot,
                        setpoints(ref, state.phase, np.zeros((0, 3))), DT, PHANTOM4)
    assert np.all(motors > PHANTOM4.weight_n / 4.0) and np.all(motors <= PHANTOM4.max_thrust_per_motor_n)


def test_failed_flights_are_parked_where_they_are_above_the_sea():
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
