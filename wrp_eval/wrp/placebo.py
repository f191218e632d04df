"""Placebo paths: the control a WRP's robustness gain must beat (issue 18; ../shared/DESIGN.md, "Telling signal
from noise").

A WRP moves some viewpoints by some amounts. A placebo moves the SAME NUMBER of viewpoints, chosen at random,
by the SAME move magnitudes: the WRP's moved viewpoints' position-offset lengths |dp| and yaw offsets, shuffled
over the chosen viewpoints, each position offset in a uniformly random direction (the yaw offsets keep their
values, hence their sign distribution), within the same flight-safety constraints (minimum altitude, no-fly
box). Flown under the same winds as the WRP, the placebos' gains are what moving viewpoints at random gives; a
WRP counts only when its gain lies beyond them.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

MOVE_TOLERANCE_M = 1e-6      # a viewpoint counts as moved when its position offset ...
MOVE_TOLERANCE_RAD = 1e-6    # ... or its yaw offset exceeds this
DIRECTION_TRIES = 64         # random directions tried per placebo move before it keeps only its yaw move


def moved_views(offsets: np.ndarray) -> np.ndarray:
    """Indices of the viewpoints a WRP moved: offsets (n, 4) dx, dy, dz m, dyaw rad."""
    offsets = np.asarray(offsets, dtype=float)
    return np.flatnonzero((np.linalg.norm(offsets[:, :3], axis=1) > MOVE_TOLERANCE_M)
                          | (np.abs(offsets[:, 3]) > MOVE_TOLERANCE_RAD))


def _unit_vectors(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    v = rng.standard_normal(shape + (3,))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def placebo_offsets(offsets: np.ndarray, count: int, rng: np.random.Generator,
                    base_positions: np.ndarray | None = None,
                    flyable: Callable[[np.ndarray], np.ndarray] | None = None) -> tuple[np.ndarray, int]:
    """``count`` placebo offset sets (count, n, 4) for a WRP's ``offsets`` (n, 4) (module docstring), and the
    number of placebo moves that found no flyable direction in ``DIRECTION_TRIES`` tries (those keep their yaw
    offset and no position offset). ``flyable(points (..., 3)) -> (...,) bool`` with ``base_positions``
    (n, 3) m: the safety predicate of a moved viewpoint (None: unconstrained)."""
    offsets = np.asarray(offsets, dtype=float)
    n = len(offsets)
    moved = moved_views(offsets)
    k = len(moved)
    out = np.zeros((count, n, 4))
    if k == 0 or count == 0:
        return out, 0
    lengths = np.linalg.norm(offsets[moved, :3], axis=1)
    yaws = offsets[moved, 3]
    views = np.stack([rng.choice(n, k, replace=False) for _ in range(count)])     # (count, k)
    order = np.stack([rng.permutation(k) for _ in range(count)])                   # which move goes where
    dirs = _unit_vectors(rng, (count, k, DIRECTION_TRIES))
    moves = lengths[order][:, :, None, None] * dirs                                 # (count, k, tries, 3)
    if flyable is None or base_positions is None:
        ok = np.ones(moves.shape[:3], bool)
    else:
        ok = flyable(np.asarray(base_positions, dtype=float)[views][:, :, None, :] + moves)
    first = np.argmax(ok, axis=2)                                                   # first flyable try
    found = np.take_along_axis(ok, first[..., None], axis=2)[..., 0]
    chosen = np.take_along_axis(moves, first[..., None, None], axis=2)[:, :, 0]
    rows = np.repeat(np.arange(count), k)
    out[rows, views.ravel(), :3] = np.where(found[..., None], chosen, 0.0).reshape(-1, 3)
    out[rows, views.ravel(), 3] = yaws[order].ravel()
    return out, int((~found).sum())
