"""``wrp-eval optimize``: the wind-resistance path (ISWRP / SWRP) of a path, from a trained surrogate.

    wrp-eval optimize CONFIG [--kind iswrp|swrp] [--threshold T] [--out DIR] [--checkpoint FILE]
                             [--campaign DIR] [--e-original E] [--no-oracle] [--quiet]

Writes <out>/path.json (the WRP) and <out>/wrp_metrics.json (the paper's Table 3 columns: offset rate,
total position / rotation offset, time, and the WRP's error from the ORACLE; plus the surrogate's figures,
per-viewpoint offsets and where E_original and r_s came from).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from wrp_eval.errors import InputError

EVALUATE_DOC = """``wrp-eval evaluate CONFIG``: robustness of the initial path, ISWRP and SWRP under the same winds.

    wrp-eval evaluate CONFIG [--trials N] [--out DIR] [--checkpoint FILE] [--campaign DIR] [--e-original E]

Optimises the ISWRP and the SWRP (as ``optimize``), then flies the three paths as campaigns with the same seed
(common random numbers, viewpoints as planned) and writes <out>/evaluate.json (per path: mean, std, 95th
percentile of the error and failure rate with bootstrap CIs; paired differences against the initial path)
and <out>/boxplot.png. Re-running resumes the campaigns.
"""


def oracle_error(config, path, config_dir: Path, ship=None) -> dict:
    """The oracle's verdict (JSON dict) on the path flown exactly as planned (no wind): capture poses =
    viewpoints, oracle seed 0. ship: a :class:`wrp_eval.recon.scene.ScoredShip` already built from ``config``
    (saves resolving the ship again); none: built here."""
    from wrp_eval.recon.capture_io import captures_from_path
    from wrp_eval.recon.scene import scored_ship
    ship = ship if ship is not None else scored_ship(config, config_dir)
    return ship.score(captures_from_path(path), seed=0).to_json_dict()


def resolve_inputs(config, section, config_dir: Path, checkpoint: str | None = None, campaign: str | None = None):
    """(path, surrogate, campaign folder or None, r_s (n,), r_s source) for ``section``."""
    from wrp_eval.campaign.runner import path_digest
    from wrp_eval.planning.path import Path as FlightPath
    from wrp_eval.surrogate.commands import default_campaign_dir, default_out_dir
    from wrp_eval.surrogate.model import Surrogate
    from wrp_eval.wrp.optimize import sample_radii
    camp = Path(campaign or section.campaign_dir or default_campaign_dir(config))
    path_file = Path(section.path) if section.path else camp / "path.json"
    path = FlightPath.load(path_file)
    digests = {path_digest(path.to_json_dict())}
    try:   # the campaign hashes the document it stored; hash the file's own document too
        digests.add(path_digest(json.loads(path_file.read_text())))
    except (KeyError, TypeError, ValueError):
        pass
    ckpt = Path(checkpoint or section.checkpoint or default_out_dir(config) / "surrogate.pt")
    surrogate = Surrogate.load(ckpt, n_views=len(path), path_digest=digests)
    radius = np.full(len(path), section.sample_radius_m)
    source = f"fixed {section.sample_radius_m} m"
    if section.sample_radius == "campaign":
        if (camp / "campaign.json").is_file():
            from wrp_eval.surrogate.data import load_campaign_trials
            data = load_campaign_trials(camp)
            if data.n_views != len(path):
                raise InputError(camp, f"campaign has {data.n_views} viewpoints, the path {len(path)}")
            measured = sample_radii(data.deviation, section.sample_radius_quantile)
            ok = np.isfinite(measured) & (measured > 0)
            radius = np.where(ok, measured, section.sample_radius_m)
            source = (f"campaign {camp}: {section.sample_radius_quantile:g} quantile of |flown - commanded| over "
                      f"{data.n_trials} trials ({int((~ok).sum())} viewpoints fell back to "
                      f"{section.sample_radius_m} m)")
        else:
            source = f"fixed {section.sample_radius_m} m (no campaign at {camp})"
    return path, surrogate, camp, radius, source


def safety_constraints(config, path, config_dir: Path) -> dict:
    """The planner's flight-safety constraints for moved viewpoints: minimum altitude and the no-fly box."""
    from wrp_eval.ship.proxy import build_proxy
    from wrp_eval.ship.resolve import resolve_particulars
    particulars, _ = resolve_particulars(config.ship, config_dir)
    proxy = build_proxy(particulars, config.ship.no_fly_margin_m)
    return {"base_positions": np.asarray(path.positions, dtype=float),
            "min_altitude_m": float(config.planning.min_altitude_m), "no_fly_bounds": proxy.no_fly_bounds()}


