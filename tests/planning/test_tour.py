import numpy as np
import pytest

from wrp_eval.planning.tour import (
    canonical_direction,
    detour_waypoints,
    flight_costs,
    local_search,
    nearest_neighbour_tours,
    open_at_longest_edge,
    solve_genetic,
    solve_multistart,
    solve_ortools,
    tour_length,
)
from wrp_eval.ship.nofly import segments_intrude

BOX = np.array([[-10.0, -5.0, 0.0], [10.0, 5.0, 20.0]])


def test_segment_box_hits():
    a = np.array([[-20.0, 0, 10], [-20.0, 0, 30], [-20.0, 8, 10], [0.0, -20, 10], [15.0, 0, 10]])
    b = np.array([[20.0, 0, 10], [20.0, 0, 30], [20.0, 8, 10], [0.0, 20, 10], [30.0, 0, 10]])
    assert segments_intrude(a, b, BOX).tolist() == [True, False, False, True, False]


def test_blocked_pairs_cost_the_over_the_top_detour():
    pos = np.array([[0.0, -20, 10], [0.0, 20, 10], [30.0, 20, 10]])
    cost, blocked = flight_costs(pos, BOX)
    assert blocked[0, 1] and blocked[1, 0] and not blocked[1, 2]
    # climb 10 -> 22 (box top 20 + 2 m), 40 m level, descend 12 m
    assert cost[0, 1] == pytest.approx(12 + 40 + 12)
    assert cost[1, 2] == pytest.approx(30.0)
    wp = detour_waypoints(pos[0], pos[1], BOX)
    np.testing.assert_allclose(wp, [[0, -20, 22], [0, 20, 22]])
    legs = np.array([pos[0], wp[0], wp[1]]), np.array([wp[0], wp[1], pos[1]])
    assert not segments_intrude(*legs, BOX).any()


def _circle(n, seed):
    ang = np.random.default_rng(seed).permutation(np.linspace(0, 2 * np.pi, n, endpoint=False))
    pos = np.column_stack([50 * np.cos(ang), 50 * np.sin(ang), np.zeros(n)])
    cost = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
    optimum = n * 2 * 50 * np.sin(np.pi / n)     # the regular polygon's perimeter
    return cost, optimum


@pytest.mark.parametrize("time_limit_s", [0.0, 0.2])   # deterministic descent, guided local search
def test_ortools_finds_the_polygon(time_limit_s):
    cost, optimum = _circle(25, 0)
    order = solve_ortools(cost, time_limit_s)
    assert sorted(order.tolist()) == list(range(25))
    assert tour_length(order, cost) == pytest.approx(optimum, rel=1e-6)


def test_multistart_finds_the_polygon_and_is_seeded():
    cost, optimum = _circle(30, 2)
    a = solve_multistart(cost, np.random.default_rng(9))
    b = solve_multistart(cost, np.random.default_rng(9))
    np.testing.assert_array_equal(a, b)
    assert sorted(a.tolist()) == list(range(30)) and a[0] == 0
    assert tour_length(a, cost) == pytest.approx(optimum, rel=1e-9)


def test_local_search_untangles_a_crossing_and_moves_a_stray_point():
    # square corners visited crosswise (0, 2, 1, 3): 2-opt removes the crossing
    sq = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], dtype=float)
    cost = np.linalg.norm(sq[:, None] - sq[None], axis=-1)
    assert tour_length(local_search(np.array([0, 2, 1, 3]), cost), cost) == pytest.approx(40.0)
    # points on a line visited 0 3 1 2 4 5: Or-opt / 2-opt bring the tour to 2 x the span
    line = np.column_stack([np.arange(6.0), np.zeros(6)])
    cost = np.linalg.norm(line[:, None] - line[None], axis=-1)
    assert tour_length(local_search(np.array([0, 3, 1, 2, 4, 5]), cost), cost) == pytest.approx(10.0)


def test_genetic_algorithm_is_seeded_and_finds_a_small_polygon():
    cost, optimum = _circle(10, 1)
    a = solve_genetic(cost, np.random.default_rng(5), population=60, generations=200)
    b = solve_genetic(cost, np.random.default_rng(5), population=60, generations=200)
    np.testing.assert_array_equal(a, b)
    assert sorted(a.tolist()) == list(range(10))
    assert tour_length(a, cost) == pytest.approx(optimum, rel=1e-6)


