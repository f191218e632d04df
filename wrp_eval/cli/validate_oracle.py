"""``wrp-eval validate-oracle CONFIG --out DIR``: the synthetic oracle against COLMAP on good, degraded and
broken capture sets (needs the ``photogrammetry`` extra unless ``--reuse-colmap``); with ``--perturbed``, on
perturbed capture sets of the config's planned ``ours`` path instead."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.recon.perturbed import FLIGHTS_PER_SPEED, flown_capture_sets, perturbed_capture_sets
from wrp_eval.recon.validate import validate_oracle, validate_perturbed

PLANNED_METHODS = ("ours", "zhou2020")   # ours with transition views, Zhou et al. 2020's Min-Max without
PERTURBED_METHOD = "ours"


def _perturbed(args: argparse.Namespace, ctx: ExperimentContext, reuse: Path | None) -> int:
    flights_per_speed = FLIGHTS_PER_SPEED if args.flights is None else args.flights
    path = ctx.plan_with(PERTURBED_METHOD).path
    flights = []
    if flights_per_speed > 0:
        print(f"flying the {PERTURBED_METHOD} path ({len(path)} views) {flights_per_speed} time(s) per wind speed, "
              f"capture mode and navigation preset", flush=True)
        flights = flown_capture_sets(ctx, path, ctx.run_seed, per_speed=flights_per_speed)
    sets = perturbed_capture_sets(path, ctx.run_seed, flights)
    summary = validate_perturbed(_oracle_section(args, ctx), ctx.ship.mesh, sets, Path(args.out),
                                 seed=ctx.run_seed, reuse_colmap=reuse)
    print(json.dumps(summary, indent=1, default=float))
    return 0


def _oracle_section(args: argparse.Namespace, ctx: ExperimentContext):
    """The config's ``oracle:`` section, COLMAP's render width replaced by ``--colmap-width`` where given."""
    section = ctx.config.oracle
    if args.colmap_width is None:
        return section
    if not 160 <= args.colmap_width <= 6000:
        raise InputError("--colmap-width", f"must be 160-6000 px, not {args.colmap_width}")
    return section.model_copy(update={"colmap": section.colmap.model_copy(
        update={"image_width_px": int(args.colmap_width)})})


def _validate(args: argparse.Namespace) -> int:
    if args.flights is not None and not args.perturbed:
        raise InputError("--flights", "only applies with --perturbed")
    if args.flights is not None and args.flights < 0:
        raise InputError("--flights", "must be >= 0")
    ctx = ExperimentContext.load(args.config)
    reuse = Path(args.reuse_colmap) if args.reuse_colmap else None
    if args.perturbed:
        return _perturbed(args, ctx, reuse)
    planned = {method: ctx.plan_with(method).path for method in PLANNED_METHODS}
    summary = validate_oracle(_oracle_section(args, ctx), ctx.ship.mesh, Path(args.out), seed=ctx.run_seed,
                              planned=planned,
                              reuse_colmap=reuse)
    print(json.dumps(summary, indent=1))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    v = sub.add_parser("validate-oracle", help="compare the synthetic oracle with COLMAP on good, degraded "
                                               "and broken capture sets",
                       description="Run both oracles on capture sets spanning good, degraded and broken paths; "
                                   "write table.csv, summary.json and scatter.png to --out. With --perturbed, "
                                   "on perturbed capture sets of the planned 'ours' path (single moved and "
                                   "dropped views, navigation drift, heading bias, motion blur, flights in both "
                                   "capture modes and three navigation presets); write "
                                   "perturbed_table.csv, perturbed_summary.json and perturbed_scatter.png.")
    v.add_argument("config", help="experiment YAML (ship:, oracle:, run.seed; with --perturbed also planning:, "
                                  "sim:, wind:)")
    v.add_argument("--out", required=True, help="output folder")
    v.add_argument("--reuse-colmap", metavar="SUMMARY_JSON",
                   help="take the COLMAP figures from a previous summary.json (perturbed_summary.json with "
                        "--perturbed; same config and seed) and re-run only the synthetic oracle (for "
                        "calibrating it)")
    v.add_argument("--perturbed", action="store_true",
                   help="perturbed capture sets of the planned 'ours' path instead of the validation sets; "
                        "reports each oracle's change from the unperturbed set and their rank correlation")
    v.add_argument("--flights", type=int, default=None, metavar="N",
                   help=f"with --perturbed: simulated flights per wind speed (U10 0, 8, 12 m/s) and capture "
                        f"mode, and per navigation preset at 8 m/s (default {FLIGHTS_PER_SPEED}; 0: no flight sets)")
    v.add_argument("--colmap-width", type=int, default=None, metavar="PX",
                   help="COLMAP's render width in px (default: the config's oracle.colmap.image_width_px; "
                        "`wrp-eval bench --only colmap` measures the time against it)")
    v.set_defaults(func=_validate)
