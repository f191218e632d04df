"""Cost against the view count (``wrp-eval bench --only views``, also part of ``--only scaling``): the quickstart
ship planned at decreasing ground sampling distance (``GSDS_MM``: 46 / 141 / 329 / 555 views), and per
plan

* planning: the ``ours`` planner's wall time and its stages (sampling, visibility, Min, Max, tour, transitions);
* oracle: the synthetic oracle on the path flown as planned (median of 3 after a warm-up call), and its
  milliseconds per view;
* campaign: ``FLIGHTS`` physical-design flights of the path at U10 ``WIND_M_S`` (directions uniform, turbulence
  from the mean wind, 2 local workers): trials per minute and each trial's flight and oracle seconds; and
  ``LARGE_CAMPAIGN_FLIGHTS`` flights of the ~141-view inspection path (a training campaign's size).

Each curve is fitted as cost ~ a views^k on log-log axes; the exponents are records (the performance issue's
targets: planning <= 1.3, oracle and campaign <= 1.1).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from wrp_eval.bench_record import BenchRecord
from wrp_eval.campaign.capture_bench import quickstart_campaign, quickstart_context
from wrp_eval.config import ExperimentConfig
from wrp_eval.recon.capture_io import captures_from_path

GSDS_MM = (7.5, 4.0, 2.5, 1.85)
FLIGHTS = 32
# the performance issue's rate on the inspection path, also at the size of a training campaign: 32 flights are a
# batch of 16 per worker and ~7 s of pool start-up; at 256 each worker flies batches of 64
INSPECTION_GSD_MM = 4.0
LARGE_CAMPAIGN_FLIGHTS = 256
WIND_M_S = 8.0
PLAN_STAGES = ("sampling_s", "visibility_s", "min_s", "max_s", "metrics_s", "tsp_s", "transitions_s")
EXPONENT_TARGETS = {"plan": 1.3, "oracle": 1.1, "campaign": 1.1}


def exponent(x, y) -> float:
    """k of the least-squares fit log y = log a + k log x."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def target_anchor(target: str, value: float, applies: bool) -> tuple[str | None, float | None]:
    """A record's (anchor, anchor_value): the target and its figure where it applies, else (None, None)."""
    return (target, value) if applies else (None, None)


def at_gsd(ctx, gsd_mm: float):
    """``ctx`` with the planner's ground sampling distance set to ``gsd_mm`` (the same ship, another view count)."""
    doc = ctx.config.model_dump(mode="json")
    doc["planning"]["gsd_mm"] = gsd_mm
    return ctx.with_config(ExperimentConfig.model_validate(doc))


def _oracle_s(ctx, path) -> float:
    scorer = ctx.scored_ship
    captures = captures_from_path(path)
    scorer.score(captures, 0)  # the ground truth is prepared once per ship
    times = []
    for seed in range(3):
        start = time.perf_counter()
        scorer.score(captures, seed)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def view_count_points(gsds=GSDS_MM, flights: int = FLIGHTS) -> list[dict]:
    """One dict per GSD: views, plan timings (s), oracle_s, trials_per_min, and the median flight, oracle and
    trial seconds per trial (medians: a worker's first trial also loads its kernels)."""
    base = quickstart_context()
    warm = at_gsd(base, gsds[0])
    _ = warm.planned  # warm-up, untimed: the ship, the compiled kernels and each worker's start load once
    with tempfile.TemporaryDirectory() as tmp:
        quickstart_campaign(warm, WIND_M_S, Path(tmp) / "warm", flights=2)
    points = []
    for gsd in gsds:
        ctx = at_gsd(base, gsd)
        start = time.perf_counter()
        planned = ctx.planned
        plan_wall = time.perf_counter() - start
        path = planned.path
        point = {"gsd_mm": gsd, "views": len(path), "plan_s": plan_wall,
                 **{k: float(planned.metrics["timings"].get(k, 0.0)) for k in PLAN_STAGES},
                 "oracle_s": _oracle_s(ctx, path)}
        with tempfile.TemporaryDirectory() as tmp:
            summary, table = quickstart_campaign(ctx, WIND_M_S, Path(tmp) / "c", flights=flights)
        point["trials_per_min"] = float(summary.trials_per_min)
        point["flights"] = flights
        for column in ("flight_s", "oracle_s", "trial_s"):
            values = table.column(column).to_numpy(zero_copy_only=False).astype(float)
            point[f"trial_{column}"] = float(np.nanmedian(values))
        points.append(point)
    return points


