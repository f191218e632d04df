"""Robustness evaluation: the initial path, the ISWRP and the SWRP flown under the SAME wind realisations.

Each path is flown as a campaign (the campaign stage's ``run_campaign``) with the same config and root seed, so
trial k of every path draws the same wind (the campaign's common random numbers) and the paths can be compared
pair by pair. The viewpoints are flown as planned (``perturbation.design: none``; the campaign's extra flown
disturbance is kept as configured): what differs between the paths is where they put the viewpoints (and, for the
reversed tour of ``direction: true``, the order it flies them in; its placebos fly the initial path with their
flights' own errors drawn again, wrp/direction.py).

Per path (the paper's Tables 4/5 analogues): mean, standard deviation and 95th percentile of the oracle's error
over the trials that did not fail, and the failure rate, each with a bootstrap confidence interval
(``scipy.stats.bootstrap``, percentile method); per WRP the paired differences against the initial path (mean
error difference over the trials where both succeeded, failure-rate difference over all trials), with paired
bootstrap intervals; a box plot of the errors.

Issue 18 adds what tells a WRP's gain from chance (``robustness`` of :func:`summarise`):
* the **robustness gain** of a WRP: per paired trial k, [e_k - E_windfree](initial) - [e_k - E_windfree](WRP)
  (E_windfree: the oracle's error of the path flown as planned), its mean and paired bootstrap CI (positive:
  the WRP loses less to the wind than the initial path);
* the **placebo gains**: the same for placebo paths (:mod:`wrp_eval.wrp.placebo`: as many viewpoints moved as
  the WRP moved, by the same magnitudes, chosen at random) flown under the same winds, and their 95th
  percentile;
* the **verdict**: a WRP is recommended only when its gain's CI excludes 0 (lower bound > 0) AND its mean gain
  exceeds the placebos' 95th percentile; otherwise the initial path is kept and the reason is stated;
* per path the probability of meeting a reconstruction spec (error <= ``spec_error_m`` and completeness >=
  ``spec_completeness``; a failed trial does not meet it), the mean number of views not taken (by any sortie),
  P(completed) and P(one sortie), the expected sorties and the mean mission time (swaps included) of the
  missions flown to their end (battery swaps and resumes, sim/mission.py; stores from before the swaps have no
  sortie column: there, n_views / the mean views a flight took), with CIs.
"""

from __future__ import annotations

import zlib
from collections.abc import Collection
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from scipy import stats

from wrp_eval.atomic import atomic_path
from wrp_eval.campaign.records import column_array
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError
from wrp_eval.wrp.evaluation import (
    EvaluationResult,
    ForecastVerdict,
    PairedDifference,
    PathSummary,
    RobustnessVerdict,
)


@dataclass(frozen=True)
class PathTrials:
    """One path's campaign: trial_id (n,), error_m (n,) (NaN where none), failed (n,) bool; completeness (n,)
    (NaN where none) and views_not_taken (n,) where the store has them (None for hand-made trials); sorties (n,),
    mission_time_s (n,) s and completed (n,) bool (the mission flown to its end) where the store has them (None
    for stores from before the battery swaps; NaN / False for a trial that raised)."""

    name: str
    trial_id: np.ndarray
    error_m: np.ndarray
    failed: np.ndarray
    completeness: np.ndarray | None = None
    views_not_taken: np.ndarray | None = None
    n_views: int | None = None
    sorties: np.ndarray | None = None
    mission_time_s: np.ndarray | None = None
    completed: np.ndarray | None = None


def read_trials(name: str, folder: str | Path) -> PathTrials:
    """The error, completeness, failure and views not taken of every stored trial of a campaign folder, in
    trial-id order."""
    table = TrialStore(folder).read_table(["trial_id", "n_views", "error_m", "completeness", "failed",
                                           "flown_offsets", "sorties", "mission_time_s", "ending"])
    order = np.argsort(table.column("trial_id").to_numpy())
    flown = column_array(table, "flown_offsets")
    not_taken = (~np.all(np.isfinite(flown), axis=2)).sum(axis=1).astype(float)

    def col(name):
        return table.column(name).to_numpy(zero_copy_only=False).astype(float)[order]

    def mission_col(name):      # None for a store from before the column (every value null)
        return col(name) if table.column(name).null_count < len(table) else None
    ending = table.column("ending")
    completed = None if ending.null_count == len(table) else \
        np.array([e == "completed" for e in ending.to_pylist()])[order]
    return PathTrials(name, table.column("trial_id").to_numpy()[order], col("error_m"),
                      table.column("failed").to_numpy(zero_copy_only=False).astype(bool)[order],
                      col("completeness"), not_taken[order], int(flown.shape[1]), mission_col("sorties"),
                      mission_col("mission_time_s"), completed)


