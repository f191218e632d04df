"""``wrp-eval run CONFIG [--smallest]``: the whole job (plan, campaign, surrogate, ISWRP/SWRP, evaluation,
export, report) into ``logs/<run.name>/``; a ``study:`` config runs its variants (the paper's tables)."""

from __future__ import annotations

import argparse
from pathlib import Path

from wrp_eval.experiment import ExperimentContext
from wrp_eval.pipeline import __doc__ as PIPELINE_DOC
from wrp_eval.pipeline import run_pipeline
from wrp_eval.run_summary import RunSummary


def _run(args: argparse.Namespace) -> int:
    ctx = ExperimentContext.load(args.config)
    summary = run_pipeline(ctx, smallest=args.smallest)
    if isinstance(summary, RunSummary):
        out, total, report = Path(summary.out), summary.timings_s["total"], summary.report
    else:                   # a study's document
        out, total, report = Path(summary["out"]), summary["timings_s"]["total"], summary["report"]
    print(f"\nwrp-eval run finished in {total:.0f} s.")
    print(f"Report:    {report}")
    if not isinstance(summary, RunSummary):   # a study: a table, and one recording per variant
        print(f"Table:     {out / 'study.json'}  (the rows as JSON; per-variant paths under {out / 'study'})")
    print(f"Recording: {out / 'run.rrd'}  (open it with: rerun {out / 'run.rrd'})")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="the whole job: plan, campaign, surrogate, ISWRP/SWRP, evaluation, "
                                   "export, report", description=PIPELINE_DOC,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config", help="experiment YAML (e.g. experiments/quickstart.yaml)")
    p.add_argument("--progress", action="store_true", help="show the stages' own progress bars and lines")
    p.add_argument("--smallest", action="store_true", help="a study config (experiments/paper/): its smallest "
                                                           "setting (study.smallest), as the tests run it")
    p.set_defaults(func=_run)