def step_from_surrogate(surrogate, section) -> float:
    """The position move bound: ``step_m``, else the training offsets' smallest position half-range."""
    if section.step_m is not None:
        return float(section.step_m)
    low, high = surrogate.meta.offset_low, surrogate.meta.offset_high
    if low is None or high is None:
        return float(section.step_fallback_m)
    return float(min(min(-low[k], high[k]) for k in range(3)))


def run_optimize(config, section, config_dir: Path, out: Path, *, checkpoint=None, campaign=None,
                 e_original=None, use_oracle=True, quiet=False) -> dict:
    """The whole ``optimize`` command as a function: returns the wrp_metrics document."""
    import torch
    from wrp_eval.atomic import write_json_atomic
    from wrp_eval.wrp.optimize import WrpParams, apply_offsets, interval_optimise
    torch.set_num_threads(section.threads)
    path, surrogate, camp, radius, radius_source = resolve_inputs(config, section, config_dir, checkpoint, campaign)
    e0 = e_original if e_original is not None else section.e_original_m
    e0_source = "given"
    if e0 is None and section.e_original_source == "surrogate":
        e0 = float(surrogate.predict(np.zeros((1, len(path), 4)))[0])
        e0_source = "surrogate at zero offsets"
    ship = None
    if e0 is None or (use_oracle and section.oracle_error):
        from wrp_eval.recon.scene import scored_ship
        ship = scored_ship(config, config_dir)     # once for both verdicts: the wind-free and the WRP path
    if e0 is None:
        verdict = oracle_error(config, path, config_dir, ship)
        if verdict["error_m"] is None:
            raise InputError("wrp", f"the oracle could not score the wind-free path ({verdict['reason']}); "
                                    "give wrp.e_original_m")
        e0, e0_source = float(verdict["error_m"]), f"oracle ({verdict['oracle']}) on the wind-free path"
    threshold = section.threshold_m if section.threshold_m is not None else section.threshold_fraction * e0
    params = WrpParams(kind=section.kind, threshold_m=float(threshold), e_original_m=float(e0),
                       sample_radius_m=radius, iterations=section.iterations,
                       attitude_samples=section.attitude_samples, yaw_range_rad=float(np.radians(section.yaw_range_deg)),
                       neighbourhood_samples=section.neighbourhood_samples,
                       step_m=step_from_surrogate(surrogate, section), swrp_spread=section.swrp_spread,
                       block_iterations=section.block_iterations, stage2_batch=section.stage2_batch,
                       acceptance=section.acceptance, min_improvement_fraction=section.min_improvement_fraction,
                       improve_candidates=section.improve_candidates,
                       **safety_constraints(config, path, config_dir))
    seed = section.seed if section.seed is not None else config.run.seed
    result = interval_optimise(surrogate, params, seed=seed)
    table = result.table3()
    wrp_path = apply_offsets(path, result.offsets, {"wrp": {"kind": section.kind, "threshold_m": threshold,
                                                            "seed": seed}})
    if use_oracle and section.oracle_error:
        verdict = oracle_error(config, wrp_path, config_dir, ship)
        table["oracle_error_m"] = verdict["error_m"]
        table["oracle"] = verdict
    else:
        table["oracle_error_m"] = None
    out.mkdir(parents=True, exist_ok=True)
    wrp_path.save(out / "path.json")
    doc = {"table3": table, "e_original_source": e0_source, "sample_radius_source": radius_source,
           "sample_radius_m": radius.tolist(), "step_m": params.step_m, "seed": seed,
           "yaw_range_deg": section.yaw_range_deg, "iterations": params.iterations,
           "attitude_samples": params.attitude_samples, "neighbourhood_samples": params.neighbourhood_samples,
           "swrp_spread": params.swrp_spread, "acceptance": params.acceptance,
           "min_improvement_fraction": params.min_improvement_fraction,
           "surrogate": {"path_digest": surrogate.meta.path_digest, "metrics": surrogate.meta.metrics.get("test")},
           "viewpoints": [{"index": i, "moved": bool(result.moved[i]), "dx_m": float(o[0]), "dy_m": float(o[1]),
                           "dz_m": float(o[2]), "dyaw_deg": float(np.degrees(o[3])),
                           "accepted_iteration": int(result.accepted_iteration[i])}
                          for i, o in enumerate(result.offsets)]}
    write_json_atomic(out / "wrp_metrics.json", doc)
    if not quiet:
        err = table["oracle_error_m"]
        print(f"{section.kind} t={threshold:.4g} m: {table['offset_rate_pct']:.1f} % viewpoints moved, position "
              f"offset {table['position_offset_m']:.2f} m, rotation offset {table['rotation_offset_deg']:.1f} deg, "
              f"{table['time_s']:.2f} s; error: oracle "
              + (f"{err:.4f} m" if err is not None else "n/a") + f", surrogate {table['surrogate_error_m']:.4f} m "
              f"(E_original {e0:.4f} m) -> {out}")
    return doc


