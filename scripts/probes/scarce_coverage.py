"""Probe (issue 30 item 1, session 26): does the scarce coverage a single-view move takes away rank the oracle's
single-view changes? Offline: reads a stored campaign, changes nothing.

    .venv/bin/python scripts/probes/scarce_coverage.py CAMPAIGN_DIR OUT_DIR [--seeds 0 1] [--moves 200]

Per ground-truth sample s, W_s = the observation weight of the planned capture set by the synthetic oracle's own
model (``recon.fusion.observe_samples``, every view registered) and W'_s with one view moved; the proxy is
sum_s [min(W_s, c) - min(W'_s, c)] for each level c. Three ways of computing it are ranked against the oracle's
change of each move (``surrogate.diagnostics.jittered_changes``: averaged over 4 pose jitters, oracle seed 0, as the
surrogate bench's, but with sharp photos where the bench uses the forecast's per-view blur):
``exact`` (a whole-set pass per move), ``linear`` / ``quadratic`` (central differences of the c = 2 proxy in each
view's 4 offsets at the plan, steps 0.5 m / 0.05 rad) and ``per_view`` (W'_s ~ W_s - w_v(s) + w'_v(s) from one-view
passes; the per-sample top-K among views ignored). Moves: ``targeted_single_view_moves`` (the surrogate bench's),
clipped to +-2 m / +-0.35 rad. Writes OUT_DIR/scarce_coverage.json.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from wrp_eval.recon.fusion import observe_samples
from wrp_eval.surrogate.diagnostics import (
    CampaignOracle,
    campaign_oracle,
    jittered_changes,
    targeted_single_view_moves,
)

LEVELS = (0.5, 1.0, 2.0, 3.0, 5.0)
C = 2.0
STEPS = np.array([0.5, 0.5, 0.5, 0.05])
CLIP = np.array([2.0, 2.0, 2.0, 0.35])


class Coverage:
    """Observation weight per ground-truth sample of a capture set of ``scorer``'s path."""

    def __init__(self, scorer: CampaignOracle):
        self.scorer, self.n = scorer, len(scorer.planned)
        self.gt, self.section = scorer.ship.oracle.ground_truth(scorer.ship.mesh), scorer.ship.oracle.section

    def weights(self, offsets: np.ndarray, view: int | None = None) -> np.ndarray:
        """(samples,) the weight of the set at ``offsets`` (n, 4), or of ``view`` alone."""
        cs = self.scorer.captures(offsets)
        if view is not None:
            cs = cs.subset(np.arange(self.n) == view)
        obs = observe_samples(cs, self.gt, np.ones(len(cs), bool), self.section, 1.0 / self.section.gt_density_per_m2)
        return np.bincount(obs.sample, weights=obs.weight, minlength=len(self.gt.samples))

    def lost(self, w0: np.ndarray, w1: np.ndarray, c: float = C) -> float:
        return float(np.sum(np.minimum(w0, c) - np.minimum(w1, c)))


def derivatives(cov: Coverage, w0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(gradient, diagonal curvature) (n, 4) of the c = 2 proxy in each view's offsets at the plan."""
    grad, curv = np.zeros((cov.n, 4)), np.zeros((cov.n, 4))
    for v in range(cov.n):
        for k in range(4):
            off = np.zeros((cov.n, 4))
            off[v, k] = STEPS[k]
            up = cov.lost(w0, cov.weights(off))
            off[v, k] = -STEPS[k]
            down = cov.lost(w0, cov.weights(off))
            grad[v, k], curv[v, k] = (up - down) / (2 * STEPS[k]), (up + down) / STEPS[k] ** 2
    return grad, curv


def ranks(proxy: np.ndarray, oracle: np.ndarray, exact: np.ndarray) -> dict:
    """Spearman with the oracle, the sign agreement of the proxy's 20 largest, Spearman over the oracle's 20 largest
    and with the exact proxy."""
    top, big = np.argsort(-np.abs(proxy))[:20], np.argsort(-np.abs(oracle))[:20]
    return {"spearman": float(spearmanr(proxy, oracle).statistic),
            "sign_top_decile": float(np.mean(np.sign(proxy[top]) == np.sign(oracle[top]))),
            "spearman_20_largest": float(spearmanr(proxy[big], oracle[big]).statistic),
            "spearman_with_exact": float(spearmanr(proxy, exact).statistic)}


def probe_moves(cov: Coverage, campaign: str, seed: int, n_moves: int, w0, grad, curv) -> dict:
    """Every proxy and the oracle on ``n_moves`` moves of ``seed``."""
    views, moves = targeted_single_view_moves(campaign, cov.n, n_moves, seed, -CLIP, CLIP)
    offsets = np.zeros((n_moves, cov.n, 4))
    offsets[np.arange(n_moves), views] = moves
    exact = np.array([[cov.lost(w0, cov.weights(o), c) for c in LEVELS] for o in offsets])
    start = time.perf_counter()
    alone = {v: cov.weights(np.zeros((cov.n, 4)), v) for v in np.unique(views)}
    per_view = np.array([cov.lost(w0, w0 - alone[v] + cov.weights(o, v))
                         for v, o in zip(views, offsets, strict=True)])
    per_view_ms = (time.perf_counter() - start) / n_moves * 1e3
    oracle = jittered_changes(cov.scorer, offsets, 4, 0.02, 0.002, 0).mean(axis=1)   # sharp photos
    lin = np.sum(grad[views] * moves, axis=1)
    out = {f"exact_c{c}": ranks(exact[:, j], oracle, exact[:, 2]) for j, c in enumerate(LEVELS)}
    out |= {"linear": ranks(lin, oracle, exact[:, 2]),
            "quadratic": ranks(lin + 0.5 * np.sum(curv[views] * moves ** 2, axis=1), oracle, exact[:, 2]),
            "per_view": ranks(per_view, oracle, exact[:, 2]) | {"ms_per_query": per_view_ms},
            "oracle_change_std_mm": float(oracle.std() * 1e3),
            "oracle_below_0.01_mm": int(np.sum(np.abs(oracle) < 1e-5)),
            "exact_c2_zero": int(np.sum(exact[:, 2] == 0.0))}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("campaign")
    parser.add_argument("out")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--moves", type=int, default=200)
    args = parser.parse_args()
    scorer, _ = campaign_oracle(args.campaign, ".")
    cov = Coverage(scorer)
    w0 = cov.weights(np.zeros((cov.n, 4)))
    grad, curv = derivatives(cov, w0)
    result = {"levels": LEVELS, "steps": STEPS.tolist(),
              **{f"seed{s}": probe_moves(cov, args.campaign, s, args.moves, w0, grad, curv) for s in args.seeds}}
    Path(args.out).mkdir(parents=True, exist_ok=True)
    (Path(args.out) / "scarce_coverage.json").write_text(json.dumps(result, indent=1))
    for s in args.seeds:
        r = result[f"seed{s}"]
        for name in ("exact_c2.0", "linear", "quadratic", "per_view"):
            print(f"seed {s} {name}: " + ", ".join(f"{k} {v:+.3f}" for k, v in r[name].items()))


if __name__ == "__main__":
    main()
