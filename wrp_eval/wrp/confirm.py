"""The oracle's confirmation of the optimiser's moves (issue 18, item 3: "the oracle confirms it (batched)").

The surrogate proposes; the oracle, which the surrogate only approximates, decides. For every viewpoint i the
surrogate moved, ``samples`` neighbourhood draws of view i are taken from its measured offset distribution
(the Cholesky factor of the campaign's position-offset covariance; the ball of r_s without one), the SAME
draws around the moved and around the planned position (common random numbers). With every other viewpoint at
the WRP's offsets, the oracle scores the 2 x ``samples`` capture sets, and the kind's neighbourhood score
(:func:`wrp_eval.wrp.optimize.neighbourhood_score`: ISWRP the mean error or its CVaR, SWRP the spread) is
compared. The move stands when the oracle's gain (score without it minus with it) clears the oracle's own
noise: for ISWRP, ``CONFIRM_Z`` standard errors of the paired differences (without - with, draw by draw); for
SWRP, whose spread has no paired standard error, the optimiser's own margin (twice the surrogate's validated
single-view error). A capture set the oracle cannot reconstruct counts as a failure: the side with fewer
failures wins; with as many, the scores are taken over the reconstructed draws. Moves it does not confirm are
reverted, and the caller confirms the remaining ones again (``CONFIRM_ROUNDS``), since each was judged beside
moves that may since have been reverted. Every capture set of every moved view is built first and scored in
one pass (the oracle scores one set per call); the pass is timed apart from the surrogate's search.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.wrp.optimize import WrpParams, neighbourhood_score

CONFIRM_STREAM = 1_000_003    # spawn key of the confirmation's draws (apart from the optimiser's blocks)
CONFIRM_Z = 2.0               # ISWRP: the paired gain must exceed this many standard errors (one-sided ~98 %)
CONFIRM_ROUNDS = 3            # confirm, revert, confirm the rest again: at most this many rounds


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

    scored_ship: :class:`wrp_eval.recon.scored_ship.ScoredShip`; path: the planned path; blur_px (n,): the forecast
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
    errors = errors.reshape(len(views), 2, samples)                        # (moves, with / without, draws)
    gain, ok = oracle_verdicts(errors, params)
    n = len(moved)
    oracle_gain = np.full(n, np.nan)
    oracle_gain[views] = gain
    confirmed = np.zeros(n, bool)
    confirmed[views] = ok
    return Confirmation(confirmed, np.asarray(moved, bool) & ~confirmed, oracle_gain, len(sets),
                        time.perf_counter() - start)


def oracle_verdicts(errors: np.ndarray, params: WrpParams) -> tuple[np.ndarray, np.ndarray]:
    """errors (moves, 2, samples) m (index 0: with the move, 1: without; NaN: not reconstructed) -> (gain (moves,)
    m: the score without minus with; confirmed (moves,) bool) by the rule of the module docstring."""
    finite = np.isfinite(errors)
    failures = (~finite).sum(axis=2)                                       # (moves, 2)
    gain = np.full(len(errors), np.nan)
    confirmed = failures[:, 0] < failures[:, 1]                            # fewer failed reconstructions wins
    for m in np.flatnonzero(failures[:, 0] == failures[:, 1]):
        both = finite[m, 0] & finite[m, 1]
        if both.sum() < 2:
            continue
        score = neighbourhood_score(errors[m][:, both], params)            # (2,): with, without
        gain[m] = score[1] - score[0]
        if params.kind == "iswrp":
            diff = errors[m, 1, both] - errors[m, 0, both]
            noise = CONFIRM_Z * diff.std(ddof=1) / np.sqrt(diff.size)
        else:
            noise = params.improvement_margin_m()
        confirmed[m] = gain[m] > noise
    return gain, confirmed
