"""``wrp-eval reconstruct CONFIG --path P [--captures F --trial K]``: the oracle's verdict on capture poses."""

from __future__ import annotations

import argparse
import json

from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_parquet, captures_from_path


def _reconstruct(args: argparse.Namespace) -> int:
    if args.trial is not None and args.captures is None:
        raise InputError("--trial", "needs --captures FILE.parquet")
    ctx = ExperimentContext.load(args.config)
    path = FlightPath.load(args.path)
    captures = (captures_from_parquet(args.captures, args.trial or 0, path) if args.captures is not None
                else captures_from_path(path))
    ship = ctx.scorer(args.oracle or ctx.config.oracle.kind)
    result = ship.score(captures, seed=ctx.run_seed if args.seed is None else args.seed)
    if args.json:
        print(json.dumps(result.to_json_dict(), indent=1))
        return 0
    verdict = f"FAILED ({result.reason})" if result.failed else "ok"
    print(f"{result.oracle}: error {result.error_m:.4f} m, accuracy {result.accuracy_m:.4f} m, "
          f"completeness {result.completeness:.3f}, F@{result.tau_m:g} m {result.fscore:.3f}, "
          f"views {result.registered_views}/{result.total_views}, {verdict}, {result.time_s:.2f} s")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("reconstruct", help="measure the reconstruction of a path's (or a trial's) captures",
                       description="Run a reconstruction oracle on the planned poses of a path, or on the poses "
                                   "actually flown in one trial of a captures.parquet.")
    p.add_argument("config", help="experiment YAML (ship:, oracle:, run.seed)")
    p.add_argument("--path", required=True, help="path.json from the planner")
    p.add_argument("--captures", help="captures.parquet from `wrp-eval fly` (default: the planned poses)")
    p.add_argument("--trial", type=int, help="trial of --captures (default 0)")
    p.add_argument("--oracle", choices=("synthetic", "colmap"), help="default: oracle.kind of the config")
    p.add_argument("--seed", type=int, help="noise seed (default: run.seed)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=_reconstruct)
