"""``wrp-eval reconstruct`` and ``wrp-eval validate-oracle``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path as FsPath

from wrp_eval.config import load_experiment
from wrp_eval.errors import InputError


def _ship_mesh(config, config_file: str):
    from wrp_eval.ship.resolve import resolve_ship
    _, _, mesh = resolve_ship(config.ship, FsPath(config_file).parent, str(config_file))
    return mesh


def _cmd_reconstruct(args: argparse.Namespace) -> int:
    from wrp_eval.planning.path import Path
    from wrp_eval.recon.scene import scored_ship
    from wrp_eval.recon.capture_io import captures_from_parquet, captures_from_path
    config = load_experiment(args.config)
    path = Path.load(args.path)
    if args.trial is not None and args.captures is None:
        raise InputError("--trial", "needs --captures FILE.parquet")
    if args.captures is not None:
        captures = captures_from_parquet(args.captures, args.trial or 0, path)
    else:
        captures = captures_from_path(path)
    ship = scored_ship(config, FsPath(args.config).parent, args.oracle or config.oracle.kind)
    seed = config.run.seed if args.seed is None else args.seed
    result = ship.score(captures, seed=seed)
    if args.json:
        print(json.dumps(result.to_json_dict(), indent=1))
    else:
        verdict = f"FAILED ({result.reason})" if result.failed else "ok"
        print(f"{result.oracle}: error {result.error_m:.4f} m, accuracy {result.accuracy_m:.4f} m, "
              f"completeness {result.completeness:.3f}, F@{result.tau_m:g} m {result.fscore:.3f}, "
              f"views {result.registered_views}/{result.total_views}, {verdict}, {result.time_s:.2f} s")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    from wrp_eval.recon.validate import validate_oracle
    config = load_experiment(args.config)
    mesh = _ship_mesh(config, args.config)
    summary = validate_oracle(config, mesh, FsPath(args.out), seed=config.run.seed,
                              config_dir=FsPath(args.config).parent,
                              reuse_colmap=FsPath(args.reuse_colmap) if args.reuse_colmap else None)
    print(json.dumps(summary, indent=1))
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
    p.set_defaults(func=_cmd_reconstruct)

    v = sub.add_parser("validate-oracle", help="compare the synthetic oracle with COLMAP on good, degraded "
                                               "and broken capture sets",
                       description="Run both oracles on capture sets spanning good, degraded and broken paths; "
                                   "write table.csv, summary.json and scatter.png to --out.")
    v.add_argument("config", help="experiment YAML (ship:, oracle:, run.seed)")
    v.add_argument("--out", required=True, help="output folder")
    v.add_argument("--reuse-colmap", metavar="SUMMARY_JSON",
                   help="take the COLMAP figures from a previous summary.json (same config and seed) and re-run "
                        "only the synthetic oracle (for calibrating it)")
    v.set_defaults(func=_cmd_validate)
