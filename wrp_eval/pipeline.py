"""``wrp-eval run CONFIG``: the whole job, stage after stage, into ``logs/<run.name>/``.

ship -> plan -> campaign (perturbed flights scored by the oracle) -> surrogate -> ISWRP and SWRP ->
evaluation of the three paths under the same winds -> mission export -> report.md + run.rrd.

Each step calls the stage's own function (the same code as the stage's sub-command) and writes where that
sub-command would, so a step can be re-run or inspected on its own. The campaign steps resume: re-running
the same config reuses the stored trials (same config and seed give the same numbers).
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
import time
from pathlib import Path

from wrp_eval.atomic import write_json_atomic
from wrp_eval.errors import InputError

RUN_RECORDING = "run.rrd"


def merge_recordings(parts: list[Path], target: Path) -> Path:
    """One .rrd of the stage recordings, merged by rerun's own CLI (written atomically)."""
    tmp = target.with_name(target.name + ".tmp")
    cmd = [sys.executable, "-m", "rerun", "rrd", "merge", *map(str, parts), "-o", str(tmp)]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0 or not tmp.is_file():
        raise RuntimeError(f"rerun rrd merge failed: {done.stderr.strip()[-500:]}")
    tmp.replace(target)
    return target


class Step:
    """Prints one line per step with its wall time (the job's progress on a terminal and in CI logs)."""

    def __init__(self, timings: dict, name: str, what: str):
        self.timings, self.name, self.what = timings, name, what

    def __enter__(self):
        print(f"[wrp-eval run] {self.name}: {self.what} ...", flush=True)
        self.start = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.timings[self.name] = time.perf_counter() - self.start
        if exc[0] is None:
            print(f"[wrp-eval run] {self.name}: done in {self.timings[self.name]:.1f} s", flush=True)
        return False


