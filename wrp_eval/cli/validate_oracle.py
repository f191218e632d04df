"""``wrp-eval validate-oracle CONFIG --out DIR``: the synthetic oracle against COLMAP on good, degraded and
broken capture sets (needs the ``photogrammetry`` extra unless ``--reuse-colmap``)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from wrp_eval.experiment import ExperimentContext
from wrp_eval.recon.validate import validate_oracle

PLANNED_METHODS = ("ours", "zhou2020")   # ours with transition views, Zhou et al. 2020's Min-Max without


def _validate(args: argparse.Namespace) -> int:
    ctx = ExperimentContext.load(args.config)
    planned = {method: ctx.plan_with(method).path for method in PLANNED_METHODS}
    summary = validate_oracle(ctx.config.oracle, ctx.ship.mesh, Path(args.out), seed=ctx.run_seed, planned=planned,
                              reuse_colmap=Path(args.reuse_colmap) if args.reuse_colmap else None)
    print(json.dumps(summary, indent=1))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    v = sub.add_parser("validate-oracle", help="compare the synthetic oracle with COLMAP on good, degraded "
                                               "and broken capture sets",
                       description="Run both oracles on capture sets spanning good, degraded and broken paths; "
                                   "write table.csv, summary.json and scatter.png to --out.")
    v.add_argument("config", help="experiment YAML (ship:, oracle:, run.seed)")
    v.add_argument("--out", required=True, help="output folder")
    v.add_argument("--reuse-colmap", metavar="SUMMARY_JSON",
                   help="take the COLMAP figures from a previous summary.json (same config and seed) and re-run "
                        "only the synthetic oracle (for calibrating it)")
    v.set_defaults(func=_validate)
