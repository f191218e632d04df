"""What a campaign's oracle lets a surrogate learn, and what the optimiser can trust it for.

**R^2 ceiling** (:func:`oracle_roughness`). The synthetic oracle is deterministic for given poses and seed,
but not smooth: a pose change of a few centimetres flips discrete decisions (which ray matches in which
partner view, which views are partners, the order of registration), and the error moves by a fraction of a
millimetre even where its trend is flat (measured on the quickstart ship: 1 mm per-view jitter -> 0.2 mm std,
5 cm -> 0.7 mm, on a 23 mm error). No regression on the offsets can resolve that: two flights the UAV cannot
tell apart (its calm-air tracking is ~2-3 cm and ~0.1 deg, see wrp_eval/sim) get errors that differ by it.
The stored trials are re-scored with their flown poses jittered at that scale (independent Gaussian per
viewpoint), the mean within-trial variance is the part no surrogate can learn, and ``r2_ceiling`` = 1 - that /
the variance of the campaign's errors (trials that did not fail): the held-out R^2 a perfect surrogate of the
smooth trend would reach on this data.

**Single-viewpoint agreement** (:func:`single_view_agreement`). The optimiser (Alg. 3/4) moves ONE viewpoint
at a time and asks the surrogate how the path's error changes. A high R^2 on the campaign's trials does not
imply the surrogate knows that (trials move every viewpoint at once). This draws single-viewpoint moves at the
campaign's targeted scale around the planned path, scores each with the surrogate and with the oracle averaged
over a few sub-tracking-precision jitters (its smooth trend), and compares the changes against the unmoved
path: Spearman rank correlation, the sign agreement on the moves the surrogate rates largest, the RMSE (the
validated single-view error the optimiser's acceptance rule uses) and both spreads.

**Baseline** (:func:`mean_offset_baseline`): a polynomial (up to a quartic, as the data allow) in the trial's
four mean offsets, on the surrogate's own split. Issue 18 measured that the mean yaw alone explained 0.87 of
the variance of the earlier campaigns: the network's R^2 only counts for what it adds to this.

The roughness re-scores each trial with the gimbal pitch it achieved (the store's ``camera_pitch``; campaigns
stored before that column fall back to the planned pitch, which differs only where the gimbal saturated); the
single-viewpoint moves use the planned pitch (they are moves of the plan). Both are estimates from a finite
sample, returned with their settings.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations_with_replacement
from math import comb
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from wrp_eval.campaign.config import TrialConfig
from wrp_eval.campaign.records import column_array
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recon.scored_ship import ScoredShip, scored_ship
from wrp_eval.surrogate.metrics import regression_metrics


@dataclass(frozen=True)
class CampaignOracle:
    """A campaign's path and its scored ship (:class:`wrp_eval.recon.scored_ship.ScoredShip`): offsets in, error out."""

    path: FlightPath
    ship: ScoredShip
    planned: np.ndarray      # (n, 4) x, y, z m, yaw rad

    def error(self, offsets: np.ndarray, seed: int, pitch: np.ndarray | None = None,
              roll: np.ndarray | None = None, blur_px: np.ndarray | None = None,
              estimated_offsets: np.ndarray | None = None) -> float:
        """Oracle error_m (m) of the path flown at planned + ``offsets`` (n, 4), every view taken, the gimbal at
        ``pitch`` (n,) rad where finite (a trial's achieved pitch), else at the planned pitch, with the camera's
        residual ``roll`` (n,) rad (a trial's; None or NaN: level), its motion ``blur_px`` (n,) (None or NaN:
        sharp) and the navigation's ``estimated_offsets`` (n, 4) from the plan (the photos' recorded positions,
        the position priors; None or NaN: the true positions)."""
        return float(self.ship.score(self.captures(offsets, pitch, roll, blur_px, estimated_offsets), seed).error_m)

    def captures(self, offsets: np.ndarray, pitch: np.ndarray | None = None, roll: np.ndarray | None = None,
                 blur_px: np.ndarray | None = None, estimated_offsets: np.ndarray | None = None):
        """The :class:`CaptureSet` that :meth:`error` scores (same arguments)."""
        if roll is not None:
            roll = np.nan_to_num(np.asarray(roll, dtype=float), nan=0.0)
        if blur_px is not None:
            blur_px = np.nan_to_num(np.asarray(blur_px, dtype=float), nan=0.0)
        prior = None
        if estimated_offsets is not None and np.all(np.isfinite(estimated_offsets)):
            prior = self.planned[:, :3] + np.asarray(estimated_offsets, dtype=float)[:, :3]
        return captures_from_path(self.path, offsets, pitch, roll=roll, prior_positions=prior, blur_px=blur_px)


