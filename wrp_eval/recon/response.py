"""How an oracle responds to small differences between capture sets of one path: the yardstick of issue 17.

Three figures, for an oracle (anything with ``evaluate(capture_set, mesh, seed) -> ReconResult``) and a capture
set (e.g. the quickstart path flown as planned):

* roughness: the std of ``error_m`` when every view is jittered by a small pose noise (2 cm per axis, 0.1 deg
  of yaw: the capture errors of an ideal flight), over ``draws`` independent jitters;
* single-view effect: the std of the change of ``error_m`` when ONE viewpoint is moved uniformly within
  +-2 m per axis and +-20 deg of yaw (the interval optimiser's query), over ``moves`` moves;
* retest: the Spearman correlation of the same moves' changes measured twice, each time with every view under
  an independent jitter (can the oracle rank single-view moves reproducibly?).

An oracle can resolve single-view effects when roughness / effect is small (issue 17 asks <= 0.3) and the
retest correlation high (>= 0.8). The oracle's own seed is held fixed (0): these figures are about poses.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import spearmanr

from wrp_eval.sim.captures import CaptureSet

JITTER_POSITION_M = 0.02
JITTER_YAW_RAD = float(np.radians(0.1))
MOVE_POSITION_M = 2.0
MOVE_YAW_RAD = float(np.radians(20.0))


@dataclass(frozen=True)
class OracleResponse:
    """roughness_m, single_view_effect_m (m); ratio = roughness / effect; retest_spearman; draws, moves: the
    counts used (finite results only); base_error_m: the unperturbed set's error."""

    roughness_m: float
    single_view_effect_m: float
    ratio: float
    retest_spearman: float
    draws: int
    moves: int
    base_error_m: float


def shifted(capture_set: CaptureSet, offsets: np.ndarray) -> CaptureSet:
    """``capture_set`` with its views moved by ``offsets`` (n, 4): (dx, dy, dz m, dyaw rad) each."""
    offsets = np.asarray(offsets, dtype=float)
    return replace(capture_set, positions=capture_set.positions + offsets[:, :3], yaw=capture_set.yaw + offsets[:, 3])


def jitter(n_views: int, rng: np.random.Generator, position_m: float = JITTER_POSITION_M,
           yaw_rad: float = JITTER_YAW_RAD) -> np.ndarray:
    """(n_views, 4) Gaussian pose noise: ``position_m`` per axis, ``yaw_rad`` of yaw."""
    return np.concatenate([rng.normal(0.0, position_m, (n_views, 3)), rng.normal(0.0, yaw_rad, (n_views, 1))], 1)


def box_single_view_moves(n_views: int, moves: int, rng: np.random.Generator) -> np.ndarray:
    """(moves, n_views, 4) offsets moving one uniformly chosen view each, within the move box, the rest at 0."""
    out = np.zeros((moves, n_views, 4))
    views = rng.integers(0, n_views, moves)
    half = np.array([MOVE_POSITION_M] * 3 + [MOVE_YAW_RAD])
    out[np.arange(moves), views] = rng.uniform(-half, half, (moves, 4))
    return out


def oracle_response(oracle, mesh, capture_set: CaptureSet, *, draws: int = 30, moves: int = 100, seed: int = 0,
                    jitter_position_m: float = JITTER_POSITION_M, jitter_yaw_rad: float = JITTER_YAW_RAD
                    ) -> OracleResponse:
    """The module's three figures for ``oracle`` on ``capture_set`` of the true ``mesh`` (seeded by ``seed``);
    draws + 3 x moves + 1 oracle calls."""
    n = len(capture_set)
    rng = np.random.default_rng(seed)

    def error(offsets: np.ndarray) -> float:
        return float(oracle.evaluate(shifted(capture_set, offsets), mesh, seed=0).error_m)

    def noise() -> np.ndarray:
        return jitter(n, rng, jitter_position_m, jitter_yaw_rad)

    base = error(np.zeros((n, 4)))
    jittered = np.array([error(noise()) for _ in range(draws)])
    offsets = box_single_view_moves(n, moves, rng)
    effect = np.array([error(o) for o in offsets]) - base
    first = np.array([error(o + noise()) for o in offsets]) - base
    second = np.array([error(o + noise()) for o in offsets]) - base
    ok_j = np.isfinite(jittered)
    ok = np.isfinite(effect) & np.isfinite(first) & np.isfinite(second)
    rough = float(np.std(jittered[ok_j], ddof=1)) if ok_j.sum() > 1 else float("nan")
    size = float(np.std(effect[ok], ddof=1)) if ok.sum() > 1 else float("nan")
    rho = float(spearmanr(first[ok], second[ok]).statistic) if ok.sum() > 2 else float("nan")
    return OracleResponse(rough, size, rough / size if size > 0 else float("nan"), rho, int(ok_j.sum()),
                          int(ok.sum()), base)
