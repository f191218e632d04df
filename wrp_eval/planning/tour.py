"""The closed tour through the views (paper Sec. 3.3: a TSP; the paper uses a genetic algorithm).

Flight cost between two views is the Euclidean distance when the straight segment stays outside the
no-fly box (the ship stage's one test, :func:`wrp_eval.ship.nofly.segments_intrude`: touching the box is not
an intrusion); otherwise the "over the top" detour: climb vertically to ``clearance`` above the box, fly
level, descend (an upper bound on the shortest way round, always flyable). ``detour_waypoints`` gives the
two corner points of such a detour so that the path can include them.

Solvers: ``multistart`` (default; deterministic for a seeded generator): nearest-neighbour tours from view 0
and from random views, each taken to a 2-opt / Or-opt local optimum (the best move found by a compiled scan of
all moves, :mod:`wrp_eval.compiled`; a whole descent is one compiled call, the descents spread over the cores:
the same optima on any number of cores), then iterated local search from the best; ``ortools``: OR-Tools
routing with guided local search under a time limit; ``ga``: a seeded genetic algorithm in the paper's spirit
(order crossover + inversion mutation, elitism, tournament selection).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from ortools.constraint_solver import pywrapcp, routing_enums_pb2

from wrp_eval.compiled import kernel
from wrp_eval.ship.nofly import segments_intrude

_COST_SCALE = 100.0  # OR-Tools works in integers: centimetres
_CLEARANCE_M = 2.0


def detour_height(box: np.ndarray) -> float:
    return float(box[1, 2] + _CLEARANCE_M)


def flight_costs(positions: np.ndarray, box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(cost (n, n) m, blocked (n, n) bool): Euclidean, or the over-the-top detour where blocked."""
    a = positions[:, None, :]
    b = positions[None, :, :]
    euclid = np.linalg.norm(a - b, axis=-1)
    blocked = segments_intrude(np.broadcast_to(a, euclid.shape + (3,)), np.broadcast_to(b, euclid.shape + (3,)),
                               box)
    z_top = np.maximum(detour_height(box), np.maximum(a[..., 2], b[..., 2]))
    level = np.linalg.norm(a[..., :2] - b[..., :2], axis=-1)
    detour = (z_top - a[..., 2]) + level + (z_top - b[..., 2])
    return np.where(blocked, detour, euclid), blocked


def detour_waypoints(a: np.ndarray, b: np.ndarray, box: np.ndarray) -> np.ndarray:
    """The two corners (2, 3) of the over-the-top detour from a to b."""
    z = max(detour_height(box), a[2], b[2])
    return np.array([[a[0], a[1], z], [b[0], b[1], z]])


def tour_length(order: np.ndarray, cost: np.ndarray) -> float:
    """Closed-tour cost of ``order`` (n,)."""
    return float(cost[order, np.roll(order, -1)].sum())


def _ortools_route(icost: list, strategy: str, time_limit_s: float) -> tuple[int, np.ndarray]:
    """One OR-Tools routing solve: (integer cost, order). time_limit_s <= 0: greedy descent to a local
    optimum (deterministic); > 0: guided local search until the time limit."""
    n = len(icost)
    manager = pywrapcp.RoutingIndexManager(n, 1, 0)
    routing = pywrapcp.RoutingModel(manager)
    # the cost matrix handed over whole: no Python callback per arc (the solver asks for millions of arcs)
    routing.SetArcCostEvaluatorOfAllVehicles(routing.RegisterTransitMatrix(icost))
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = getattr(routing_enums_pb2.FirstSolutionStrategy, strategy)
    metaheuristics = routing_enums_pb2.LocalSearchMetaheuristic
    if time_limit_s > 0:
        params.local_search_metaheuristic = metaheuristics.GUIDED_LOCAL_SEARCH
        params.time_limit.FromMilliseconds(max(1, int(round(time_limit_s * 1000))))
    else:
        params.local_search_metaheuristic = metaheuristics.GREEDY_DESCENT
    solution = routing.SolveWithParameters(params)
    if solution is None:  # cannot happen for a complete graph; keep the identity tour then
        return 2 ** 62, np.arange(n)
    order, index = [], routing.Start(0)
    while not routing.IsEnd(index):
        order.append(manager.IndexToNode(index))
        index = solution.Value(routing.NextVar(index))
    return int(solution.ObjectiveValue()), np.array(order, dtype=int)


