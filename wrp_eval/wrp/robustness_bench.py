"""``wrp-eval bench --only robustness``: does a WRP beat its placebos?

The main job's evaluation on the quickstart config (experiments/quickstart.yaml: its campaign, surrogate, ISWRP
and SWRP, then the initial path, both WRPs and ``wrp.evaluate.placebos`` placebo paths per WRP flown under the
same winds), written to a temporary folder. ~12 minutes on the 2-core machine, most of it the placebo flights.

Records per WRP kind (``.iswrp`` / ``.swrp``): ``wrp.robustness_gain_mm`` ([E_wind - E_windfree](initial) -
[E_wind - E_windfree](WRP), mean over paired trials), ``wrp.robustness_gain_ci_low_mm`` (its bootstrap CI's
lower bound), ``wrp.placebo_gain_p95_mm`` (the placebos' 95th percentile), ``wrp.recommended`` (1 when the CI
excludes 0 and the gain beats the placebo 95th percentile, else 0), and ``wrp.evaluate_s``; first with the
product's acceptance (``validated``), then with Alg. 3 as written (kinds ``iswrp_alg3`` / ``swrp_alg3``), whose
WRPs move viewpoints, so that the placebo control is exercised whatever the product decides.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from wrp_eval.bench_record import BenchRecord
from wrp_eval.campaign.jobs import campaign_job
from wrp_eval.experiment import ExperimentContext
from wrp_eval.resources import source_experiments_dir
from wrp_eval.surrogate.train import train_from_campaign
from wrp_eval.wrp.evaluation import EvaluationResult
from wrp_eval.wrp.jobs import evaluate_job

CONFIG = source_experiments_dir() / "quickstart.yaml"


def run_bench() -> list[BenchRecord]:
    ctx = ExperimentContext.load(CONFIG)
    records = []
    with tempfile.TemporaryDirectory(prefix="wrp-robustness-") as tmp:
        out = Path(tmp)
        start = time.perf_counter()
        campaign_job(ctx, out_dir=out / "campaign")
        trained, trials, _ = train_from_campaign(ctx, out / "campaign", out / "surrogate")
        for acceptance, suffix in (("validated", ""), ("paper", "_alg3")):
            # the product's WRPs, then Alg. 3 as written (it moves viewpoints: the placebo control at work)
            wrp = ctx.config.wrp.model_copy(update={"acceptance": acceptance})
            config = ctx.config.model_copy(update={"wrp": wrp})
            run_ctx = ctx.with_config(config, f"{ctx.source} (acceptance {acceptance})")
            doc = evaluate_job(run_ctx, out / f"evaluate-{acceptance}", campaign=out / "campaign",
                               surrogate=trained.surrogate, trials=trials)
            records += _records(doc, trained.metrics["test"]["r2"], suffix, acceptance)
        seconds = time.perf_counter() - start
    records.append(BenchRecord("wrp.evaluate_s", seconds, "s", None, None,
                               f"campaign {ctx.config.campaign.n_trials} trials + training + for each acceptance "
                               f"ISWRP/SWRP + {len(doc.paths)} paths and their placebos flown"))
    return records


def _records(doc: EvaluationResult, r2: float, suffix: str, acceptance: str) -> list[BenchRecord]:
    records = []
    for name, v in (doc.robustness or {}).items():
        kind = name + suffix
        table = (doc.wrp or {})[name]
        note = (f"quickstart, acceptance {acceptance}, {doc.paths[0].trials} winds per path, "
                f"{len(v.placebo_gains_m)} placebos; {table.offset_rate_pct:.0f} % of the viewpoints moved; "
                f"surrogate held-out R^2 {r2:.3f}; verdict: {'recommended' if v.recommended else v.reason}; "
                f"path to fly: {doc.recommended_path}")
        ci = v.gain_ci_m
        records += [
            BenchRecord(f"wrp.robustness_gain_mm.{kind}", 1e3 * v.gain_m, "mm", None, None, note),
            BenchRecord(f"wrp.robustness_gain_ci_low_mm.{kind}", 1e3 * ci[0] if ci else float("nan"), "mm",
                        "issue 18: > 0 to recommend", 0.0, note),
            BenchRecord(f"wrp.placebo_gain_p95_mm.{kind}", 1e3 * v.placebo_gain_p95_m, "mm",
                        "issue 18: the gain must exceed it", None, note),
            BenchRecord(f"wrp.recommended.{kind}", float(v.recommended), "bool", None, None, note),
        ]
    return records