def test_open_at_longest_edge():
    cost = np.array([[0, 1, 9, 1], [1, 0, 1, 9], [9, 1, 0, 5], [1, 9, 5, 0]], dtype=float)
    order = open_at_longest_edge(np.array([0, 1, 2, 3]), cost)   # edges 1, 1, 5, 1: cut 2 -> 3
    assert order.tolist() == [3, 0, 1, 2]


# -- the compiled move scans against the vectorised numpy scans they replaced (same moves, same ties) -----------

def _two_opt_move_numpy(order, cost):
    """The 2-opt scan as numpy evaluated it before the compiled kernel (reference for the test)."""
    n = len(order)
    a, b = order, np.roll(order, -1)
    edge = cost[a, b]
    delta = cost[a[:, None], a[None, :]] + cost[b[:, None], b[None, :]] - edge[:, None] - edge[None, :]
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))
    i, j = i[keep], j[keep]
    k = int(np.argmin(delta[i, j]))
    if delta[i[k], j[k]] >= -1e-9:
        return None
    new = order.copy()
    new[i[k] + 1:j[k] + 1] = order[i[k] + 1:j[k] + 1][::-1]
    return new


def _or_opt_best_numpy(order, cost, max_len=3):
    """(i, j, length, reverse) of the best Or-opt move as the numpy scan found it, or None."""
    n = len(order)
    best, best_move = -1e-9, None
    pos = np.arange(n)
    u, v = order, np.roll(order, -1)
    for length in range(1, min(max_len, n - 3) + 1):
        first, last = order, np.roll(order, -(length - 1))
        prev, nxt = np.roll(order, 1), np.roll(order, -length)
        gain = cost[prev, first] + cost[last, nxt] - cost[prev, nxt]
        fwd = cost[u[None, :], first[:, None]] + cost[last[:, None], v[None, :]] - cost[u, v][None, :]
        rev = cost[u[None, :], last[:, None]] + cost[first[:, None], v[None, :]] - cost[u, v][None, :]
        offset = (pos[None, :] - pos[:, None]) % n
        valid = (offset >= length) & (offset != n - 1)
        for delta, reverse in ((fwd, False), (rev, True)):
            d = np.where(valid, delta - gain[:, None], np.inf)
            k = int(np.argmin(d))
            if d.flat[k] < best:
                best, best_move = d.flat[k], (k // n, k % n, length, reverse)
    return best_move


def test_compiled_move_scans_pick_the_moves_the_numpy_scans_picked():
    from wrp_eval.planning.tour import (
        _best_or_opt,
        _or_opt_move,
        _two_opt_move,
        flight_costs,
        neighbour_lists,
    )

    rng = np.random.default_rng(1)
    box = np.array([[10.0, 10.0, 0.0], [40.0, 25.0, 20.0]])
    for trial in range(150):
        n = int(rng.integers(4, 50))
        pts = rng.random((n, 3)) * 50
        if trial % 3 == 0:
            pts = np.round(pts / 10)  # many equal costs: the tie-breaking must match too
        # every other instance with the ship's over-the-top detours (a cost that is not a norm, symmetric only
        # up to rounding)
        cost = flight_costs(pts, box)[0] if trial % 2 else np.linalg.norm(pts[:, None] - pts[None], axis=-1)
        neighbours = neighbour_lists(cost)
        order = rng.permutation(n)
        # the whole 2-opt descent: the pruned scan must agree near the optimum too, where it skips the most
        while True:
            old, new = _two_opt_move_numpy(order, cost), _two_opt_move(order, cost, neighbours)
            assert (old is None and new is None) or np.array_equal(old, new)
            if new is None:
                break
            order = new
        # the Or-opt scan from a random tour and along an Or-opt descent from the 2-opt optimum
        for start in (rng.permutation(n), order):
            current = start
            while True:
                old_move = _or_opt_best_numpy(current, cost)
                _, i, j, length, reverse = _best_or_opt(current, cost, 3, neighbours)
                assert old_move == (None if i < 0 else (i, j, length, reverse))
                if i < 0:
                    break
                current = _or_opt_move(current, cost, neighbours)


def _or_opt_applied_numpy(order, i, j, length, reverse):
    """The Or-opt move as first written in numpy: the run taken out, put back after order[j]."""
    n = len(order)
    run_idx = (i + np.arange(length)) % n
    run = order[run_idx][::-1] if reverse else order[run_idx]
    rest = np.delete(order, run_idx)
    after = int(np.flatnonzero(rest == order[j])[0])
    return np.concatenate([rest[:after + 1], run, rest[after + 1:]])


def test_compiled_descent_makes_the_moves_of_the_move_by_move_descent():
    from wrp_eval.planning.tour import _best_or_opt, _two_opt_move, local_search, neighbour_lists

    rng = np.random.default_rng(7)
    for trial in range(60):
        n = int(rng.integers(4, 60))
        pts = rng.random((n, 3)) * 50
        if trial % 3 == 0:
            pts = np.round(pts / 10)   # ties
        cost = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
        neighbours = neighbour_lists(cost)
        order = rng.permutation(n)
        expected = order
        while True:     # one move at a time, Or-opt applied by the numpy reference
            new = _two_opt_move(expected, cost, neighbours)
            if new is None:
                _, i, j, length, reverse = _best_or_opt(expected, cost, 3, neighbours)
                if i < 0:
                    break
                new = _or_opt_applied_numpy(expected, i, j, length, reverse)
            expected = new
        assert np.array_equal(local_search(order, cost, neighbours), expected)


def test_multistart_tour_does_not_depend_on_the_thread_count(monkeypatch):
    from wrp_eval.planning import tour

    rng = np.random.default_rng(3)
    pts = rng.random((70, 3)) * 100
    cost = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    tours = []
    for cores in (1, 3):
        monkeypatch.setattr(tour.os, "cpu_count", lambda cores=cores: cores)
        tours.append(tour.solve_multistart(cost, np.random.default_rng(11), random_starts=5, kicks=10))
    assert np.array_equal(tours[0], tours[1])


def _nearest_neighbour_reference(cost: np.ndarray, start: int) -> list[int]:
    tour, left = [start], set(range(len(cost))) - {start}
    while left:
        here = tour[-1]
        nxt = min(sorted(left), key=lambda j: cost[here, j])     # ties: the lowest index
        tour.append(nxt)
        left.remove(nxt)
    return tour


def test_nearest_neighbour_tours_match_the_definition():
    rng = np.random.default_rng(5)
    pts = rng.integers(0, 6, size=(25, 2)).astype(float)        # a coarse grid: many equal distances (ties)
    cost = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    starts = np.array([0, 7, 24])
    tours = nearest_neighbour_tours(cost, starts)
    for row, start in enumerate(starts):
        assert tours[row].tolist() == _nearest_neighbour_reference(cost, int(start))


def test_canonical_direction_fixes_the_way_round_and_keeps_the_cycle():
    order = np.array([3, 0, 5, 1, 4, 2])
    fixed = canonical_direction(order)
    assert fixed[0] == 0 and fixed[1] < fixed[-1]
    assert fixed.tolist() == [0, 3, 2, 4, 1, 5]                  # the same cycle, run the other way
    assert np.array_equal(canonical_direction(fixed), fixed)
    assert np.array_equal(canonical_direction(fixed[::-1]), fixed)


def test_multistart_is_not_longer_than_the_ortools_descent_on_scattered_views():
    # 150 points in clusters (faces seen from a standoff): the default solver against OR-Tools' deterministic
    # greedy descent taken on by the same 2-opt / Or-opt descent
    rng = np.random.default_rng(8)
    centres = rng.random((6, 3)) * 200
    pts = (centres[:, None] + rng.normal(scale=15, size=(6, 25, 3))).reshape(-1, 3)
    cost = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    ours = solve_multistart(cost, np.random.default_rng(0))
    reference = local_search(solve_ortools(cost), cost)
    assert sorted(ours.tolist()) == list(range(len(pts)))
    assert tour_length(ours, cost) <= tour_length(reference, cost) + 1e-9
