"""Run a ``study:`` config: every variant of the base config through the stages it needs, one table.

Per variant: ship -> plan -> [campaign -> surrogate -> ISWRP/SWRP] -> [random viewpoint offsets] -> oracle.
The stages are called through their public functions (``plan``, ``run_campaign``,
``train_from_campaign``, ``run_optimize``, ``oracle_error``), never re-implemented. Variants whose
ship / planning / wind / sim / campaign / oracle / surrogate sections and seed are equal share one campaign and
one surrogate (Table 3's six WRPs are optimised against the same surrogate, as in the paper).

Outputs under ``logs/<run.name>/``: ``study/<variant>/`` (path.json per path, wrp metrics, ship.rrd + plan.rrd),
``study/shared-<key>/`` (campaign, surrogate), ``study.json`` (every row, ours and the paper's), ``report.md`` and
``run.rrd`` (one rerun recording per variant, id ``<run>/<variant>``: ship, plan, and the WRP or offset paths under
``paths/<name>``).
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import logging
import re
import time
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from wrp_eval.atomic import write_json_atomic
from wrp_eval.campaign.runner import run_campaign
from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import KIND_TRANSITION, FlightPath
from wrp_eval.planning.rerun_log import save_plan_recording
from wrp_eval.recording import merge_recordings
from wrp_eval.schema import parse_model
from wrp_eval.ship.rerun_log import save_ship_recording
from wrp_eval.study.config import StudySection
from wrp_eval.study.report import write_study_report
from wrp_eval.surrogate.train import CHECKPOINT_NAME, train_from_campaign
from wrp_eval.wrp.config import WrpSection
from wrp_eval.wrp.jobs import oracle_error, resolve_inputs, run_optimize
from wrp_eval.wrp.optimize import Table3Row, apply_offsets, offset_totals

log = logging.getLogger(__name__)

# the offsets stream of the study's random viewpoint offsets (SeedSequence([seed, STREAM, crc(name), rep]))
OFFSETS_STREAM = 9_001
TRAINING_SECTIONS = ("ship", "planning", "wind", "sim", "campaign", "oracle", "surrogate")


def deep_merge(base: dict, update: dict) -> dict:
    """A copy of ``base`` with ``update`` merged in: mappings merge key by key, anything else replaces."""
    out = copy.deepcopy(base)
    for key, value in update.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def slug(name: str) -> str:
    """A folder name for a variant name (letters, digits, ._- kept; the rest becomes '_')."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_") or "variant"


def study_section(config: ExperimentConfig) -> StudySection:
    """The config's ``study:`` section (an InputError without one)."""
    if config.study is None:
        raise InputError("study", "the config has no study: section")
    return config.study


def base_document(config: ExperimentConfig, smallest: bool) -> dict:
    """The base config as a document (only the keys the file set, so that section defaults keep their meaning,
    e.g. ``ship.type`` given or not), without the study, with the study's ``smallest`` overrides if asked."""
    doc = config.model_dump(mode="json", exclude_unset=True)
    doc.pop("study", None)
    if smallest:
        study = study_section(config)
        doc = deep_merge(doc, study.smallest)
        if "name" not in study.smallest.get("run", {}):
            doc.setdefault("run", {})["name"] = f"{config.run.name}-smallest"
    return doc


def variant_configs(config: ExperimentConfig, source: str, smallest: bool = False) -> list:
    """[(variant, ExperimentConfig)] for the variants to run; every one validated before anything runs."""
    base = base_document(config, smallest)
    study = study_section(config)
    variants = list(study.variants)
    if smallest and study.smallest_variants:
        variants = variants[:study.smallest_variants]
    return [(v, parse_model(ExperimentConfig, deep_merge(base, v.overrides), f"{source} study variant {v.name!r}"))
            for v in variants]


def random_offsets(n_views: int, position_half_width_m: float, yaw_half_width_rad: float,
                   rng: np.random.Generator) -> np.ndarray:
    """(n_views, 4) offsets (dx, dy, dz m, dyaw rad), each uniform in its +-half width."""
    half = np.array([position_half_width_m] * 3 + [yaw_half_width_rad])
    return rng.uniform(-1.0, 1.0, size=(n_views, 4)) * half


def training_key(config: ExperimentConfig) -> str:
    """Variants with the same key share one campaign and one surrogate."""
    doc = {k: config.model_dump(mode="json")[k] for k in TRAINING_SECTIONS}
    doc["seed"] = config.run.seed
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:10]