def _optimize(args: argparse.Namespace) -> int:
    from wrp_eval.config import load_experiment
    from wrp_eval.wrp.config import WrpSection
    config = load_experiment(args.config)
    updates = {}
    if args.kind:
        updates["kind"] = args.kind
    if args.threshold is not None:
        if args.threshold < 0:
            raise InputError("--threshold", f"must be >= 0, got {args.threshold}")
        updates["threshold_m"] = args.threshold
    section = WrpSection.model_validate({**config.wrp.model_dump(), **updates})
    out = Path(args.out or section.out_dir or Path("logs") / config.run.name / f"wrp-{section.kind}")
    run_optimize(config, section, Path(args.config).parent, out, checkpoint=args.checkpoint,
                 campaign=args.campaign, e_original=args.e_original, use_oracle=not args.no_oracle,
                 quiet=args.quiet)
    return 0


def run_evaluate(config, config_dir: Path, out: Path, *, n_trials: int | None = None, checkpoint=None,
                 campaign=None, e_original=None, quiet=False, evaluator: str | None = None) -> dict:
    """The ``evaluate`` command as a function: ISWRP and SWRP optimised, then the initial path and both WRPs
    flown as campaigns with the same seed (common random numbers); returns the evaluate.json document.
    ``evaluator``: the campaign's trial evaluator ("module:function"; default the MuJoCo flight + oracle)."""
    from wrp_eval.campaign.evaluators import DEFAULT_EVALUATOR
    from wrp_eval.campaign.runner import run_campaign
    from wrp_eval.config import ExperimentConfig
    from wrp_eval.atomic import write_json_atomic
    from wrp_eval.wrp.config import WrpSection
    from wrp_eval.wrp.evaluate import box_plot, read_trials, summarise
    from wrp_eval.planning.path import Path as FlightPath
    section, ev = config.wrp, config.wrp.evaluate
    if ev.thresholds_m is not None and len(ev.thresholds_m) != 2:
        raise InputError("wrp.evaluate.thresholds_m", "give two thresholds: [iswrp, swrp]")
    initial, *_ = resolve_inputs(config, section, config_dir, checkpoint, campaign)
    paths = {"initial": initial}
    optimised = {}
    for i, kind in enumerate(("iswrp", "swrp")):
        update = {"kind": kind}
        if ev.thresholds_m is not None:
            update["threshold_m"] = ev.thresholds_m[i]
        kind_section = WrpSection.model_validate({**section.model_dump(), **update})
        optimised[kind] = run_optimize(config, kind_section, config_dir, out / f"wrp-{kind}", checkpoint=checkpoint,
                                       campaign=campaign, e_original=e_original, quiet=quiet)
        paths[kind] = FlightPath.load(out / f"wrp-{kind}" / "path.json")
    doc = config.model_dump(mode="json")
    doc["campaign"].update({"n_trials": n_trials or ev.n_trials, "path": None})
    doc["campaign"]["perturbation"]["design"] = "none"
    doc["campaign"]["outputs"].update({"dir": None, "rerun": False})
    flown_config = ExperimentConfig.model_validate(doc)
    trials = []
    for name, path in paths.items():
        folder = out / f"campaign-{name}"
        summary = run_campaign(flown_config, out_dir=folder, config_dir=config_dir, path=path, progress=not quiet,
                               evaluator=evaluator or DEFAULT_EVALUATOR)
        if not quiet:
            print(f"{name}: {summary.done} trials in {folder} ({summary.failed} failed)")
        trials.append(read_trials(name, folder))
    seed = config.campaign.seed if config.campaign.seed is not None else config.run.seed
    result = summarise(trials, seed, ev.bootstrap, ev.confidence)
    result["wrp"] = {kind: d["table3"] for kind, d in optimised.items()}
    result["common_random_numbers"] = (f"every path flown with campaign seed {seed}: trial k of every path "
                                       "draws the same wind")
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "evaluate.json", result)
    box_plot(trials, out / "boxplot.png")
    if not quiet:
        for row in result["paths"]:
            print(f"{row['path']:8s} mean {row['mean_error_m']:.4f} m  std {row['std_error_m']:.4f}  "
                  f"p95 {row['p95_error_m']:.4f}  failed {100 * row['failure_rate']:.1f} %")
        for row in result["paired"]:
            ci = row["mean_error_diff_ci"]
            print(f"{row['path']} - initial: mean error {row['mean_error_diff_m']:+.4f} m "
                  + (f"[{ci[0]:+.4f}, {ci[1]:+.4f}]" if ci else "") + f" over {row['both_succeeded']} pairs, "
                  f"failure rate {100 * row['failure_rate_diff']:+.1f} points")
    return result