def view_count_records(points: list[dict]) -> list[BenchRecord]:
    views = [p["views"] for p in points]
    records = []
    for p in points:
        tag = f"v{p['views']}"
        note = (f"quickstart ship at gsd {p['gsd_mm']:g} mm, {p['views']} views; stages "
                + ", ".join(f"{k[:-2]} {p[k]:.2f}" for k in PLAN_STAGES) + " s")
        records += [
            BenchRecord(f"scaling.views.plan_s.{tag}", p["plan_s"], "s",
                        *target_anchor("performance issue target (330 views)", 5.0, 300 <= p["views"] <= 360),
                        note),
            BenchRecord(f"scaling.views.oracle_ms_per_view.{tag}", 1e3 * p["oracle_s"] / p["views"], "ms", None, None,
                        f"synthetic oracle, path flown as planned, median of 3: {p['oracle_s']:.3f} s"),
            BenchRecord(f"scaling.views.campaign_trials_per_min.{tag}", p["trials_per_min"], "trials/min",
                        *target_anchor("performance issue target (143 views, 2 workers)", 150.0,
                                       120 <= p["views"] <= 170),
                        f"{p['flights']} physical flights at U10 {WIND_M_S:g} m/s, 2 local workers; median "
                        "trial: flight "
                        f"{p['trial_flight_s']:.3f} s + oracle {p['trial_oracle_s']:.3f} s (trial "
                        f"{p['trial_trial_s']:.3f} s); oracle share {p['trial_oracle_s'] / p['trial_trial_s']:.0%}"),
        ]
    curves = {"plan": [p["plan_s"] for p in points], "oracle": [p["oracle_s"] for p in points],
              "campaign": [p["trial_trial_s"] for p in points]}  # median seconds per trial
    for name, cost in curves.items():
        records.append(BenchRecord(f"scaling.views.{name}_exponent", exponent(views, cost), "",
                                   "performance issue target (at most)", EXPONENT_TARGETS[name],
                                   f"{name} cost ~ views^k over {views[0]}-{views[-1]} views"
                                   + (" (campaign: median seconds per trial)" if name == "campaign" else "")))
    for stage in PLAN_STAGES:
        cost = [max(p[stage], 1e-4) for p in points]
        records.append(BenchRecord(f"scaling.views.plan_{stage[:-2]}_exponent", exponent(views, cost), "", None,
                                   None, f"planning stage {stage[:-2]} ~ views^k"))
    return records


def large_campaign_record(flights: int = LARGE_CAMPAIGN_FLIGHTS) -> BenchRecord:
    """Trials per minute of ``flights`` physical flights of the inspection path (gsd ``INSPECTION_GSD_MM``)."""
    ctx = at_gsd(quickstart_context(), INSPECTION_GSD_MM)
    path = ctx.planned.path
    with tempfile.TemporaryDirectory() as tmp:
        summary, table = quickstart_campaign(ctx, WIND_M_S, Path(tmp) / "c", flights=flights)
    median = {c: float(np.nanmedian(table.column(c).to_numpy(zero_copy_only=False).astype(float)))
              for c in ("flight_s", "oracle_s")}
    return BenchRecord(f"scaling.views.campaign_trials_per_min_{flights}.v{len(path)}", float(summary.trials_per_min),
                       "trials/min", "performance issue target (143 views, 2 workers)", 150.0,
                       f"{flights} physical flights at U10 {WIND_M_S:g} m/s, 2 local workers, wall "
                       f"{summary.wall_s:.1f} s; median trial: flight {median['flight_s']:.3f} s + oracle "
                       f"{median['oracle_s']:.3f} s")


def run_bench() -> list[BenchRecord]:
    return view_count_records(view_count_points()) + [large_campaign_record()]