def _ci(samples, statistic, rng, resamples: int, confidence: float, paired: bool = False) -> list | None:
    """Percentile bootstrap interval of ``statistic`` (None when there are too few samples)."""
    if len(samples[0]) < 2:
        return None
    res = stats.bootstrap(samples, statistic, paired=paired, vectorized=True, n_resamples=resamples,
                          confidence_level=confidence, method="percentile", random_state=rng)
    low, high = res.confidence_interval
    return [float(low), float(high)]


def meets_spec(p: PathTrials, spec_error_m: float, spec_completeness: float) -> np.ndarray:
    """(n,) bool: the trial's reconstruction meets the spec (error and completeness; failed trials do not)."""
    comp = p.completeness if p.completeness is not None else np.full(p.error_m.shape, np.inf)
    with np.errstate(invalid="ignore"):
        return ~p.failed & (p.error_m <= spec_error_m) & (comp >= spec_completeness)


def proportion_ci(successes: int, trials: int, confidence: float) -> list | None:
    """The exact (Clopper-Pearson) CI of a proportion: a bootstrap of 0/1 outcomes collapses to [1, 1] when
    every trial succeeds, which would let 5 of 5 flights say 'surely above 0.8'."""
    if trials < 1:
        return None
    ci = stats.binomtest(successes, trials).proportion_ci(confidence_level=confidence, method="exact")
    return [float(ci.low), float(ci.high)]


def path_summary(p: PathTrials, rng: np.random.Generator, resamples: int, confidence: float,
                 spec: tuple[float, float] | None = None) -> PathSummary:
    """mean / std / p95 of the error over trials that did not fail, failure rate; with ``spec`` (error m,
    completeness) the probability of meeting it; the mean views not taken; each with its CI."""
    ok = p.error_m[~p.failed & np.isfinite(p.error_m)]
    fail = p.failed.astype(float)
    out: dict[str, Any] = {
        "path": p.name, "trials": int(p.trial_id.size), "succeeded": int(ok.size),
        "failure_rate": float(fail.mean()) if fail.size else float("nan"),
        "failure_rate_ci": _ci((fail,), lambda x, axis: x.mean(axis=axis), rng, resamples, confidence)}
    for key, fn in (("mean_error_m", lambda x, axis: x.mean(axis=axis)),
                    ("std_error_m", lambda x, axis: x.std(axis=axis, ddof=1)),
                    ("p95_error_m", lambda x, axis: np.percentile(x, 95, axis=axis))):
        out[key] = float(fn(ok, None)) if ok.size > 1 else float("nan")
        out[key + "_ci"] = _ci((ok,), fn, rng, resamples, confidence) if ok.size > 2 else None
    mean = lambda x, axis: x.mean(axis=axis)  # noqa: E731
    if spec is not None:
        met = meets_spec(p, *spec)
        out.update({"spec_error_m": spec[0], "spec_completeness": spec[1],
                    "p_meets_spec": float(met.mean()) if met.size else float("nan"),
                    "p_meets_spec_ci": proportion_ci(int(met.sum()), int(met.size), confidence)})
    if p.views_not_taken is not None:
        out["mean_views_not_taken"] = float(p.views_not_taken.mean()) if p.views_not_taken.size else float("nan")
        out["mean_views_not_taken_ci"] = _ci((p.views_not_taken,), mean, rng, resamples, confidence)
        if p.n_views and p.sorties is None:
            # a store from before the battery swaps: every sortie took on average n - (views not taken) views,
            # the whole mission needs n / that
            taken = p.n_views - p.views_not_taken
            out["expected_sorties"] = float(p.n_views / taken.mean()) if taken.size and taken.mean() > 0 \
                else float("inf")
            out["expected_sorties_ci"] = _ci((taken,), lambda x, axis: p.n_views / x.mean(axis=axis), rng,
                                             resamples, confidence) if taken.size > 2 and taken.min() > 0 else None
    if p.sorties is not None and p.completed is not None:
        out.update(mission_summary(p, rng, resamples, confidence))
    return PathSummary(**out)


