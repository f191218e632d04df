"""The oracle's confirmation of the optimiser's moves (issue 18, item 3: "the oracle confirms it (batched)").

The surrogate proposes; the oracle, which the surrogate only approximates, decides. For every viewpoint i the
surrogate moved, ``samples`` neighbourhood draws of view i are taken from its measured offset distribution
(the Cholesky factor of the campaign's position-offset covariance; the ball of r_s without one), the SAME
draws around the moved and around the planned position (common random numbers). With every other viewpoint at
the WRP's offsets, the oracle scores the 2 x ``samples`` capture sets, and the kind's neighbourhood score
(:func:`wrp_eval.wrp.optimize.neighbourhood_score`: ISWRP the mean error or its CVaR, SWRP the spread) is
compared: the move stands when the oracle's score with it is lower than without it. Moves it does not
confirm are reverted. Every capture set of every moved view is built first and scored in one pass (the oracle
scores one set per call); the pass is timed apart from the surrogate's search.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.wrp.optimize import WrpParams, neighbourhood_score

CONFIRM_STREAM = 1_000_003    # spawn key of the confirmation's draws (apart from the optimiser's blocks)


@dataclass(frozen=True)
class Confirmation:
    """confirmed (n,) bool: moved and confirmed; rejected (n,) bool: moved and reverted; oracle_gain_m (n,):
    the oracle's score without the move minus with it (NaN where not moved); oracle_calls; seconds."""

    confirmed: np.ndarray
    rejected: np.ndarray
    oracle_gain_m: np.ndarray
    oracle_calls: int
    seconds: float

    def to_json_dict(self) -> dict:
        return {"confirmed": int(self.confirmed.sum()), "rejected": int(self.rejected.sum()),
                "oracle_gain_mm": [None if not np.isfinite(g) else round(1000 * float(g), 4)
                                   for g in self.oracle_gain_m],
                "oracle_calls": self.oracle_calls, "seconds": self.seconds}


def neighbour_draws(params: WrpParams, view: int, samples: int, seed: int) -> np.ndarray:
    """(samples, 3) m position draws of viewpoint ``view``'s neighbourhood (seeded per view)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(view, CONFIRM_STREAM)))
    direction = rng.normal(size=(samples, 3))
    if params.neighbour_cholesky is not None:
        return direction @ np.asarray(params.neighbour_cholesky[view]).T
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    return direction * params.sample_radius_m[view] * rng.uniform(size=(samples, 1)) ** (1.0 / 3.0)


def confirm_moves(scored_ship, path, offsets: np.ndarray, moved: np.ndarray, params: WrpParams, seed: int,
                  samples: int = 8, blur_px: np.ndarray | None = None) -> Confirmation:
    """The oracle's verdict on each move of ``offsets`` (n, 4) where ``moved`` (n,) (module docstring).

    scored_ship: :class:`wrp_eval.recon.scene.ScoredShip`; path: the planned path; blur_px (n,): the forecast
    blur at each view (None: sharp); oracle seed 0.
    """
    start = time.perf_counter()
    offsets = np.asarray(offsets, dtype=float)
    views = np.flatnonzero(moved)
    sets = []
    for i in views:                       # the capture sets of every move: (moved, unmoved) x samples
        draws = neighbour_draws(params, int(i), samples, seed)
        for centre in (offsets[i], np.zeros(4)):
            for d in draws:
                o = offsets.copy()
                o[i] = centre + np.array([*d, 0.0])
                sets.append(o)
    errors = np.array([scored_ship.score(captures_from_path(path, o, blur_px=blur_px), seed=0).error_m
                       for o in sets])    # one oracle call per capture set: the oracle is not batched
    errors = np.where(np.isfinite(errors), errors, np.inf).reshape(len(views), 2, samples)
    with np.errstate(invalid="ignore"):
        score = neighbourhood_score(errors, params)         # (moves, 2): with, without
        gain = score[:, 1] - score[:, 0]
    n = len(moved)
    oracle_gain = np.full(n, np.nan)
    oracle_gain[views] = gain
    confirmed = np.zeros(n, bool)
    confirmed[views] = gain > 0          # +inf: the oracle fails without the move only; NaN: fails both
    return Confirmation(confirmed, np.asarray(moved, bool) & ~confirmed, oracle_gain, len(sets),
                        time.perf_counter() - start)
