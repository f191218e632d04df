"""The flight-state values: start of a batch, segment rows, outcomes, capture and trajectory logs."""

import numpy as np
import pytest

from wrp_eval.camera import Camera
from wrp_eval.sim.capture_mode import trigger_planes
from wrp_eval.sim.flight_state import (
    COMPLETED,
    DITCHED,
    DONE,
    ENDED,
    FAILURES,
    LOST_ENERGY,
    LOST_HEADWAY,
    LOST_OUTSIDE,
    NON_FINITE,
    OUTCOME_NAMES,
    RETURNED_BATTERY,
    RETURNED_HEADWAY,
    RETURNED_WIND,
    RETURNED_WIND_AVERAGE,
    SETTLE,
    TIMED_OUT,
    TRAJECTORY_FIELDS,
    CaptureLog,
    FlightState,
    FlightTargets,
    Segment,
    Shot,
    TrajectoryLog,
)

from .conftest import make_path

VIEWS = np.array([[0.0, 0.0, 20.0], [10.0, 0.0, 21.0]])


def _targets(batch: int) -> FlightTargets:
    yaw = np.array([0.5, 1.0])
    body = np.tile(VIEWS, (batch, 1, 1)) + np.arange(batch)[:, None, None]
    return FlightTargets(VIEWS, yaw, np.full(2, -0.3), np.tile(yaw, (batch, 1)), body, np.array([12.0, np.nan]))


def _shot(position, yaw, time, estimated_position=None, estimated_yaw=None, **fields) -> Shot:
    """A Shot of m = len(position) photos; the fields not given are level, unsaturated, blur 0, charge 1."""
    position = np.asarray(position, dtype=float)
    m = len(position)
    values = {"time": np.full(m, time), "position": position, "yaw": np.asarray(yaw, dtype=float),
              "pitch": np.full(m, -0.3), "roll": np.zeros(m), "saturated": np.zeros(m, dtype=bool),
              "estimated_position": position if estimated_position is None else np.asarray(estimated_position),
              "estimated_yaw": np.asarray(yaw if estimated_yaw is None else estimated_yaw, dtype=float),
              "blur_px": np.zeros(m), "charge": np.ones(m), "ship_motion": np.zeros((m, 4))}
    values.update(fields)
    return Shot(**values)


def test_a_batch_starts_settling_at_its_first_view_with_nothing_taken():
    targets = _targets(3)
    state = FlightState.start(targets)
    assert state.phase.tolist() == [SETTLE] * 3 and state.index.tolist() == [0, 0, 0]
    assert state.photo.tolist() == [0, 0, 0] and state.phase_time.tolist() == [0.0] * 3
    assert state.outcome.tolist() == [COMPLETED] * 3 and state.flying.all() and not state.failed.any()
    assert np.array_equal(state.segment.end, targets.body[:, 0]) and state.segment.length.tolist() == [0.0] * 3
    for name in ("duration", "v0", "v1", "v_max"):
        assert getattr(state.segment, name).tolist() == [0.0] * 3
    assert not state.captures.taken.any() and np.isnan(state.captures.offsets).all()
    assert np.isnan(state.captures.estimated_offsets).all() and not state.captures.saturated.any()
    # the segment owns its arrays: moving its end does not move the targets or its start
    state.segment.end[0] += 1.0
    assert np.array_equal(targets.body[0, 0], VIEWS[0]) and np.array_equal(state.segment.start[0], VIEWS[0])


def test_segment_rows_are_replaced_in_place():
    seg = Segment.at_rest(np.zeros((3, 3)), np.zeros(3))
    new = Segment(np.ones((1, 3)), np.full((1, 3), 2.0), np.array([0.1]), np.array([0.2]), np.array([1.7]),
                  np.array([[1.0, 0.0, 0.0]]), np.array([3.0]), np.array([1.0]), np.array([2.0]), np.array([4.0]))
    seg.assign(np.array([1]), new)
    assert seg.length.tolist() == [0.0, 1.7, 0.0] and seg.duration.tolist() == [0.0, 3.0, 0.0]
    assert seg.end[1].tolist() == [2.0, 2.0, 2.0] and seg.direction[[0, 2]].tolist() == [[0.0] * 3] * 2
    assert seg.v0.tolist() == [0.0, 1.0, 0.0] and seg.v1.tolist() == [0.0, 2.0, 0.0]
    assert seg.v_max.tolist() == [0.0, 4.0, 0.0]


def test_only_crashes_lost_vehicles_and_the_time_limit_are_failures():
    state = FlightState.start(_targets(11))
    state.outcome[:] = [COMPLETED, NON_FINITE, DITCHED, TIMED_OUT, RETURNED_BATTERY, RETURNED_WIND,
                        RETURNED_WIND_AVERAGE, RETURNED_HEADWAY, LOST_HEADWAY, LOST_OUTSIDE, LOST_ENERGY]
    state.phase[:] = [DONE] + [ENDED] * 10
    assert set(FAILURES) == {NON_FINITE, DITCHED, TIMED_OUT, LOST_HEADWAY, LOST_OUTSIDE, LOST_ENERGY}
    # going home on the battery reserve, a wind limit or without headway is what a real autopilot does: not a
    # failure; a vehicle that cannot get home (no headway, no energy against the wind) or is blown out of the
    # field is lost
    assert state.failed.tolist() == [False, True, True, True, False, False, False, False, True, True, True]
    assert not state.flying.any() and not state.active.any()
    assert len(OUTCOME_NAMES) == 11


