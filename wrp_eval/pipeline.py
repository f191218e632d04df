"""The whole job of ``wrp-eval run CONFIG``, stage after stage, into ``logs/<run.name>/``.

ship -> plan -> campaign (perturbed flights scored by the oracle) -> surrogate -> ISWRP and SWRP ->
evaluation of the three paths under the same winds -> the wind envelope of the recommended path
(``envelope.run_grid``) -> mission export -> what each capture error costs the campaign's flights
(error_sources.json) -> report.md (opening with the envelope's go / no-go) + run.rrd.

Each step calls the stage's own function (the same code as the stage's sub-command) and writes where that
sub-command would, so a step can be re-run or inspected on its own. The campaign steps resume: re-running
the same config reuses the stored trials (same config and seed give the same numbers).
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace
from pathlib import Path

from wrp_eval.atomic import write_json_atomic
from wrp_eval.campaign.jobs import campaign_job
from wrp_eval.campaign.rerun_log import campaign_recording_id
from wrp_eval.envelope.jobs import envelope_job
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.export.formats import FORMATS, export_path
from wrp_eval.export.mission import FlightStyle
from wrp_eval.planning.path import FlightPath
from wrp_eval.planning.rerun_log import save_plan_recording
from wrp_eval.recording import merge_recordings
from wrp_eval.report import write_report
from wrp_eval.run_summary import CampaignRun, EnvelopeRun, RunSummary, SurrogateFit
from wrp_eval.ship.rerun_log import save_ship_recording
from wrp_eval.study.runner import run_study
from wrp_eval.surrogate.train import CHECKPOINT_NAME, train_from_campaign
from wrp_eval.wrp.jobs import evaluate_job
from wrp_eval.wrp.risk import campaign_flown_offsets, save_risk_recording, view_risk
from wrp_eval.wrp.robust import campaign_error_sources

log = logging.getLogger(__name__)


class Step:
    """Prints one line per step with its wall time (the job's progress on a terminal and in CI logs)."""

    def __init__(self, timings: dict, name: str, what: str):
        self.timings, self.name, self.what = timings, name, what

    def __enter__(self):
        log.info(f"[wrp-eval run] {self.name}: {self.what} ...")
        self.start = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.timings[self.name] = time.perf_counter() - self.start
        if exc[0] is None:
            log.info(f"[wrp-eval run] {self.name}: done in {self.timings[self.name]:.1f} s")
        return False


def run_pipeline(ctx: ExperimentContext, *, smallest: bool = False) -> RunSummary | dict:
    """Run every stage of the experiment; returns the :class:`RunSummary` (also run_summary.json).

    A config with a ``study:`` section runs its variants instead (:mod:`wrp_eval.study.runner`: each variant
    through the stages it needs) and returns the study document; ``smallest`` applies the study's
    ``smallest`` overrides (the tests' setting). The campaign table is read once (by the surrogate's training,
    whose trials the WRP and the report reuse) and the surrogate is trained once and used as trained."""
    config = ctx.config
    if config.study is not None:
        return run_study(ctx, smallest=smallest)
    if smallest:
        raise InputError(ctx.source, "--smallest needs a study: section (it applies study.smallest)")
    out = ctx.folders.root
    out.mkdir(parents=True, exist_ok=True)
    timings: dict[str, float] = {}
    summary: dict = {"config": ctx.source, "seed": ctx.run_seed, "out": str(out)}
    job_start = time.perf_counter()
    path = _ship_and_plan(ctx, summary, timings)
    trials, envelope = _flights(ctx, path, summary, timings)
    with Step(timings, "export", "missions of the initial path and of every path the evaluation built"):
        summary["missions"] = export_missions(ctx)
    with Step(timings, "error sources", "the campaign's flights re-scored without each capture error"):
        sources = campaign_error_sources(ctx.folders.campaign, ctx.config.wrp.robust.screen_flights, ctx.run_seed,
                                         ctx.config_dir)
        write_json_atomic(out / "error_sources.json", sources)
    with Step(timings, "report", "report.md, figures and run.rrd"):
        risk = _risk_and_recording(ctx, path, summary, envelope is not None)
        timings["total"] = time.perf_counter() - job_start
        run = RunSummary(**summary, timings_s=timings)
        report = write_report(ctx, path, run, trials, risk, envelope, sources)
    timings["total"] = time.perf_counter() - job_start
    write_json_atomic(out / "run_summary.json", run.to_json_dict())
    return replace(run, report=str(report))


def _ship_and_plan(ctx: ExperimentContext, summary: dict, timings: dict) -> FlightPath:
    """The ship and the planned path, with their files and recordings; returns the path."""
    out, folders = ctx.folders.root, ctx.folders
    with Step(timings, "ship", "particulars, proxy, mesh, surface complexity"):
        ship = ctx.ship
        write_json_atomic(out / "ship.json", ship.report())
    with Step(timings, "plan", f"{ctx.config.planning.method} reconstruction path (paper Sec. 3)"):
        result = ctx.planned
        path = result.path
        path.save(folders.plan / "path.json")
        write_json_atomic(folders.plan / "plan_metrics.json", result.metrics)
        # one recording id for the run's parts, so that run.rrd merges them into one recording
        recording_id = campaign_recording_id(path)
        save_ship_recording(ship, out / "ship.rrd", recording_id=recording_id)
        save_plan_recording(result, ship.proxy, out / "plan.rrd", recording_id=recording_id)
        summary["plan"] = result.metrics
    return path


def _flights(ctx: ExperimentContext, path: FlightPath, summary: dict, timings: dict):
    """Campaign, surrogate, ISWRP / SWRP with their evaluation, and the envelope of the recommended path;
    returns (the campaign's trials, the envelope or None)."""
    config, folders = ctx.config, ctx.folders
    campaign_dir = folders.campaign
    with Step(timings, "campaign", f"{config.campaign.n_trials} perturbed flights scored by the "
                                   f"{config.campaign.oracle} oracle"):
        camp = campaign_job(ctx, out_dir=campaign_dir, path=path)
        summary["campaign"] = CampaignRun(str(campaign_dir), camp.done, camp.failed, camp.trials_per_min,
                                          camp.stress_note)
    with Step(timings, "surrogate", "train the CNN surrogate on the campaign"):
        trained, trials, _ = train_from_campaign(ctx, campaign_dir, folders.surrogate)
        summary["surrogate"] = SurrogateFit.of(trained.metrics["test"], trained.metrics.get("physical_variance_share"))
    with Step(timings, "wrp", "ISWRP and SWRP, then the three paths flown under the same winds"):
        summary["evaluate"] = evaluate_job(ctx, folders.evaluate, checkpoint=folders.surrogate / CHECKPOINT_NAME,
                                           campaign=campaign_dir, surrogate=trained.surrogate,
                                           trials=trials, forecast=config.envelope.run_grid is None)
        evaluation = summary["evaluate"]
        if camp.stress_note and evaluation.forecast is not None:
            notes = (f"**Stress test**: {camp.stress_note}.", "")
            summary["evaluate"] = replace(evaluation, forecast=replace(evaluation.forecast, stress_notes=notes))
    return trials, _envelope(ctx, path, summary, timings)


def _envelope(ctx: ExperimentContext, path: FlightPath, summary: dict, timings: dict):
    """The wind envelope of the recommended path on ``envelope.run_grid`` (None when that is off)."""
    grid = ctx.config.envelope.run_grid
    summary["envelope"] = None
    if grid is None:
        return None
    chosen = summary["evaluate"].recommended_path
    with Step(timings, "envelope", f"wind envelope of the {chosen} path ({grid.directions} directions, "
                                   f"U10 up to {grid.speeds_m_s[-1]:g} m/s)"):
        fly = path if chosen == "initial" else FlightPath.load(ctx.folders.evaluated_wrp(chosen) / "path.json")
        job = envelope_job(ctx, grid, path=fly)
        summary["envelope"] = EnvelopeRun(chosen, job.envelope.go, job.files,
                                          {b.direction: b.boundary_m_s for b in job.envelope.boundaries},
                                          job.envelope.flights_total)
    return job.envelope


def _risk_and_recording(ctx: ExperimentContext, path: FlightPath, summary: dict, with_envelope: bool):
    """The per-view risk map (risk.rrd and the summary) and the run's merged recording; returns the risk."""
    out, folders, campaign_dir = ctx.folders.root, ctx.folders, ctx.folders.campaign
    risk = view_risk(ctx.scored_ship, path, campaign_flown_offsets(campaign_dir))
    save_risk_recording(path, risk, out / "risk.rrd", recording_id=campaign_recording_id(path))
    parts = [out / "ship.rrd", out / "plan.rrd", out / "risk.rrd"]
    if with_envelope:
        parts.append(folders.envelope / "envelope.rrd")
    if (campaign_dir / "campaign.rrd").is_file():
        parts.append(campaign_dir / "campaign.rrd")
    merge_recordings(parts, folders.recording)
    summary["view_risk"] = {"risk_m": risk.risk_m.tolist(), "p_missed": risk.p_missed.tolist(),
                            "loss_m": risk.loss_m.tolist(), "base_error_m": risk.base_error_m}
    return risk


def export_missions(ctx: ExperimentContext) -> dict[str, list[str]]:
    """Every format's missions of the initial path and of every path the evaluation built (the ISWRP and SWRP of
    ``wrp.evaluate.kinds``, and the robust, reversed, stops and slow-legs paths where it built them: any of them
    may be the one it recommends) into the run's missions folder; returns path name -> files written."""
    folders, ship, ev = ctx.folders, ctx.ship, ctx.config.wrp.evaluate
    levers = [name for name, on in (("robust", ev.robust), ("reversed", ev.direction), ("stops", ev.capture_stops),
                                    ("slow-legs", ev.slow_legs)) if on]
    files: dict[str, Path] = {"initial": folders.plan / "path.json",
                              **{kind: folders.evaluated_wrp(kind) / "path.json" for kind in ev.kinds},
                              **{name: folders.evaluated_wrp(name) / "path.json" for name in levers
                                 if (folders.evaluated_wrp(name) / "path.json").is_file()}}   # none: changed nothing
    missions: dict[str, list[str]] = {}
    for name, file in files.items():
        flight_path = FlightPath.load(file)
        style = FlightStyle.of(flight_path, ctx.config.sim.capture, ctx.config.sim.dwell_s)   # as simulated
        for fmt, spec in FORMATS.items():
            written = export_path(flight_path, ship.particulars, ship.proxy, fmt,
                                  folders.missions / f"{name}{spec.suffix}", ctx.config.export, str(file), style)
            missions.setdefault(name, []).extend(str(f) for f, _ in written)
    return missions
