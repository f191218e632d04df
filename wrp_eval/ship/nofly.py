"""The no-fly box around the ship and the one safety predicate of every stage that moves the aircraft.

The box is the proxy inflated by the no-fly margin r, down to the sea: ``Proxy.no_fly_bounds()``, a (2, 3)
array of its lower and upper corners (paper Sec. 3.1). The planner (views, tour, detours), the WRP
optimiser and the mission export all ask the functions below, so a position or a leg the planner accepts is
one the export accepts.

**Edge rule: the box is open.** A position on its boundary, or a straight leg that only touches it (runs
along a face, grazes an edge or a corner, ends on a face), is not an intrusion; only what lies deeper inside
than ``EDGE_TOLERANCE_M`` in every axis is. Why open: the box already holds the margin r, so its boundary is
r from the proxy, as close as the planner means to fly; and it is the rule the tour's cost matrix used
(legs touching the box cost the straight flight), so the tour, the planned paths, the quickstart path and
the campaign numbers stay what they were. Before, the proxy, the views and the export used a closed box, so
a leg the planner accepted (one level with the box's top face, say) was refused by the export. Measured on
the plans of the five ship types x three methods (quickstart config, seed 0): every view and every pair of
views is classified the same by the open rule, the old tour rule and the closed rule, and every plan is
unchanged; the rule only decides boundary cases (tests/ship/test_nofly.py).

``EDGE_TOLERANCE_M`` (one place for every tolerance here) absorbs the rounding of positions computed as "on
the boundary" (an edge plus an offset minus the offset): the box is shrunk by it before the strict tests,
so such a point, or a leg that runs along a face or through an edge line, stays outside whatever the last
bit. The minimum altitude gets the same tolerance (a view lifted to exactly the minimum is above it).
"""

from __future__ import annotations

import numpy as np

from wrp_eval.compiled import as_rows, kernel

EDGE_TOLERANCE_M = 1e-9   # m: closer to the box's boundary (or to the minimum altitude) than this counts as on it


def _shrunk(box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The open box's inner corners (lo, hi), each (3,): the box (2, 3) shrunk by the edge tolerance."""
    box = np.asarray(box, dtype=float)
    return box[0] + EDGE_TOLERANCE_M, box[1] - EDGE_TOLERANCE_M


def inside_no_fly_box(points: np.ndarray, box: np.ndarray) -> np.ndarray:
    """(...,) bool: points (..., 3) m strictly inside the open no-fly box (2, 3) (see the edge rule)."""
    lo, hi = _shrunk(box)
    p = np.asarray(points, dtype=float)
    return np.all((p > lo) & (p < hi), axis=-1)


def segments_intrude(starts: np.ndarray, ends: np.ndarray, box: np.ndarray) -> np.ndarray:
    """(...,) bool: straight segments starts -> ends (..., 3) m that pass through the open no-fly box (2, 3).

    Slab test (Kay & Kajiya 1986, "Ray tracing complex scenes", SIGGRAPH): along p(t) = a + t (b - a), each
    axis keeps the segment inside its open slab for t in an open interval; the segment intrudes when the
    intersection of the three intervals with [0, 1] is not empty. An axis the segment does not move along is
    inside for every t or for none. A segment of zero length intrudes when its point is inside."""
    lo, hi = _shrunk(box)
    a = np.asarray(starts, dtype=float)
    enter, leave = _slabs(a, np.asarray(ends, dtype=float) - a, lo, hi, (a > lo) & (a < hi))
    return np.maximum(enter, 0.0) < np.minimum(leave, 1.0)


def _slabs(a: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray, inside_slab: np.ndarray):
    """(enter, leave) (...,): the parameters t at which a + t d (..., 3) enters and leaves the box lo..hi (3,),
    the intersection of its three slabs; ``inside_slab`` (..., 3): whether a is within each slab (what decides
    an axis the line does not move along: inside for every t, or for none)."""
    flat = d == 0
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (lo - a) / d, (hi - a) / d
    enter = np.where(flat, np.where(inside_slab, -np.inf, np.inf), np.minimum(t1, t2)).max(axis=-1)
    leave = np.where(flat, np.where(inside_slab, np.inf, -np.inf), np.maximum(t1, t2)).min(axis=-1)
    return enter, leave


def above_min_altitude(points: np.ndarray, min_altitude_m: float) -> np.ndarray:
    """(...,) bool: points (..., 3) m at or above ``min_altitude_m`` above the sea (within the tolerance)."""
    return np.asarray(points, dtype=float)[..., 2] >= min_altitude_m - EDGE_TOLERANCE_M


def flyable(points: np.ndarray, box: np.ndarray | None, min_altitude_m: float) -> np.ndarray:
    """The one safety predicate of a position: (...,) bool, points (..., 3) m at or above the minimum altitude
    and outside the open no-fly box (2, 3) (None: no box)."""
    ok = above_min_altitude(points, min_altitude_m)
    if box is not None:
        ok &= ~inside_no_fly_box(points, box)
    return ok


def leg_flyable(starts: np.ndarray, ends: np.ndarray, box: np.ndarray | None, min_altitude_m: float) -> np.ndarray:
    """The one safety predicate of a straight leg: (...,) bool, legs starts -> ends (..., 3) m with both ends
    at or above the minimum altitude (the leg between them then is too) that do not pass through the open
    no-fly box (2, 3) (None: no box)."""
    ok = above_min_altitude(starts, min_altitude_m) & above_min_altitude(ends, min_altitude_m)
    if box is not None:
        ok &= ~segments_intrude(starts, ends, box)
    return ok


@kernel
def _box_distance_rows(points, box):
    """(n,) m from points (n, 3) to the closed box (2, 3) (0 inside), one row at a time."""
    out = np.empty(points.shape[0])
    for row in range(points.shape[0]):
        total = 0.0
        for d in range(3):
            outside = np.maximum(box[0, d] - points[row, d], 0.0) + np.maximum(points[row, d] - box[1, d], 0.0)
            total += outside ** 2
        out[row] = np.sqrt(total)
    return out


def distance_to_box(points: np.ndarray, box: np.ndarray) -> np.ndarray:
    """(...,) m: Euclidean distance from points (..., 3) to the closed box (2, 3) (0 inside)."""
    p = np.asarray(points, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"points must have shape (..., 3), got {p.shape}")
    rows = _box_distance_rows(np.ascontiguousarray(p.reshape(-1, 3)), as_rows("box", box, (2, 3)))
    return rows.reshape(p.shape[:-1])[()]


def ray_box_distance(origins: np.ndarray, directions: np.ndarray, box: np.ndarray) -> np.ndarray:
    """(...,) m: distance along unit rays origins + t directions (..., 3) to where they enter the box (2, 3);
    NaN where a ray misses it or starts inside (the slab test of :func:`segments_intrude`, on a ray)."""
    a = np.asarray(origins, dtype=float)
    box = np.asarray(box, dtype=float)
    enter, leave = _slabs(a, np.asarray(directions, dtype=float), box[0], box[1], (a >= box[0]) & (a <= box[1]))
    hit = (enter > 0.0) & (enter <= leave)
    return np.where(hit, enter, np.nan)