@kernel
def _best_two_opt(order: np.ndarray, cost: np.ndarray, neighbours: np.ndarray) -> tuple[float, int, int]:
    """(delta, i, j) of the best improving 2-opt move of a closed tour: reversing order[i+1 .. j] changes the
    length by delta < 0; over i < j - 1, (0, n - 1) excluded, ties to the smallest (i, j); (inf, -1, -1) when
    no move improves. ``neighbours`` (n, n - 1): each node's other nodes by increasing cost
    (:func:`neighbour_lists`).

    A move replaces edges (a, b) and (c, d) by (a, c) and (b, d); it improves only if (a, c) is shorter than
    (a, b) or (b, d) shorter than (c, d) (else the new pair costs at least the old). So from each edge
    (x, y) only the nodes nearer x than y (the move's other edge starts there) and nearer y than x (the
    other edge ends there) are scanned: every improving move is met, at a cost that falls as the tour
    shortens (Bentley 1992, "Fast algorithms for geometric traveling salesman problems", neighbour lists).
    The delta is the full scan's expression, so the move chosen is the full scan's (tests/planning)."""
    n = len(order)
    pos = np.empty(n, dtype=np.int64)
    edge = np.empty(n)
    for k in range(n):
        pos[order[k]] = k
        edge[k] = cost[order[k], order[(k + 1) % n]]
    best, best_i, best_j = np.inf, -1, -1
    for k in range(n):
        for end in range(2):        # 0: scan from the edge's first node x, 1: from its second node y
            node = order[k] if end == 0 else order[(k + 1) % n]
            # a tolerance over the edge: the cost matrix may differ from its transpose by rounding
            bound = edge[k] + 1e-6
            for other in neighbours[node]:
                if cost[node, other] >= bound:
                    break
                m = pos[other] if end == 0 else (pos[other] - 1) % n
                i, j = (k, m) if k < m else (m, k)
                if j < i + 2 or (i == 0 and j == n - 1):
                    continue
                delta = cost[order[i], order[j]] + cost[order[i + 1], order[(j + 1) % n]] - edge[i] - edge[j]
                if delta < best or (delta == best and (i < best_i or (i == best_i and j < best_j))):
                    best, best_i, best_j = delta, i, j
    return best, best_i, best_j


def neighbour_lists(cost: np.ndarray) -> np.ndarray:
    """(n, n - 1): each node's other nodes by increasing ``cost`` from it (ties by index)."""
    order = np.argsort(cost, axis=1, kind="stable")
    mine = order == np.arange(len(cost))[:, None]
    return order[~mine].reshape(len(cost), len(cost) - 1)


def _two_opt_move(order: np.ndarray, cost: np.ndarray, neighbours: np.ndarray) -> np.ndarray | None:
    """The best improving 2-opt move of a closed tour, or None at a 2-opt optimum."""
    if len(order) < 4:
        return None
    delta, i, j = _best_two_opt(order, cost, neighbours)
    if delta >= -1e-9:
        return None
    return _two_opt_applied(order, i, j)


@kernel
def _two_opt_applied(order: np.ndarray, i: int, j: int) -> np.ndarray:
    """A copy of ``order`` with order[i+1 .. j] reversed."""
    new = order.copy()
    new[i + 1:j + 1] = order[i + 1:j + 1][::-1]
    return new