def run_pipeline(config_path: Path, *, quiet: bool = True, smallest: bool = False) -> dict:
    """Run every stage of the config at ``config_path``; returns the run summary (also run_summary.json).

    A config with a ``study:`` section runs its variants instead (:mod:`wrp_eval.study.runner`: each variant
    through the stages it needs) and returns the study document; ``smallest`` applies the study's
    ``smallest`` overrides (the tests' setting)."""
    from wrp_eval.campaign.rerun_log import campaign_recording_id
    from wrp_eval.campaign.runner import run_campaign
    from wrp_eval.config import load_experiment
    from wrp_eval.export.formats import FORMATS, export_path
    from wrp_eval.planning.commands import planning_rng
    from wrp_eval.planning.path import Path as FlightPath
    from wrp_eval.planning.planner import plan
    from wrp_eval.planning.rerun_log import save_plan_recording
    from wrp_eval.report import write_report
    from wrp_eval.ship.commands import ship_report
    from wrp_eval.ship.resolve import resolve_ship_full
    from wrp_eval.ship.rerun_log import save_ship_recording
    from wrp_eval.surrogate.train import train_from_campaign
    from wrp_eval.wrp.commands import run_evaluate

    config = load_experiment(config_path)
    if config.study is not None:
        from wrp_eval.study.runner import run_study
        return run_study(config, config_path, smallest=smallest, quiet=quiet)
    if smallest:
        raise InputError(config_path, "--smallest needs a study: section (it applies study.smallest)")
    config_dir = config_path.parent
    # the stages' own defaults put their outputs under logs/<run.name>/...; the pipeline relies on them
    out = Path("logs") / config.run.name
    out.mkdir(parents=True, exist_ok=True)
    timings: dict[str, float] = {}
    summary: dict = {"config": str(config_path), "seed": config.run.seed, "out": str(out)}
    job_start = time.perf_counter()

    with Step(timings, "ship", "particulars, proxy, mesh, surface complexity"):
        ship = resolve_ship_full(config.ship, config_dir, str(config_path))
        write_json_atomic(out / "ship.json", ship_report(ship))

    with Step(timings, "plan", f"{config.planning.method} reconstruction path (paper Sec. 3)"):
        result = plan(ship.proxy, ship.complexity.complexity, config.planning, planning_rng(config.run.seed))
        path = dataclasses.replace(result.path, metadata={**result.path.metadata, "config": str(config_path),
                                                          "seed": config.run.seed})
        path.save(out / "plan" / "path.json")
        write_json_atomic(out / "plan" / "plan_metrics.json", result.metrics)
        # one recording id for the run's parts, so that run.rrd merges them into one recording
        recording_id = campaign_recording_id(path.to_json_dict())
        save_ship_recording(ship, out / "ship.rrd", recording_id=recording_id)
        save_plan_recording(result, ship.proxy, out / "plan.rrd", recording_id=recording_id)
        summary["plan"] = result.metrics

    campaign_dir = Path(config.campaign.outputs.dir or out / "campaign")
    with Step(timings, "campaign", f"{config.campaign.n_trials} perturbed flights scored by the "
                                   f"{config.campaign.oracle} oracle"):
        camp = run_campaign(config, out_dir=campaign_dir, config_dir=config_dir, path=path, progress=not quiet)
        summary["campaign"] = {"dir": str(campaign_dir), "trials": camp.done, "failed": camp.failed,
                               "trials_per_min": camp.trials_per_min}

    surrogate_dir = Path(config.surrogate.out_dir or out / "surrogate")
    with Step(timings, "surrogate", "train the CNN surrogate on the campaign"):
        trained, _, _ = train_from_campaign(config, campaign_dir, surrogate_dir, progress=not quiet)
        summary["surrogate"] = trained.metrics["test"]

    evaluate_dir = Path(config.wrp.evaluate.out_dir or out / "evaluate")
    with Step(timings, "wrp", "ISWRP and SWRP, then the three paths flown under the same winds"):
        evaluation = run_evaluate(config, config_dir, evaluate_dir, checkpoint=str(surrogate_dir / "surrogate.pt"),
                                  campaign=str(campaign_dir), quiet=quiet)
        summary["evaluate"] = evaluation

    with Step(timings, "export", "missions of the three paths"):
        missions = {}
        paths = {"initial": out / "plan" / "path.json", "iswrp": evaluate_dir / "wrp-iswrp" / "path.json",
                 "swrp": evaluate_dir / "wrp-swrp" / "path.json"}
        for name, file in paths.items():
            flight_path = FlightPath.load(file)
            for fmt, spec in FORMATS.items():
                written = export_path(flight_path, ship.particulars, ship.proxy, fmt,
                                      out / "missions" / f"{name}{spec.suffix}", config.export, str(file))
                missions.setdefault(name, []).extend(str(f) for f, _ in written)
        summary["missions"] = missions

    with Step(timings, "report", "report.md, figures and run.rrd"):
        parts = [out / "ship.rrd", out / "plan.rrd"]
        if (campaign_dir / "campaign.rrd").is_file():
            parts.append(campaign_dir / "campaign.rrd")
        merge_recordings(parts, out / RUN_RECORDING)
        timings["total"] = time.perf_counter() - job_start
        summary["timings_s"] = timings
        report = write_report(out, config, ship, path, summary)
    timings["total"] = time.perf_counter() - job_start
    write_json_atomic(out / "run_summary.json", summary)
    summary["report"] = str(report)
    return summary


def _cmd_run(args: argparse.Namespace) -> int:
    config_path = Path(args.config)
    if not config_path.is_file():
        raise InputError(config_path, "no such config file")
    summary = run_pipeline(config_path, quiet=not args.progress, smallest=args.smallest)
    out = Path(summary["out"])
    print(f"\nwrp-eval run finished in {summary['timings_s']['total']:.0f} s.")
    print(f"Report:    {summary['report']}")
    if "rows" in summary:   # a study: a table, and one recording per variant
        print(f"Table:     {out / 'study.json'}  (the rows as JSON; per-variant paths under {out / 'study'})")
    print(f"Recording: {out / RUN_RECORDING}  (open it with: rerun {out / RUN_RECORDING})")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="the whole job: plan, campaign, surrogate, ISWRP/SWRP, evaluation, "
                                   "export, report", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config", help="experiment YAML (e.g. experiments/quickstart.yaml)")
    p.add_argument("--progress", action="store_true", help="show the stages' own progress bars and lines")
    p.add_argument("--smallest", action="store_true", help="a study config (experiments/paper/): its smallest "
                                                           "setting (study.smallest), as the tests run it")
    p.set_defaults(func=_cmd_run)