def _train(ctx: ExperimentContext, path: FlightPath, folder: Path) -> dict:
    """Campaign of ``path`` + surrogate; returns {campaign, checkpoint, trials, failed, surrogate test metrics}."""
    campaign_dir, surrogate_dir = folder / "campaign", folder / "surrogate"
    start = time.perf_counter()
    trial = ctx.trial_config
    camp = run_campaign(trial, path, campaign_dir, root_seed=ctx.campaign_seed, config_dir=ctx.config_dir,
                        ship_mesh=ctx.ship.mesh if trial.campaign.outputs.rerun else None)
    campaign_s = time.perf_counter() - start
    trained, _, _ = train_from_campaign(ctx, campaign_dir, surrogate_dir)
    return {"campaign": str(campaign_dir), "checkpoint": str(surrogate_dir / CHECKPOINT_NAME), "trials": camp.done,
            "failed": camp.failed, "campaign_s": campaign_s,
            "surrogate_s": time.perf_counter() - start - campaign_s, "surrogate_test": trained.metrics["test"]}


def _plan_columns(ship, result, path, section) -> dict:
    m, t = result.metrics, result.metrics.get("timings", {})
    oblique = m.get("method") == "oblique"
    return {"method": m.get("method"), "proxy_height_m": float(ship.proxy.height_m),
            "height_disturbance_m": float(ship.proxy.height_m - ship.particulars.height_above_water_m),
            "H": m.get("H"), "R": m.get("R"), "min_s": t.get("min_s"), "max_s": t.get("max_s"),
            "minmax_s": (t["min_s"] + t["max_s"]) if "min_s" in t and "max_s" in t else None,
            "tsp_s": t.get("tsp_s"), "plan_s": t.get("total_s"),
            "pitch_deg": section.oblique_pitch_deg if oblique else None,
            "front_overlap": section.front_overlap if oblique else None,
            "side_overlap": section.side_overlap if oblique else None}


def _path_columns(path, verdict: dict) -> dict:
    views, adopted = len(path), int(verdict.get("registered_views", 0))
    return {"views": views, "adopted": adopted, "images_adopted": f"{views}/{adopted}",
            "transition_views": int(np.sum(np.asarray(path.kind) == KIND_TRANSITION)), "length_m": path.length_m,
            "flight_time_s": path.flight_time_s, "error_m": verdict.get("error_m"),
            "failed": bool(verdict.get("failed")), "reason": verdict.get("reason", ""),
            "completeness": verdict.get("completeness"), "fscore": verdict.get("fscore")}


def run_study(ctx: ExperimentContext, *, smallest: bool = False) -> dict:
    """Every variant of ``ctx.config.study``; writes study.json and report.md under logs/<run.name>/ and returns
    the study document."""
    config = ctx.config
    study = study_section(config)
    built = [(v, ctx.with_config(cfg)) for v, cfg in variant_configs(config, ctx.source, smallest)]
    run_name = built[0][1].config.run.name
    out = built[0][1].folders.root
    built[0][1].folders.study.mkdir(parents=True, exist_ok=True)
    job_start = time.perf_counter()
    shared: dict[str, dict] = {}
    optimised: dict[tuple, tuple] = {}
    rows, figures, timings, recordings = [], [], {}, []
    for number, (variant, vctx) in enumerate(built, 1):
        start = time.perf_counter()
        log.info(f"[wrp-eval run] study {number}/{len(built)}: {variant.name} ...")
        folder = vctx.folders.study / slug(variant.name)
        for _, earlier in built[:number - 1]:
            vctx.reuse_from(earlier)
        ship, result = vctx.ship, vctx.planned
        path = dataclasses.replace(result.path, metadata={**result.path.metadata, "variant": variant.name})
        path.save(folder / "plan" / "path.json")
        write_json_atomic(folder / "plan" / "plan_metrics.json", result.metrics)
        measured, verdict = path, None
        wrp_cols: dict = {}
        if variant.path != "plan":
            measured, verdict, wrp_cols = _optimised_variant(vctx, variant, path, folder, shared, optimised)
        shown = {variant.path: measured} if variant.path != "plan" else {}   # paths drawn beside the plan
        base_cols = _plan_columns(ship, result, path, vctx.config.planning)
        rows += _variant_rows(vctx, variant, study.random_offsets, measured, verdict, base_cols, wrp_cols, folder,
                              shown)
        if study.figures:
            figures.append((variant.name, measured, ship, folder))
        # one rerun recording per variant (its own recording id): ship, plan, and the WRP / offset paths
        recording_id = f"{run_name}/{variant.name}"
        save_ship_recording(ship, folder / "ship.rrd", recording_id=recording_id)
        save_plan_recording(result, ship.proxy, folder / "plan.rrd", recording_id=recording_id, other_paths=shown)
        recordings += [folder / "ship.rrd", folder / "plan.rrd"]
        timings[variant.name] = time.perf_counter() - start
        log.info(f"[wrp-eval run] study {number}/{len(built)}: {variant.name}: done in {timings[variant.name]:.1f} s")
    timings["total"] = time.perf_counter() - job_start
    box = study.random_offsets
    doc: dict[str, Any] = {"config": ctx.source, "run": run_name, "seed": config.run.seed, "smallest": smallest,
                           "table": study.table, "title": study.title, "columns": study.columns, "rows": rows,
                           "random_offsets": {"position_half_width_m": box.position_half_width_m,
                                              "yaw_half_width_deg": box.yaw_half_width_deg},
                           "shared_training": shared, "timings_s": timings}
    write_json_atomic(out / "study.json", doc)
    merge_recordings(recordings, built[0][1].folders.recording)
    report = write_study_report(out, doc, figures)
    doc["timings_s"]["total"] = time.perf_counter() - job_start
    write_json_atomic(out / "study.json", doc)
    return {**doc, "out": str(out), "report": str(report)}