def mission_summary(p: PathTrials, rng: np.random.Generator, resamples: int, confidence: float) -> dict:
    """P(completed) (the mission flown to its end, whatever the sorties), P(one sortie) (completed on one battery)
    with exact CIs; expected sorties and mean mission time (battery swaps included) over the COMPLETED missions,
    with bootstrap CIs: a mission lost or sent home early ends on one short sortie, which says nothing of what
    the mission needs (NaN when none completed)."""
    done, sorties, mission_time_s = p.completed, p.sorties, p.mission_time_s
    if done is None or sorties is None or mission_time_s is None:
        raise ValueError(f"path {p.name!r}: no sorties / mission time / completed columns to summarise")
    out = {"p_completed": float(done.mean()) if done.size else float("nan"),
           "p_completed_ci": proportion_ci(int(done.sum()), int(done.size), confidence)}
    one = done & (sorties == 1)
    out.update(p_one_sortie=float(one.mean()) if one.size else float("nan"),
               p_one_sortie_ci=proportion_ci(int(one.sum()), int(one.size), confidence))
    for key, values in (("expected_sorties", sorties), ("mean_mission_time_s", mission_time_s)):
        v = values[done & np.isfinite(values)]
        out[key] = float(v.mean()) if v.size else float("nan")
        constant = v.size > 2 and np.ptp(v) == 0       # the bootstrap of a constant is that constant
        out[key + "_ci"] = [float(v[0])] * 2 if constant else (_ci((v,), lambda x, axis: x.mean(axis=axis), rng,
                                                                   resamples, confidence) if v.size > 2 else None)
    return out


def robustness_gains(base: PathTrials, other: PathTrials, windfree_base_m: float,
                     windfree_other_m: float) -> np.ndarray:
    """Per paired trial where both succeeded: [e - E_windfree](base) - [e - E_windfree](other) (m): how much
    less ``other`` loses to the same wind than ``base``."""
    common, ib, io = np.intersect1d(base.trial_id, other.trial_id, return_indices=True)
    both = (~base.failed[ib] & ~other.failed[io] & np.isfinite(base.error_m[ib]) & np.isfinite(other.error_m[io]))
    return (base.error_m[ib][both] - windfree_base_m) - (other.error_m[io][both] - windfree_other_m)


def robustness_verdict(gains: np.ndarray, placebo_means: np.ndarray, rng: np.random.Generator, resamples: int,
                       confidence: float) -> RobustnessVerdict:
    """A WRP's gain against its placebos: mean gain and CI, the placebos' mean gains and 95th percentile, and
    whether the WRP is recommended (CI lower bound > 0 and mean > the placebo 95th percentile), with why."""
    mean = lambda x, axis: x.mean(axis=axis)  # noqa: E731
    gain = float(gains.mean()) if gains.size else float("nan")
    ci = _ci((gains,), mean, rng, resamples, confidence) if gains.size > 2 else None
    flown = len(placebo_means)
    placebo = np.asarray(placebo_means, dtype=float)
    placebo = placebo[np.isfinite(placebo)]   # a placebo without a paired success has no gain
    p95 = float(np.percentile(placebo, 95)) if placebo.size else float("nan")
    reasons = []
    if ci is None:
        reasons.append("too few paired trials for a confidence interval")
    elif ci[0] <= 0:
        reasons.append(f"the gain's {100 * confidence:g} % CI [{1e3 * ci[0]:+.2f}, {1e3 * ci[1]:+.2f}] mm "
                       "does not exclude 0")
    if not placebo.size:
        reasons.append("no placebo paths were flown" if not flown else
                       f"none of the {flown} placebo paths has a trial that succeeded on it and on the initial path")
    elif not gain > p95:
        reasons.append(f"the gain {1e3 * gain:+.2f} mm does not exceed the placebo 95th percentile "
                       f"{1e3 * p95:+.2f} mm ({placebo.size} placebos)")
    return RobustnessVerdict(gain, ci, int(gains.size), flown, tuple(float(x) for x in placebo), p95, not reasons,
                             "; ".join(reasons) or f"the gain {1e3 * gain:+.2f} mm is above 0 at {100 * confidence:g} "
                                                   f"% and beyond every placebo but the top 5 %")