def campaign_oracle(campaign_dir: str | Path, config_dir: str | Path = ".") -> tuple[CampaignOracle, TrialStore]:
    """(:class:`CampaignOracle`, the campaign's TrialStore) from a campaign folder's campaign.json and path.json."""
    folder = Path(campaign_dir)
    store = TrialStore(folder)
    meta = store.read_meta()
    if meta is None or "config" not in meta:
        raise InputError(folder, "not a campaign folder (no campaign.json with its config)")
    trial = TrialConfig.from_stored(meta["config"])
    path = FlightPath.load(folder / "path.json")
    planned = np.concatenate([np.asarray(path.positions, float), np.asarray(path.yaw, float)[:, None]], axis=1)
    ship = scored_ship(trial.ship, trial.oracle, trial.campaign.oracle, config_dir)
    return CampaignOracle(path, ship, planned), store


def oracle_roughness(campaign_dir: str | Path, *, n_trials: int = 60, repeats: int = 5,
                     position_jitter_m: float = 0.02, yaw_jitter_rad: float = 0.002, seed: int = 0,
                     config_dir: str | Path = ".") -> dict:
    """Roughness of the oracle on a campaign's own trials and the R^2 ceiling it implies.

    Draws ``n_trials`` trials that did not fail (seeded), re-scores each ``repeats`` times with its flown poses
    jittered (``position_jitter_m`` per axis, ``yaw_jitter_rad``), with the trial's own oracle seed. Returns
    noise_var_m2 (mean within-trial variance), noise_std_m, total_var_m2 (variance of error_m over every trial
    that did not fail), r2_ceiling, and the settings.
    """
    if repeats < 2:
        raise InputError("oracle_roughness", f"repeats must be >= 2 to measure a variance, got {repeats}")
    scorer, store = campaign_oracle(campaign_dir, config_dir)
    table = store.read_table(["n_views", "flown_offsets", "camera_pitch", "camera_roll", "blur_px",
                              "estimated_offsets", "error_m", "failed", "oracle_seed"])
    flown = column_array(table, "flown_offsets")
    pitch = column_array(table, "camera_pitch")       # NaN (-> planned pitch) in campaigns stored before the column
    roll = column_array(table, "camera_roll")         # NaN (-> level) likewise
    blur = column_array(table, "blur_px")             # NaN (-> sharp) likewise
    estimated = column_array(table, "estimated_offsets")  # NaN (-> priors at the true positions) likewise
    error = table.column("error_m").to_numpy(zero_copy_only=False).astype(float)
    failed = table.column("failed").to_numpy(zero_copy_only=False).astype(bool)
    oracle_seed = table.column("oracle_seed").to_numpy().astype(np.int64)
    usable = np.flatnonzero(~failed & np.isfinite(error) & np.all(np.isfinite(flown), axis=(1, 2)))
    if usable.size < 3:
        raise InputError(campaign_dir, f"only {usable.size} trials without failure; need at least 3")
    rng = np.random.default_rng(seed)
    chosen = rng.choice(usable, size=min(n_trials, usable.size), replace=False)
    n = len(scorer.planned)
    scores = np.empty((chosen.size, repeats))
    for row, trial in enumerate(chosen):   # one oracle call per capture set: the oracle is not batched
        for rep in range(repeats):
            jitter = np.concatenate([rng.normal(0.0, position_jitter_m, (n, 3)),
                                     rng.normal(0.0, yaw_jitter_rad, (n, 1))], axis=1)
            scores[row, rep] = scorer.error(flown[trial] + jitter, oracle_seed[trial], pitch[trial], roll[trial],
                                            blur[trial], estimated[trial])
    finite = np.all(np.isfinite(scores), axis=1)
    if not finite.any():
        raise InputError(campaign_dir, "the oracle returned no finite error on the re-scored trials")
    noise_var = float(np.var(scores[finite], axis=1, ddof=1).mean())
    total_var = float(np.var(error[usable]))
    return {"noise_var_m2": noise_var, "noise_std_m": float(np.sqrt(noise_var)), "total_var_m2": total_var,
            "r2_ceiling": 1.0 - noise_var / total_var if total_var > 0 else float("nan"),
            "n_trials": int(finite.sum()), "repeats": int(repeats), "position_jitter_m": position_jitter_m,
            "yaw_jitter_rad": yaw_jitter_rad, "seed": seed}


