"""``wrp-eval plan CONFIG --out DIR``: plan a path for the config's ship; writes path.json and
plan_metrics.json (and optionally a rerun recording)."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from wrp_eval.atomic import write_json_atomic
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.rerun_log import save_plan_recording


def _plan(args: argparse.Namespace) -> int:
    ctx = ExperimentContext.load(args.config)
    if args.method:
        ctx = ctx.with_config(ctx.config.model_copy(
            update={"planning": ctx.config.planning.model_copy(update={"method": args.method})}))
    ship, result = ctx.ship, ctx.planned
    out = Path(args.out)
    path = dataclasses.replace(result.path, metadata={**result.path.metadata,
                                                      "ship_type": ship.particulars.ship_type.value})
    path.save(out / "path.json")
    metrics = {**result.metrics, "config": ctx.source, "seed": ctx.run_seed,
               "ship": {"type": ship.particulars.ship_type.value, "mesh_source": ship.mesh_source,
                        "proxy_m": [ship.proxy.length_m, ship.proxy.breadth_m, ship.proxy.height_m],
                        "no_fly_margin_m": ship.proxy.no_fly_margin_m}}
    write_json_atomic(out / "plan_metrics.json", metrics)
    if args.rerun:
        save_plan_recording(result, ship.proxy, args.rerun)
    m = result.metrics
    print(f"{m['method']}: {len(path)} viewpoints ({m.get('n_transition_views', 0)} transition), "
          f"{m['length_m']:.1f} m, {m['flight_time_s']:.1f} s flight, {m['sorties']} sortie(s); "
          f"planned in {m['timings']['total_s']:.2f} s -> {out}")
    return 0


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "plan", help="plan the reconstruction path of a config's ship (paper Sec. 3)",
        description="Sample the ship's proxy, choose views by Min-Max, order them by a TSP tour, add "
                    "transition viewpoints, and write DIR/path.json and DIR/plan_metrics.json.")
    parser.add_argument("config", help="experiment YAML file")
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--method", choices=("ours", "zhou2020", "oblique"), default=None,
                        help="override planning.method")
    parser.add_argument("--rerun", default=None, metavar="FILE", help="also write a rerun recording (.rrd)")
    parser.set_defaults(func=_plan)