def paired_difference(base: PathTrials, other: PathTrials, rng: np.random.Generator, resamples: int,
                      confidence: float, spec: tuple[float, float] | None = None) -> PairedDifference:
    """other - base on the same trial ids: mean and p95 error (trials where both succeeded), failure rate and,
    with ``spec``, P(meets spec) (all paired trials)."""
    common, ib, io = np.intersect1d(base.trial_id, other.trial_id, return_indices=True)
    if common.size == 0:
        raise InputError(other.name, "no trial ids in common with the initial path's campaign")
    both = (~base.failed[ib] & ~other.failed[io] & np.isfinite(base.error_m[ib]) & np.isfinite(other.error_m[io]))
    d_err = other.error_m[io][both] - base.error_m[ib][both]
    d_fail = other.failed[io].astype(float) - base.failed[ib].astype(float)
    mean = lambda x, axis: x.mean(axis=axis)  # noqa: E731
    e_base, e_other = base.error_m[ib][both], other.error_m[io][both]
    p95 = lambda b, o, axis: np.percentile(o, 95, axis=axis) - np.percentile(b, 95, axis=axis)  # noqa: E731
    spec_diff = None
    if spec is not None:
        spec_diff = (meets_spec(other, *spec)[io].astype(float) - meets_spec(base, *spec)[ib].astype(float))
    return PairedDifference(
        other.name, base.name, int(common.size), int(both.sum()),
        float(d_err.mean()) if d_err.size else float("nan"),
        _ci((d_err,), mean, rng, resamples, confidence) if d_err.size > 2 else None,
        int((d_err < 0).sum()), int((d_err > 0).sum()), float(d_fail.mean()),
        _ci((d_fail,), mean, rng, resamples, confidence),
        float(p95(e_base, e_other, None)) if d_err.size else float("nan"),
        _ci((e_base, e_other), p95, rng, resamples, confidence, paired=True) if d_err.size > 2 else None,
        None if spec_diff is None else float(spec_diff.mean()),
        None if spec_diff is None else _ci((spec_diff,), mean, rng, resamples, confidence))


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


def summarise(paths: list[PathTrials], seed: int, resamples: int, confidence: float,
              spec: tuple[float, float] | None = None, windfree_m: dict[str, float] | None = None,
              placebos: dict[str, list[PathTrials]] | None = None, unmoved: Collection[str] = ()) -> EvaluationResult:
    """Tables 4/5 analogues: per-path summaries and paired differences against the first path; with
    ``windfree_m`` (path name -> wind-free error, placebos included) and ``placebos`` (WRP name -> its placebo
    paths' trials) the robustness gain of every other path and its verdict (module docstring). A path named in
    ``unmoved`` (a WRP that moved no viewpoint: the first path again) is never recommended, for that reason."""
    # one bootstrap stream per statistic and path (by name): a path added to the evaluation changes no other
    # path's intervals
    def rng_for(kind: int, name: str) -> np.random.Generator:
        return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(7, kind, zlib.crc32(name.encode()))))

    result = EvaluationResult(confidence, resamples,
                              tuple(path_summary(p, rng_for(0, p.name), resamples, confidence, spec) for p in paths),
                              tuple(paired_difference(paths[0], p, rng_for(1, p.name), resamples, confidence, spec)
                                    for p in paths[1:]))
    if windfree_m is None:
        return result
    base = paths[0]
    robustness = {}
    for p in paths[1:]:
        gains = robustness_gains(base, p, windfree_m[base.name], windfree_m[p.name])
        placebo_gains = [robustness_gains(base, q, windfree_m[base.name], windfree_m[q.name])
                         for q in (placebos or {}).get(p.name, [])]
        placebo_means = [g.mean() if g.size else np.nan for g in placebo_gains]
        verdict = replace(robustness_verdict(gains, np.array(placebo_means), rng_for(2, p.name), resamples,
                                             confidence),
                          windfree_error_m=windfree_m[p.name])
        if p.name in unmoved:
            verdict = replace(verdict, recommended=False, reason="it moved no viewpoint: it is the initial path")
        robustness[p.name] = verdict
    recommended = [k for k, v in robustness.items() if v.recommended]
    return replace(result, windfree_error_m=dict(windfree_m), robustness=robustness,
                   recommended_path=max(recommended, key=lambda k: robustness[k].gain_m) if recommended
                   else base.name)


def forecast_verdict(trials: PathTrials, ev, spec: tuple[float, float], seed: int, wind) -> ForecastVerdict:
    """What the operator reads: the chosen path in the forecast wind (``wind``: the config's
    ``wind:`` section), P(meets spec) with its CI, views not taken and sorties, and GO when the CI's lower bound
    reaches ``ev.go_probability`` (``ev``: the ``wrp.evaluate`` section, for its bootstrap and confidence)."""
    go_probability = ev.go_probability
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(8,)))
    row = path_summary(trials, rng, ev.bootstrap, ev.confidence, spec)
    ci = row.p_meets_spec_ci
    low = ci[0] if ci else float("nan")
    go = bool(np.isfinite(low) and low >= go_probability)
    summary = (f"forecast wind {wind.speed_10m_m_s:g} m/s from {wind.direction_deg:g} deg, path {trials.name}: "
               f"P(meets spec) {row.p_meets_spec:.2f}"
               + (f" [{ci[0]:.2f}, {ci[1]:.2f}]" if ci else "")
               + f" over {row.trials} flights -> {'GO' if go else 'NO-GO'} (needs the CI's lower bound >= "
               f"{go_probability:g})")
    return ForecastVerdict(row, go, go_probability, float(wind.speed_10m_m_s), float(wind.direction_deg), summary)