def _evaluate(args: argparse.Namespace) -> int:
    from wrp_eval.config import load_experiment
    config = load_experiment(args.config)
    out = Path(args.out or config.wrp.evaluate.out_dir or Path("logs") / config.run.name / "evaluate")
    if args.trials is not None and args.trials < 2:
        raise InputError("--trials", f"need at least 2 trials, got {args.trials}")
    run_evaluate(config, Path(args.config).parent, out, n_trials=args.trials, checkpoint=args.checkpoint,
                 campaign=args.campaign, e_original=args.e_original, quiet=args.quiet)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser("evaluate", help="fly the initial path, ISWRP and SWRP under the same winds; "
                                        "Tables 4/5 analogues", description=EVALUATE_DOC,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("config", metavar="CONFIG")
    e.add_argument("--trials", type=int, default=None, help="trials per path (overrides wrp.evaluate.n_trials)")
    e.add_argument("--out", default=None, help="output folder (default wrp.evaluate.out_dir or "
                                               "logs/<run.name>/evaluate)")
    e.add_argument("--checkpoint", default=None)
    e.add_argument("--campaign", default=None, help="campaign folder for the initial path and r_s")
    e.add_argument("--e-original", type=float, default=None, help="E_original in m (default: the oracle)")
    e.add_argument("--quiet", action="store_true")
    e.set_defaults(func=_evaluate)

    p = sub.add_parser("optimize", help="wind-resistance path (ISWRP/SWRP, paper Alg. 3/4) from a surrogate",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config", metavar="CONFIG")
    p.add_argument("--kind", choices=("iswrp", "swrp"), default=None, help="overrides wrp.kind")
    p.add_argument("--threshold", type=float, default=None, help="t in metres of error (overrides wrp.threshold_m)")
    p.add_argument("--out", default=None, help="output folder (default wrp.out_dir or logs/<run.name>/wrp-<kind>)")
    p.add_argument("--checkpoint", default=None, help="surrogate checkpoint (overrides wrp.checkpoint)")
    p.add_argument("--campaign", default=None, help="campaign folder for the path and r_s")
    p.add_argument("--e-original", type=float, default=None, help="E_original in m (default: the oracle)")
    p.add_argument("--no-oracle", action="store_true", help="do not score the WRP with the oracle")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=_optimize)