@kernel
def _best_or_opt(order: np.ndarray, cost: np.ndarray, max_len: int,
                 neighbours: np.ndarray) -> tuple[float, int, int, int, bool]:
    """(delta, i, j, length, reverse) of the best Or-opt move: the run order[i .. i+length-1] (length 1 ..
    max_len) moved between u = order[j] and v = order[j+1], reversed or not; i = -1 when no move improves by
    more than 1e-9. Ties go to the smallest (length, reverse, i, j). ``neighbours``: :func:`neighbour_lists`.

    The run's end that meets u is a, the one that meets v is b; the move changes the length by
    c(u, a) + c(b, v) - c(u, v) - gain (gain: what taking the run out saves). It can only improve if c(u, a) or
    c(b, v) is below (gain + c(u, v)) / 2, so from each run only the nodes nearer a or b than (gain + the
    longest edge) / 2 are tried as u or v: every improving move is met and its delta is the full scan's
    expression, the same move is chosen (tests/planning)."""
    n = len(order)
    pos = np.empty(n, dtype=np.int64)
    edge = np.empty(n)
    for k in range(n):
        pos[order[k]] = k
        edge[k] = cost[order[k], order[(k + 1) % n]]
    longest = edge.max()
    best, best_i, best_j, best_len, best_rev = np.inf, -1, -1, 0, 0
    for length in range(1, min(max_len, n - 3) + 1):
        for i in range(n):
            first, last = order[i], order[(i + length - 1) % n]
            prev, nxt = order[(i - 1) % n], order[(i + length) % n]
            gain = cost[prev, first] + cost[last, nxt] - cost[prev, nxt]
            bound = 0.5 * (gain + longest) + 1e-6
            for reverse in range(2):
                end_u, end_v = (last, first) if reverse else (first, last)
                for side in range(2):
                    near = end_u if side == 0 else end_v
                    for other in neighbours[near]:
                        if cost[near, other] >= bound:
                            break
                        j = pos[other] if side == 0 else (pos[other] - 1) % n
                        offset = j - i if j >= i else j - i + n
                        if offset < length or offset == n - 1:  # edge j outside the run, not just before it
                            continue
                        d = cost[end_u, order[j]] + cost[end_v, order[(j + 1) % n]] - edge[j] - gain
                        if d < best or (d == best and (length, reverse, i, j) < (best_len, best_rev, best_i,
                                                                                    best_j)):
                            best, best_i, best_j, best_len, best_rev = d, i, j, length, reverse
    if best >= -1e-9:
        return -1e-9, -1, -1, 0, False
    return best, best_i, best_j, best_len, best_rev == 1


def _or_opt_move(order: np.ndarray, cost: np.ndarray, neighbours: np.ndarray,
                 max_len: int = 3) -> np.ndarray | None:
    """The best improving Or-opt move (a run of 1..max_len views moved elsewhere, either way round), or None."""
    n = len(order)
    if n < 4:
        return None
    _, i, j, length, reverse = _best_or_opt(order, cost, max_len, neighbours)
    if i < 0:
        return None
    return _or_opt_applied(order, i, j, length, reverse)


@kernel
def _or_opt_applied(order: np.ndarray, i: int, j: int, length: int, reverse: bool) -> np.ndarray:
    """A copy of ``order`` with the run order[i .. i+length-1] (cyclic; reversed if ``reverse``) moved to just
    after order[j] (j outside the run); the other views keep their order."""
    n = len(order)
    run = np.empty(length, dtype=order.dtype)
    in_run = np.zeros(n, dtype=np.bool_)
    for k in range(length):
        run[k] = order[(i + k) % n]
        in_run[(i + k) % n] = True
    if reverse:
        run = run[::-1].copy()
    new = np.empty_like(order)
    w = 0
    for k in range(n):
        if in_run[k]:
            continue
        new[w] = order[k]
        w += 1
        if k == j:
            new[w:w + length] = run
            w += length
    return new


@kernel
def _descend(order: np.ndarray, cost: np.ndarray, neighbours: np.ndarray) -> np.ndarray:
    """2-opt and Or-opt (runs of up to 3) best-improvement descent of a closed tour to a local optimum, in one
    compiled call (no Python between moves, the GIL released): each step takes the best 2-opt move, or when
    none improves the best Or-opt move, exactly as :func:`_two_opt_move` / :func:`_or_opt_move` choose them."""
    if len(order) < 4:
        return order
    while True:
        delta, i, j = _best_two_opt(order, cost, neighbours)
        if delta < -1e-9:
            order = _two_opt_applied(order, i, j)
            continue
        _, i, j, length, reverse = _best_or_opt(order, cost, 3, neighbours)
        if i < 0:
            return order
        order = _or_opt_applied(order, i, j, length, reverse)


@kernel
def _descend_rows(tours: np.ndarray, cost: np.ndarray, neighbours: np.ndarray) -> np.ndarray:
    """:func:`_descend` of each row of ``tours`` (k, n), in one compiled call: (k, n)."""
    out = np.empty_like(tours)
    for row in range(tours.shape[0]):
        out[row] = _descend(tours[row].copy(), cost, neighbours)
    return out


