"""The flight-state values: start of a batch, segment rows, capture and trajectory logs."""

import numpy as np

from wrp_eval.sim.flight_state import (NO_FAILURE, SETTLE, CaptureLog, FlightState, FlightTargets, Segment,
                                       TrajectoryLog)
from wrp_eval.sim.phases import CapturePose

VIEWS = np.array([[0.0, 0.0, 20.0], [10.0, 0.0, 21.0]])


def _targets(batch: int) -> FlightTargets:
    yaw = np.array([0.5, 1.0])
    body = np.tile(VIEWS, (batch, 1, 1)) + np.arange(batch)[:, None, None]
    return FlightTargets(VIEWS, yaw, np.full(2, -0.3), np.tile(yaw, (batch, 1)), body)


def test_a_batch_starts_settling_at_its_first_view_with_nothing_taken():
    targets = _targets(3)
    state = FlightState.start(targets)
    assert state.phase.tolist() == [SETTLE] * 3 and state.index.tolist() == [0, 0, 0]
    assert state.failure.tolist() == [NO_FAILURE] * 3 and state.flying.all()
    assert np.array_equal(state.segment.end, targets.body[:, 0]) and state.segment.length.tolist() == [0.0] * 3
    assert not state.captures.taken.any() and np.isnan(state.captures.offsets).all()
    # the segment owns its arrays: moving its end does not move the targets or its start
    state.segment.end[0] += 1.0
    assert np.array_equal(targets.body[0, 0], VIEWS[0]) and np.array_equal(state.segment.start[0], VIEWS[0])


def test_segment_rows_are_replaced_in_place():
    seg = Segment.at_rest(np.zeros((3, 3)), np.zeros(3))
    new = Segment(np.ones((1, 3)), np.full((1, 3), 2.0), np.array([0.1]), np.array([0.2]), np.array([1.7]),
                  np.array([[1.0, 0.0, 0.0]]), np.array([3.0]))
    seg.assign(np.array([1]), new)
    assert seg.length.tolist() == [0.0, 1.7, 0.0] and seg.duration.tolist() == [0.0, 3.0, 0.0]
    assert seg.end[1].tolist() == [2.0, 2.0, 2.0] and seg.direction[[0, 2]].tolist() == [[0.0] * 3] * 2


def test_capture_log_measures_offsets_against_the_plan():
    log = CaptureLog.empty(2, 2)
    pose = CapturePose(VIEWS[[1]] + [0.1, -0.2, 0.3], np.array([1.0 + 2 * np.pi]), np.array([-0.25]),
                       np.array([0.0]), np.array([False]))
    log.record(np.array([1]), np.array([1]), pose, _targets(2), 3.5)
    assert np.allclose(log.offsets[1, 1], [0.1, -0.2, 0.3, 0.0])      # yaw offset wrapped
    assert log.taken.tolist() == [[False, False], [False, True]] and log.time[1, 1] == 3.5
    assert np.isnan(log.offsets[0]).all() and np.isnan(log.offsets[1, 0]).all()
    sets = log.capture_sets(None)
    assert len(sets[0]) == 0 and sets[1].planned_index.tolist() == [1]
    assert np.array_equal(sets[1].positions, pose.position)


def test_trajectory_log_is_batch_first_and_keeps_its_own_copies():
    log = TrajectoryLog()
    drag = np.zeros((2, 3))
    for k in range(3):
        drag[:] = k
        log.append(0.2 * k, position=np.full((2, 3), k), reference=np.zeros((2, 3)), yaw=np.full(2, k),
                   tilt=np.zeros(2), thrust=np.full(2, 13.5), wind=np.zeros((2, 3)), drag=drag)
    tr = log.trajectory()
    assert tr.time.tolist() == [0.0, 0.2, 0.4]
    assert tr.position.shape == (2, 3, 3) and tr.yaw.shape == (2, 3)
    assert tr.drag[:, :, 0].tolist() == [[0.0, 1.0, 2.0]] * 2
