"""``wrp-eval plan CONFIG --out DIR``: plan a path for the config's ship; writes path.json and
plan_metrics.json (and optionally a rerun recording)."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from wrp_eval.atomic import write_json_atomic

# Stream id of the planning stage inside the run seed (other stages spawn their own).
PLANNING_SEED_STREAM = 3


def planning_rng(seed: int) -> np.random.Generator:
    """The planning stage's generator for run seed ``seed``."""
    return np.random.default_rng(np.random.SeedSequence([seed, PLANNING_SEED_STREAM]))


def _run_plan(args: argparse.Namespace) -> int:
    from wrp_eval.config import load_experiment
    from wrp_eval.planning.planner import plan
    from wrp_eval.ship.resolve import resolve_ship_full

    config_path = Path(args.config)
    config = load_experiment(config_path)
    section = config.planning
    if args.method:
        section = section.model_copy(update={"method": args.method})
    ship = resolve_ship_full(config.ship, config_path.parent, str(config_path))
    result = plan(ship.proxy, ship.complexity.complexity, section, planning_rng(config.run.seed))
    out = Path(args.out)
    meta = dict(result.path.metadata)
    meta.update({"config": str(config_path), "ship_type": ship.particulars.ship_type.value, "seed": config.run.seed})
    path = dataclasses.replace(result.path, metadata=meta)
    path.save(out / "path.json")
    metrics = {**result.metrics, "config": str(config_path), "seed": config.run.seed,
               "ship": {"type": ship.particulars.ship_type.value, "mesh_source": ship.mesh_source,
                        "proxy_m": [ship.proxy.length_m, ship.proxy.breadth_m, ship.proxy.height_m],
                        "no_fly_margin_m": ship.proxy.no_fly_margin_m}}
    write_json_atomic(out / "plan_metrics.json", metrics)
    if args.rerun:
        from wrp_eval.planning.rerun_log import save_plan_recording
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
    parser.set_defaults(func=_run_plan)