def _optimised_variant(vctx: ExperimentContext, variant, path: FlightPath, folder: Path, shared: dict,
                       optimised: dict) -> tuple[FlightPath, dict | None, dict]:
    """The WRP of ``variant`` (its training shared through ``shared`` by training key, its optimisation through
    ``optimised`` by section): (the optimised path, the optimiser's oracle verdict, the WRP's table columns)."""
    cfg = vctx.config
    key = training_key(cfg)
    if key not in shared:
        shared[key] = _train(vctx, path, vctx.folders.study / f"shared-{key}")
    training = shared[key]
    section = WrpSection.model_validate({**cfg.wrp.model_dump(), "kind": variant.path})
    wrp_key = (key, json.dumps(section.model_dump(mode="json"), sort_keys=True))
    if wrp_key not in optimised:   # e.g. Table 5's SWRP row and its offset rows: one optimisation
        wrp_dir = folder / f"wrp-{variant.path}"
        inputs = resolve_inputs(vctx, section, training["checkpoint"], training["campaign"])
        optimised[wrp_key] = (run_optimize(vctx, section, wrp_dir, inputs), wrp_dir)
    doc, wrp_dir = optimised[wrp_key]
    table = Table3Row.from_json_dict(doc["table3"])
    cols = {"threshold_m": table.threshold_m, "offset_rate_pct": table.offset_rate_pct,
            "position_offset_m": table.position_offset_m, "rotation_offset_deg": table.rotation_offset_deg,
            "wrp_time_s": table.time_s, "surrogate_error_m": table.surrogate_error_m,
            "e_original_m": table.e_original_m}
    return FlightPath.load(wrp_dir / "path.json"), table.oracle, cols


def _variant_rows(vctx: ExperimentContext, variant, box, measured: FlightPath, verdict: dict | None,
                  base_cols: dict, wrp_cols: dict, folder: Path, shown: dict) -> list[dict]:
    """The table rows of ``variant``: one per repetition, each with its random offsets when the variant has them
    (the study's ``box``, else the campaign's perturbation box; their paths saved under ``folder`` and added to
    ``shown``); a row's columns are the plan's (``base_cols``),
    the flown path's, then the WRP's or the offsets' (``wrp_cols``)."""
    cfg = vctx.config
    pert = cfg.campaign.perturbation
    half_m = box.position_half_width_m if box.position_half_width_m is not None else pert.position_half_width_m
    half_deg = box.yaw_half_width_deg if box.yaw_half_width_deg is not None else pert.yaw_half_width_deg
    rows = []
    for rep in range(variant.repetitions):
        row_path, row_verdict, cols = measured, verdict, dict(wrp_cols)
        if variant.random_offsets:
            rng = np.random.default_rng(np.random.SeedSequence(
                [cfg.run.seed, OFFSETS_STREAM, zlib.crc32(variant.name.encode()), rep]))
            offsets = random_offsets(len(measured), half_m, np.radians(half_deg), rng)
            row_path = apply_offsets(measured, offsets, {"random_offsets": {"repetition": rep + 1,
                                                                          "position_half_width_m": half_m,
                                                                          "yaw_half_width_deg": half_deg}})
            row_path.save(folder / f"offsets-{rep + 1}" / "path.json")
            shown[f"offsets-{rep + 1}"] = row_path
            cols["position_offset_m"], cols["rotation_offset_deg"] = offset_totals(offsets)
            cols["offset_rate_pct"], cols["wrp_time_s"] = 100.0, None   # random rows: no optimisation time
            cols["offsets_half_width"] = {"position_m": half_m, "yaw_deg": half_deg}
            row_verdict = None
        if row_verdict is None:
            row_verdict = oracle_error(vctx.scored_ship, row_path)   # built at the first row that needs it
        ours = {**base_cols, **_path_columns(row_path, row_verdict), **cols}
        rows.append({"variant": variant.name, "repetition": rep + 1 if variant.random_offsets else None,
                     "path": variant.path, "random_offsets": variant.random_offsets,
                     "overrides": variant.overrides, "ours": ours, "paper": variant.paper_row(rep),
                     "folder": str(folder)})
    return rows