def targeted_single_view_moves(campaign_dir: str | Path, n_views: int, n_moves: int, seed: int,
                      low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(views (n_moves,), moves (n_moves, 4)): single-viewpoint moves drawn as the campaign's targeted trials
    draw theirs (Gaussian, ``targeted_position_sigma_m`` per axis and ``targeted_yaw_sigma_deg``: the realistic
    scale of what the optimiser asks about), clipped to the surrogate's training range [low, high]."""
    meta = TrialStore(Path(campaign_dir)).read_meta() or {}
    pert = TrialConfig.from_stored(meta["config"]).campaign.perturbation if "config" in meta else None
    sigma_m = pert.targeted_position_sigma_m if pert is not None else 1.5
    sigma_yaw = np.radians(pert.targeted_yaw_sigma_deg if pert is not None else 8.0)
    rng = np.random.default_rng(seed)
    views = rng.integers(0, n_views, n_moves)
    moves = rng.normal(0.0, 1.0, (n_moves, 4)) * np.array([sigma_m, sigma_m, sigma_m, sigma_yaw])
    return views, np.clip(moves, low, high)


def single_view_agreement(surrogate, campaign_dir: str | Path, *, n_moves: int = 200, jitters: int = 4,
                          position_jitter_m: float = 0.02, yaw_jitter_rad: float = 0.002, seed: int = 0,
                          config_dir: str | Path = ".", oracle: dict | None = None) -> dict:
    """Surrogate vs a jitter-averaged oracle on single-viewpoint moves from the planned path (the optimiser's
    queries; issue 18 item 2).

    Moves: :func:`targeted_single_view_moves`; the other viewpoints at zero offset. The oracle's change of a move is
    averaged over ``jitters`` small pose jitters of every view (``position_jitter_m`` / ``yaw_jitter_rad``,
    below the UAV's tracking precision; the same jitter for the moved and the unmoved path, oracle seed 0): the
    smooth trend, not the oracle's roughness at one point. Both sides see the forecast's per-view blur (the
    surrogate's reference conditions). Returns spearman (rank correlation of the changes), sign_top_decile
    (the share of the 10 % of moves the surrogate rates largest |change| whose sign the oracle agrees with),
    rmse_m (the surrogate's validated single-view error: RMSE of its change against the oracle's),
    oracle_change_std_m, surrogate_change_std_m, oracle_noise_std_m (std over jitters of one move's change,
    mean over moves), the largest oracle changes with the surrogate's answer (view, oracle, surrogate; m),
    n_moves, jitters, seed, and ``oracle`` (views, offsets, changes): pass it back to compare another surrogate
    of the same path with the same oracle scores (its moves, jitters and blur are then reused).
    """
    if oracle is None:
        oracle = single_view_oracle(surrogate, campaign_dir, n_moves=n_moves, jitters=jitters,
                                    position_jitter_m=position_jitter_m, yaw_jitter_rad=yaw_jitter_rad, seed=seed,
                                    config_dir=config_dir)
    views, offsets, changes = oracle["views"], oracle["offsets"], oracle["changes"]
    n = offsets.shape[1]
    if surrogate.n_views != n:
        raise InputError(campaign_dir, f"the surrogate has {surrogate.n_views} viewpoints, the moves {n}")
    oracle_change = changes.mean(axis=1)
    surrogate_change = surrogate.predict(offsets) - surrogate.predict(np.zeros((1, n, 4)))[0]
    ok = np.isfinite(oracle_change)
    rho = float(spearmanr(oracle_change[ok], surrogate_change[ok]).statistic) if ok.sum() > 2 else float("nan")
    idx = np.flatnonzero(ok)
    top = idx[np.argsort(-np.abs(surrogate_change[idx]))[:max(1, idx.size // 10)]]
    largest = idx[np.argsort(-np.abs(oracle_change[idx]))[:5]]
    return {"spearman": rho,
            "sign_top_decile": float(np.mean(np.sign(surrogate_change[top]) == np.sign(oracle_change[top]))),
            "rmse_m": float(np.sqrt(np.mean((oracle_change[ok] - surrogate_change[ok]) ** 2))),
            "oracle_change_std_m": float(np.std(oracle_change[ok])),
            "surrogate_change_std_m": float(np.std(surrogate_change[ok])),
            "oracle_noise_std_m": float(np.nanmean(np.std(changes[ok], axis=1))) if changes.shape[1] > 1
            else float("nan"),
            "largest": [[int(views[k]), float(oracle_change[k]), float(surrogate_change[k])] for k in largest],
            "n_moves": int(ok.sum()), "jitters": int(changes.shape[1]), "seed": oracle["seed"], "oracle": oracle}


def single_view_oracle(surrogate, campaign_dir: str | Path, *, n_moves: int, jitters: int, position_jitter_m: float,
                       yaw_jitter_rad: float, seed: int, config_dir: str | Path = ".") -> dict:
    """The oracle side of :func:`single_view_agreement`: views (n_moves,), offsets (n_moves, n, 4) and the
    changes (n_moves, jitters) m, one per jitter; seed."""
    scorer, _ = campaign_oracle(campaign_dir, config_dir)
    n = len(scorer.planned)
    if surrogate.n_views != n:
        raise InputError(campaign_dir, f"the surrogate has {surrogate.n_views} viewpoints, the campaign's path {n}")
    if jitters < 1:
        raise InputError("single_view_agreement", f"jitters must be >= 1, got {jitters}")
    low = np.asarray(surrogate.meta.offset_low if surrogate.meta.offset_low is not None else [-2, -2, -2, -0.35])
    high = np.asarray(surrogate.meta.offset_high if surrogate.meta.offset_high is not None else [2, 2, 2, 0.35])
    views, moves = targeted_single_view_moves(campaign_dir, n, n_moves, seed, low, high)
    offsets = np.zeros((n_moves, n, 4))
    offsets[np.arange(n_moves), views] = moves
    blur = surrogate.views.condition_reference[:, 0] if surrogate.views is not None else None
    changes = jittered_changes(scorer, offsets, jitters, position_jitter_m, yaw_jitter_rad, seed, blur)
    return {"views": views, "offsets": offsets, "changes": changes, "seed": seed}


def jittered_changes(scorer: CampaignOracle, offsets: np.ndarray, jitters: int, position_jitter_m: float,
                     yaw_jitter_rad: float, seed: int, blur_px: np.ndarray | None = None) -> np.ndarray:
    """(moves, jitters) m: the oracle's change (seed 0) of each path at ``offsets`` (moves, n, 4) from the planned
    one, under each of ``jitters`` pose jitters of every view (``position_jitter_m`` per axis, ``yaw_jitter_rad``;
    drawn from ``seed``, the same for the moved and the planned path), photos blurred by ``blur_px`` (n,) or sharp."""
    n = len(scorer.planned)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(1,)))
    jit = np.concatenate([rng.normal(0.0, position_jitter_m, (jitters, n, 3)),
                          rng.normal(0.0, yaw_jitter_rad, (jitters, n, 1))], axis=2)
    base = np.array([scorer.error(j, 0, blur_px=blur_px) for j in jit])          # the oracle is not batched
    return np.array([[scorer.error(o + j, 0, blur_px=blur_px) for j in jit] for o in offsets]) - base


def mean_offset_baseline(data, split: dict, usable: np.ndarray | None = None, max_degree: int = 4,
                         ridge: float = 1e-6, trials_per_term: int = 10) -> dict:
    """The small model the surrogate must beat (issue 18 item 2: ``surrogate.r2_baseline``): a polynomial in the
    trial's four MEAN offsets (over its viewpoints), least squares with a tiny ridge, fitted on the split's
    train + val trials and scored on its test trials (``split``: a TrainResult's). Its degree is the highest
    <= ``max_degree`` with at least ``trials_per_term`` fitted trials per coefficient (a quartic has 70: on the
    quickstart's ~220 trials it would fit noise), so the baseline stays small. ``usable`` (n_trials,) bool: the
    trials the network's error fit and R^2 count (:func:`wrp_eval.surrogate.train.usable_rows`; default: finite
    error, not failed, every view taken). Returns r2, rmse (m), n, degree; NaN figures when fewer than 2 trials
    are left to fit or to test."""
    y = np.asarray(data.error, float)
    scored = (np.isfinite(y) & ~np.asarray(data.failed, bool) & data.complete() if usable is None
              else np.asarray(usable, bool) & np.isfinite(y))
    fit = np.asarray(list(split["train"]) + list(split["val"]), dtype=int)
    test = np.asarray(split["test"], dtype=int)
    fit, test = fit[scored[fit]], test[scored[test]]
    if fit.size < 2 or test.size < 2:
        return {"r2": float("nan"), "rmse": float("nan"), "mae": float("nan"), "n": int(test.size), "degree": 0}
    mean = np.asarray(data.offsets, float).mean(axis=1)
    centre, scale = mean[fit].mean(axis=0), mean[fit].std(axis=0)                  # the fit trials only
    z = (mean - centre) / np.where(scale > 0, scale, 1.0)
    degree = max([1] + [d for d in range(1, max_degree + 1) if comb(4 + d, d) * trials_per_term <= len(fit)])
    terms = [np.ones(len(z))] + [np.prod(z[:, list(c)], axis=1) for d in range(1, degree + 1)
                                 for c in combinations_with_replacement(range(4), d)]
    X = np.column_stack(terms)
    A = X[fit]
    coef = np.linalg.solve(A.T @ A + ridge * len(fit) * np.eye(A.shape[1]), A.T @ y[fit])
    return {**regression_metrics(y[test], X[test] @ coef), "degree": degree}