def local_search(order: np.ndarray, cost: np.ndarray, neighbours: np.ndarray | None = None) -> np.ndarray:
    """2-opt and Or-opt best-improvement descent to a local optimum (:func:`_descend`). ``neighbours``:
    :func:`neighbour_lists` of ``cost`` (computed here when not given)."""
    neighbours = neighbour_lists(cost) if neighbours is None else neighbours
    return _descend(np.asarray(order, dtype=np.int64), np.asarray(cost, dtype=float), neighbours)


_KICK_SPAN = 12        # views spanned by a local kick: local kicks suit tours that sweep face after face
_ACCEPT_WORSE = 0.01   # threshold acceptance: a kicked tour up to 1 % longer becomes the current one


def iterated_local_search(order: np.ndarray, cost: np.ndarray, kicks: int,
                          rng: np.random.Generator, neighbours: np.ndarray | None = None) -> np.ndarray:
    """Iterated local search (double-bridge kicks, Martin, Otto & Felten 1991) for a fixed number of kicks:
    deterministic for a seeded ``rng``. Returns the best tour found, starting at node 0."""
    n = len(order)
    neighbours = neighbour_lists(cost) if neighbours is None else neighbours
    best = local_search(np.asarray(order), cost, neighbours)
    best_len = tour_length(best, cost)
    if n < 8:
        return np.roll(best, -int(np.flatnonzero(best == 0)[0]))
    span = min(n - 1, _KICK_SPAN)
    current, current_len = best, best_len
    for kick in range(kicks):
        rolled = np.roll(current, -int(rng.integers(0, n)))
        # alternate a global double bridge and a local one (inside ``span`` consecutive views)
        a, b = np.sort(rng.choice(np.arange(2, n if kick % 2 == 0 else span), size=2, replace=False))
        kicked = np.concatenate([rolled[:1], rolled[a:b], rolled[1:a], rolled[b:]])
        cand = local_search(kicked, cost, neighbours)
        cand_len = tour_length(cand, cost)
        # threshold acceptance (Dueck & Scheuer 1990): wander over slightly worse tours, keep the best
        if cand_len < current_len * (1.0 + _ACCEPT_WORSE):
            current, current_len = cand, cand_len
        if cand_len < best_len - 1e-9:
            best, best_len = cand, cand_len
    return np.roll(best, -int(np.flatnonzero(best == 0)[0]))


def solve_ortools(cost: np.ndarray, time_limit_s: float = 0.0) -> np.ndarray:
    """Closed tour (permutation starting at 0) by OR-Tools routing from the cheapest-arc start:
    time_limit_s = 0: greedy descent (2-opt, Or-opt, relocate, exchange ...) to a local optimum
    (deterministic); > 0: guided local search for that long (how far it gets depends on the load)."""
    n = len(cost)
    if n <= 3:
        return np.arange(n)
    icost = np.rint(cost * _COST_SCALE).astype(np.int64).tolist()
    return _ortools_route(icost, "PATH_CHEAPEST_ARC", time_limit_s)[1]