def test_capture_log_measures_true_and_recorded_offsets_against_the_plan():
    log = CaptureLog.empty(2, 2)
    true_pos = VIEWS[[1]] + [0.1, -0.2, 0.3]
    shot = _shot(true_pos, [1.0 + 2 * np.pi], 3.5, estimated_position=true_pos + [1.0, 0.5, -0.25],
                 estimated_yaw=[1.0 - 0.05], roll=np.array([0.02]), saturated=np.array([True]),
                 blur_px=np.array([0.7]), charge=np.array([0.8]), ship_motion=np.array([[0.1, 0.01, 0.02, 0.0]]))
    log.record(np.array([1]), np.array([1]), shot, _targets(2))
    assert log.offsets[1, 1] == pytest.approx([0.1, -0.2, 0.3, 0.0])        # yaw offset wrapped
    assert log.estimated_offsets[1, 1] == pytest.approx([1.1, 0.3, 0.05, -0.05])
    assert log.taken.tolist() == [[False, False], [False, True]] and log.time[1, 1] == 3.5
    assert log.saturated.tolist() == [[False, False], [False, True]]
    assert (log.roll[1, 1], log.blur_px[1, 1], log.charge[1, 1]) == (0.02, 0.7, 0.8)
    assert log.ship_motion[1, 1].tolist() == [0.1, 0.01, 0.02, 0.0]
    assert np.isnan(log.offsets[0]).all() and np.isnan(log.offsets[1, 0]).all() and np.isnan(log.blur_px[0]).all()
    sets = log.capture_sets(Camera())
    assert len(sets[0]) == 0 and sets[1].planned_index.tolist() == [1]
    assert np.array_equal(sets[1].positions, true_pos)
    # the image's position prior is the navigation's record, its roll the gimbal's residual
    assert np.array_equal(sets[1].position_priors(), shot.estimated_position)
    assert sets[1].roll.tolist() == [0.02]


def test_trajectory_log_is_batch_first_and_keeps_its_own_copies():
    log = TrajectoryLog()
    drag = np.zeros((2, 3))
    for k in range(3):
        drag[:] = k
        log.append(0.2 * k, position=np.full((2, 3), k), reference=np.zeros((2, 3)), yaw=np.full(2, k),
                   tilt=np.zeros(2), thrust=np.full(2, 13.5), wind=np.zeros((2, 3)), drag=drag,
                   power=np.full(2, 150.0 + k), charge=np.full(2, 1.0 - 0.01 * k))
    tr = log.trajectory()
    assert tr.time.tolist() == [0.0, 0.2, 0.4]
    assert tr.position.shape == (2, 3, 3) and tr.yaw.shape == (2, 3)
    assert tr.drag[:, :, 0].tolist() == [[0.0, 1.0, 2.0]] * 2
    assert tr.power[0].tolist() == [150.0, 151.0, 152.0] and tr.charge[1] == pytest.approx([1.0, 0.99, 0.98])
    assert {"power", "charge"} <= set(TRAJECTORY_FIELDS)


def test_targets_carry_the_views_depth_and_the_fly_through_speeds():
    path = make_path(3)
    plain = FlightTargets.from_path(path, 2, None, (0.0, 0.0, 0.0))
    assert np.isnan(plain.depth).all() and plain.vertex_speed is None and plain.leg_speed is None
    assert np.array_equal(plain.body, np.broadcast_to(path.positions, (2, 3, 3)))   # camera at the centre
    deep = FlightTargets.from_path(path, 2, None, (0.0, 0.0, 0.0), depth_m=np.array([5.0, 6.0, 7.0]))
    assert deep.depth.tolist() == [5.0, 6.0, 7.0] and (deep.batch, deep.n_views) == (2, 3)
    fast = deep.flown_through(np.ones((2, 3)), np.full((2, 2), 5.0), *trigger_planes(deep.body))
    assert fast.vertex_speed.shape == (2, 3) and fast.leg_speed.tolist() == [[5.0, 5.0]] * 2
    assert deep.vertex_speed is None and np.array_equal(fast.body, deep.body)    # a new value, the old one kept


def test_a_reversed_tour_starts_at_its_own_first_view_and_keeps_its_planned_home():
    path = make_path(5)
    ahead = FlightTargets.from_path(path, 2, None, np.zeros(3))
    back = FlightTargets.from_path(path.reversed(), 2, None, np.zeros(3))
    np.testing.assert_array_equal(ahead.home, ahead.body[:, 0])
    np.testing.assert_array_equal(back.home, back.body[:, -1])          # the plan's viewpoint 0, flown last
    np.testing.assert_array_equal(back.home, ahead.home)
