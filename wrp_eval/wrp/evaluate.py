"""Robustness evaluation: the initial path, the ISWRP and the SWRP flown under the SAME wind realisations.

Each path is flown as a campaign (the campaign stage's ``run_campaign``) with the same config and root seed, so
trial k of every path draws the same wind (the campaign's common random numbers) and the paths can be compared
pair by pair. The viewpoints are flown as planned (``perturbation.design: none``; the campaign's extra flown
disturbance is kept as configured): what differs between the paths is only where they put the viewpoints.

Per path (the paper's Tables 4/5 analogues): mean, standard deviation and 95th percentile of the oracle's error
over the trials that did not fail, and the failure rate, each with a bootstrap confidence interval
(``scipy.stats.bootstrap``, percentile method); per WRP the paired differences against the initial path (mean
error difference over the trials where both succeeded, failure-rate difference over all trials), with paired
bootstrap intervals; a box plot of the errors.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from scipy import stats

from wrp_eval.atomic import atomic_path
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError


@dataclass(frozen=True)
class PathTrials:
    """One path's campaign: trial_id (n,), error_m (n,) (NaN where none), failed (n,) bool."""

    name: str
    trial_id: np.ndarray
    error_m: np.ndarray
    failed: np.ndarray


def read_trials(name: str, folder: str | Path) -> PathTrials:
    """The error and failure of every stored trial of a campaign folder, in trial-id order."""
    table = TrialStore(folder).read_table(["trial_id", "error_m", "failed"])
    order = np.argsort(table.column("trial_id").to_numpy())
    return PathTrials(name, table.column("trial_id").to_numpy()[order],
                      table.column("error_m").to_numpy(zero_copy_only=False).astype(float)[order],
                      table.column("failed").to_numpy(zero_copy_only=False).astype(bool)[order])


def _ci(samples, statistic, rng, resamples: int, confidence: float, paired: bool = False) -> list | None:
    """Percentile bootstrap interval of ``statistic`` (None when there are too few samples)."""
    if len(samples[0]) < 2:
        return None
    res = stats.bootstrap(samples, statistic, paired=paired, vectorized=True, n_resamples=resamples,
                          confidence_level=confidence, method="percentile", random_state=rng)
    low, high = res.confidence_interval
    return [float(low), float(high)]


def path_summary(p: PathTrials, rng: np.random.Generator, resamples: int, confidence: float) -> dict:
    """mean / std / p95 of the error over trials that did not fail, failure rate; each with its CI."""
    ok = p.error_m[~p.failed & np.isfinite(p.error_m)]
    fail = p.failed.astype(float)
    out = {"path": p.name, "trials": int(p.trial_id.size), "succeeded": int(ok.size),
           "failure_rate": float(fail.mean()) if fail.size else float("nan"),
           "failure_rate_ci": _ci((fail,), lambda x, axis: x.mean(axis=axis), rng, resamples, confidence)}
    for key, fn in (("mean_error_m", lambda x, axis: x.mean(axis=axis)),
                    ("std_error_m", lambda x, axis: x.std(axis=axis, ddof=1)),
                    ("p95_error_m", lambda x, axis: np.percentile(x, 95, axis=axis))):
        out[key] = float(fn(ok, None)) if ok.size > 1 else float("nan")
        out[key + "_ci"] = _ci((ok,), fn, rng, resamples, confidence) if ok.size > 2 else None
    return out


def paired_difference(base: PathTrials, other: PathTrials, rng: np.random.Generator, resamples: int,
                      confidence: float) -> dict:
    """other - base on the same trial ids: mean error (trials where both succeeded) and failure rate."""
    common, ib, io = np.intersect1d(base.trial_id, other.trial_id, return_indices=True)
    if common.size == 0:
        raise InputError(other.name, "no trial ids in common with the initial path's campaign")
    both = (~base.failed[ib] & ~other.failed[io] & np.isfinite(base.error_m[ib]) & np.isfinite(other.error_m[io]))
    d_err = other.error_m[io][both] - base.error_m[ib][both]
    d_fail = other.failed[io].astype(float) - base.failed[ib].astype(float)
    mean = lambda x, axis: x.mean(axis=axis)  # noqa: E731
    return {"path": other.name, "versus": base.name, "paired_trials": int(common.size),
            "both_succeeded": int(both.sum()),
            "mean_error_diff_m": float(d_err.mean()) if d_err.size else float("nan"),
            "mean_error_diff_ci": _ci((d_err,), mean, rng, resamples, confidence) if d_err.size > 2 else None,
            "wins": int((d_err < 0).sum()), "losses": int((d_err > 0).sum()),
            "failure_rate_diff": float(d_fail.mean()),
            "failure_rate_diff_ci": _ci((d_fail,), mean, rng, resamples, confidence)}


def box_plot(paths: list[PathTrials], file: Path) -> None:
    """Errors of the trials that did not fail, one box per path (PNG, written atomically)."""
    fig = Figure(figsize=(5.5, 4), dpi=120)
    ax = fig.subplots()
    data = [p.error_m[~p.failed & np.isfinite(p.error_m)] for p in paths]
    ax.boxplot(data, showmeans=True)
    ax.set_xticks(range(1, len(paths) + 1),
                  [f"{p.name}\n({int(p.failed.sum())}/{p.failed.size} failed)" for p in paths])
    ax.set_ylabel("reconstruction error (m)")
    ax.set_title("same wind realisations (common random numbers)", fontsize=9)
    fig.tight_layout()
    with atomic_path(file) as tmp:
        fig.savefig(tmp, format="png")


def summarise(paths: list[PathTrials], seed: int, resamples: int, confidence: float) -> dict:
    """Tables 4/5 analogues: per-path summaries and paired differences against the first path."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(7,)))
    return {"confidence": confidence, "bootstrap_resamples": resamples,
            "paths": [path_summary(p, rng, resamples, confidence) for p in paths],
            "paired": [paired_difference(paths[0], p, rng, resamples, confidence) for p in paths[1:]]}