@kernel
def nearest_neighbour_tours(cost: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(k, n): from each view of ``starts`` (k,) the nearest-neighbour tour (Rosenkrantz, Stearns & Lewis 1977):
    always on to the cheapest view not yet visited (ties: the lowest index). O(n^2) per tour, no Python per
    step."""
    n = cost.shape[0]
    tours = np.empty((starts.size, n), dtype=np.int64)
    for row in range(starts.size):
        visited = np.zeros(n, dtype=np.bool_)
        here = starts[row]
        tours[row, 0] = here
        visited[here] = True
        for k in range(1, n):
            best, nxt = np.inf, -1
            for other in range(n):
                if not visited[other] and cost[here, other] < best:
                    best, nxt = cost[here, other], other
            tours[row, k] = nxt
            visited[nxt] = True
            here = nxt
    return tours


def canonical_direction(order: np.ndarray) -> np.ndarray:
    """The closed tour ``order`` (n,) from view 0, run the way that leaves view 0 towards the lower-indexed of its
    two tour neighbours. A closed tour has no direction of its own; this convention fixes the multistart
    solver's, whichever way its last local search ran."""
    order = np.roll(np.asarray(order), -int(np.flatnonzero(np.asarray(order) == 0)[0]))
    if len(order) < 3 or order[1] < order[-1]:
        return order
    return np.roll(order[::-1], 1)


def solve_multistart(cost: np.ndarray, rng: np.random.Generator, random_starts: int = 16,
                     kicks: int = 60) -> np.ndarray:
    """Default tour solver, deterministic for a seeded ``rng``: nearest-neighbour tours from view 0 and from
    ``random_starts`` other views drawn at random (Johnson & McGeoch 1997: greedy starts make 2-opt / Or-opt
    both shorter and much faster than random starts), each taken to a 2-opt / Or-opt local optimum, then
    iterated local search from the best (ties: the earlier start). Returns the tour from view 0 in
    :func:`canonical_direction`."""
    n = len(cost)
    if n <= 3:
        return np.arange(n)
    neighbours = neighbour_lists(cost)
    others = rng.choice(np.arange(1, n), size=min(random_starts, n - 1), replace=False)
    tours = nearest_neighbour_tours(cost, np.concatenate([[0], others]).astype(np.int64))
    # the descents are compiled with the GIL released: one group per core, each descent deterministic, so the
    # optima (and their order) do not depend on the number of cores
    groups = np.array_split(tours, min(len(tours), os.cpu_count() or 1))
    with ThreadPoolExecutor(max_workers=len(groups)) as pool:
        optima = [tour for group in pool.map(lambda rows: _descend_rows(rows, cost, neighbours), groups)
                  for tour in group]
    best = min(optima, key=lambda o: tour_length(o, cost))
    return canonical_direction(iterated_local_search(best, cost, kicks, rng, neighbours))


def solve_genetic(cost: np.ndarray, rng: np.random.Generator, population: int = 120,
                  generations: int = 600, mutation_rate: float = 0.3, elite: int = 4) -> np.ndarray:
    """Closed tour by a genetic algorithm (the paper's solver, Sec. 3.3; its operators are not given:
    order crossover (Davis 1985), inversion mutation, tournament selection of size 3, elitism)."""
    n = len(cost)
    if n <= 3:
        return np.arange(n)
    pop = np.argsort(rng.random((population, n)), axis=1)
    for _ in range(generations):
        fitness = cost[pop, np.roll(pop, -1, axis=1)].sum(axis=1)
        rank = np.argsort(fitness)
        children = [pop[rank[:elite]]]
        n_children = population - elite
        contenders = rng.integers(0, population, size=(2, n_children, 3))
        parents = [contenders[k][np.arange(n_children), np.argmin(fitness[contenders[k]], axis=1)]
                   for k in range(2)]
        cuts = np.sort(rng.integers(0, n + 1, size=(n_children, 2)), axis=1)
        kids = np.empty((n_children, n), dtype=pop.dtype)
        for i in range(n_children):  # order crossover: one child per pair (the loop is over the population)
            p1, p2 = pop[parents[0][i]], pop[parents[1][i]]
            a, b = cuts[i]
            middle = p1[a:b]
            rest = p2[~np.isin(p2, middle)]
            kids[i] = np.concatenate([rest[:a], middle, rest[a:]])
        mutate = rng.random(n_children) < mutation_rate
        seg = np.sort(rng.integers(0, n, size=(n_children, 2)), axis=1)
        for j in np.flatnonzero(mutate):
            a, b = seg[j]
            kids[j, a:b + 1] = kids[j, a:b + 1][::-1]
        children.append(kids)
        pop = np.concatenate(children)
    fitness = cost[pop, np.roll(pop, -1, axis=1)].sum(axis=1)
    best = pop[int(np.argmin(fitness))]
    return np.roll(best, -int(np.flatnonzero(best == 0)[0]))


def open_at_longest_edge(order: np.ndarray, cost: np.ndarray) -> np.ndarray:
    """The closed tour as an open sequence, cut at its most expensive edge (the shortest flight)."""
    if len(order) < 2:
        return order
    edges = cost[order, np.roll(order, -1)]
    return np.roll(order, -(int(np.argmax(edges)) + 1))
