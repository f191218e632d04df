"""The one no-fly geometry: an open box (touching is not an intrusion), one tolerance, one safety predicate."""

from __future__ import annotations

import numpy as np

from wrp_eval.planning.tour import flight_costs
from wrp_eval.ship.nofly import (
    EDGE_TOLERANCE_M,
    above_min_altitude,
    flyable,
    inside_no_fly_box,
    leg_flyable,
    segments_intrude,
)
from wrp_eval.ship.particulars import ShipParticulars, ShipType
from wrp_eval.ship.proxy import build_proxy

BOX = np.array([[-10.0, -5.0, 0.0], [10.0, 5.0, 20.0]])


def test_points_inside_the_open_box_only():
    points = np.array([[0.0, 0.0, 10.0],      # inside
                       [10.0, 0.0, 10.0],     # on the bow face: not inside
                       [10.0, 5.0, 20.0],     # on a corner
                       [0.0, 0.0, 20.0 - 0.5 * EDGE_TOLERANCE_M],   # within the tolerance of the top
                       [0.0, 0.0, 20.0 - 1e-6],               # a micrometre inside
                       [11.0, 0.0, 10.0]])    # outside
    np.testing.assert_array_equal(inside_no_fly_box(points, BOX), [True, False, False, False, True, False])
    assert inside_no_fly_box(np.broadcast_to(points, (2, 6, 3)), BOX).shape == (2, 6)


def test_segment_slab_test_cases():
    mid, out = BOX.mean(axis=0), BOX[1] + 5.0
    cases = [  # (start, end, intrudes)
        ([0.0, -10.0, 10.0], [0.0, 10.0, 10.0], True),        # straight through
        ([0.0, -10.0, 21.0], [0.0, 10.0, 21.0], False),       # over the top
        ([-15.0, -10.0, 10.0], [15.0, -10.0, 10.0], False),   # along the side, outside
        ([0.0, -10.0, 10.0], mid, True),                      # ends inside
        (mid, mid, True),                                     # zero length, inside
        (out, out, False),                                    # zero length, outside
        ([-15.0, 0.0, 10.0], [-11.0, 0.0, 10.0], False),      # stops short of the stern
        ([-15.0, -10.0, 20.0], [15.0, 10.0, 20.0], False),    # slides over the top face: touching only
        ([0.0, -10.0, 10.0], [0.0, -5.0, 10.0], False),       # ends on a face
        ([-20.0, 0.0, 10.0], [0.0, -10.0, 10.0], False),      # grazes the edge line x = -10, y = -5
        ([-20.0, -15.0, 10.0], [0.0, 5.0, 30.0], False),      # touches the corner (-10, -5, 20) only
        ([-20.0, -5.0, 10.0], [0.0, 5.0, 10.0], True),        # from outside the edge, then inside
    ]
    starts, ends, want = (np.array([c[k] for c in cases], dtype=float) for k in range(3))
    np.testing.assert_array_equal(segments_intrude(starts, ends, BOX), want.astype(bool))
    intrude = segments_intrude(np.broadcast_to(starts, (3, 12, 3)), np.broadcast_to(ends, (3, 12, 3)), BOX)
    assert intrude.shape == (3, 12)


def test_random_segments_agree_with_dense_sampling():
    rng = np.random.default_rng(4)
    starts = rng.uniform([-25, -15, -5], [25, 15, 30], (400, 3))
    ends = rng.uniform([-25, -15, -5], [25, 15, 30], (400, 3))
    got = segments_intrude(starts, ends, BOX)
    t = np.linspace(0, 1, 4001)[None, :, None]
    sampled = inside_no_fly_box(starts[:, None] + t * (ends - starts)[:, None], BOX).any(axis=1)
    assert got.any() and not got.all()
    np.testing.assert_array_equal(got[sampled], True)   # sampling finds a subset of the true intrusions
    assert (got & ~sampled).sum() <= 2                   # (only legs that clip a corner by < a sample)


def test_flyable_is_altitude_and_box_and_legs_need_both_ends():
    points = np.array([[0.0, 20.0, 5.0], [0.0, 20.0, 5.0 - 0.5 * EDGE_TOLERANCE_M], [0.0, 20.0, 4.9],
                       [0.0, 0.0, 10.0]])
    np.testing.assert_array_equal(above_min_altitude(points, 5.0), [True, True, False, True])
    np.testing.assert_array_equal(flyable(points, BOX, 5.0), [True, True, False, False])
    np.testing.assert_array_equal(flyable(points, None, 5.0), [True, True, False, True])
    starts = np.array([[0.0, -20.0, 10.0], [0.0, -20.0, 10.0], [0.0, -20.0, 4.0]])
    ends = np.array([[0.0, 20.0, 10.0], [0.0, 20.0, 25.0], [0.0, 20.0, 25.0]])
    # through the box; climbing over it too late (at y = -5 it is at z 15.6 < 20); starting too low
    np.testing.assert_array_equal(leg_flyable(starts, ends, BOX, 5.0), [False, False, False])
    over = np.array([[0.0, -20.0, 20.0]]), np.array([[0.0, 20.0, 20.0]])
    assert leg_flyable(*over, BOX, 5.0).all()       # level with the top face: touching, flyable


def test_planner_and_export_agree_on_a_leg_touching_the_box():
    """A leg along the no-fly box's top face: the tour prices it as a straight flight (not blocked), and the
    export's predicate accepts it (the closed rule refused it)."""
    proxy = build_proxy(ShipParticulars(140.0, 20.0, 12.0, 19.0, 6.0, ShipType.STYLIZED))
    box = proxy.no_fly_bounds()
    top = box[1, 2]
    legs = np.array([[-80.0, 0.0, top], [80.0, 0.0, top]])
    cost, blocked = flight_costs(legs, box)
    assert not blocked.any() and cost[0, 1] == 160.0
    assert leg_flyable(legs[:1], legs[1:], box, 5.0).all() and flyable(legs, box, 5.0).all()
