"""The WRP jobs of an experiment: optimise a wind-resistance path (ISWRP / SWRP, paper Alg. 3/4) from a trained
surrogate, and evaluate the initial path and both WRPs under the same winds.

``optimize`` writes <out>/path.json (the WRP) and <out>/wrp_metrics.json (the paper's Table 3 columns: offset
rate, total position / rotation offset, time, and the WRP's error from the ORACLE; plus the surrogate's figures,
per-viewpoint offsets and where E_original and r_s came from). ``evaluate`` optimises both kinds, then flies the
three paths as campaigns with the same seed (common random numbers, viewpoints as planned) into
<out>/evaluate.json and <out>/boxplot.png.

The inputs (path, surrogate, campaign trials for r_s) are resolved once per job (:func:`resolve_inputs`) and
shared by both optimisations of ``evaluate``; a caller that holds them already (``wrp-eval run``) passes them.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from wrp_eval.atomic import write_json_atomic
from wrp_eval.campaign.evaluators import DEFAULT_EVALUATOR
from wrp_eval.campaign.runner import run_campaign
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext, evaluated_campaign_dir, evaluated_wrp_dir
from wrp_eval.logs import progress_log
from wrp_eval.planning.path import FlightPath, digest_of_document
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recon.scored_ship import ScoredShip
from wrp_eval.ship.nofly import flyable
from wrp_eval.sim.capture_mode import FLY_THROUGH
from wrp_eval.sim.onboard import view_depths
from wrp_eval.surrogate.data import TrialData, load_campaign_trials
from wrp_eval.surrogate.model import Surrogate
from wrp_eval.surrogate.scarce import ship_scarce_coverage
from wrp_eval.wrp.capture_lever import (
    blurred_views,
    capture_lever_paths,
    held_out_blur,
    legs_at,
    slow_leg_paths,
)
from wrp_eval.wrp.config import WrpSection
from wrp_eval.wrp.confirm import CONFIRM_ROUNDS, confirm_moves
from wrp_eval.wrp.direction import direction_placebos
from wrp_eval.wrp.evaluate import PathTrials, box_plot, forecast_verdict, read_trials, summarise
from wrp_eval.wrp.evaluation import EvaluationResult, PlaceboControl
from wrp_eval.wrp.optimize import (
    Table3Row,
    WrpParams,
    WrpResult,
    apply_offsets,
    interval_optimise,
    offset_cholesky,
    sample_radii,
)
from wrp_eval.wrp.placebo import placebo_offsets
from wrp_eval.wrp.robust import robust_job, robust_placebo_paths

EVALUATED_PATHS = ("initial", "iswrp", "swrp")
WRP_KINDS = EVALUATED_PATHS[1:]


@dataclass(frozen=True)
class WrpInputs:
    """What an optimisation starts from: the path, its surrogate, the campaign folder it was trained on, and the
    per-viewpoint neighbourhood radii r_s (n,) m with a line saying where they came from."""

    path: FlightPath
    surrogate: Surrogate | None     # None: an evaluation of the initial path and flown levers only
    campaign_dir: Path
    radius_m: np.ndarray
    radius_source: str
    neighbour_cholesky: np.ndarray | None = None   # (n, 3, 3) m: the measured neighbourhoods, when a campaign is


def oracle_error(ship: ScoredShip, path: FlightPath) -> dict:
    """The oracle's verdict (JSON dict) on the path flown exactly as planned (no wind): capture poses =
    viewpoints, oracle seed 0."""
    return ship.score(captures_from_path(path), seed=0).to_json_dict()


def resolve_inputs(ctx: ExperimentContext, section: WrpSection, checkpoint: str | Path | None = None,
                   campaign: str | Path | None = None, *, surrogate: Surrogate | None = None,
                   trials: TrialData | None = None, need_surrogate: bool = True) -> WrpInputs:
    """The :class:`WrpInputs` of ``section``: the path of the campaign folder (or ``wrp.path``), the checkpoint
    (or the ``surrogate`` already loaded; none read when not ``need_surrogate``), r_s from the campaign's trials
    (or the ``trials`` already read)."""
    camp = Path(campaign or section.campaign_dir or ctx.training_campaign_dir)
    path_file = Path(section.path) if section.path else camp / "path.json"
    path = FlightPath.load(path_file)
    digests = {path.digest()}
    try:   # the campaign hashes the document it stored; hash the file's own document too
        digests.add(digest_of_document(json.loads(path_file.read_text())))
    except (KeyError, TypeError, ValueError):
        pass
    if surrogate is None and need_surrogate:
        ckpt = Path(checkpoint or section.checkpoint or ctx.folders.surrogate / "surrogate.pt")
        surrogate = Surrogate.load(ckpt, n_views=len(path), path_digest=digests,
                                   inputs=ctx.config.surrogate.inputs,
                                   scarce=lambda: ship_scarce_coverage(ctx.scored_ship, captures_from_path(path)))
    elif surrogate is not None:
        surrogate.check_path(len(path), digests, source="surrogate")
    radius = np.full(len(path), section.sample_radius_m)
    source = f"fixed {section.sample_radius_m} m"
    if trials is None and (section.sample_radius == "campaign" or section.neighbourhood == "measured") \
            and (camp / "campaign.json").is_file():
        trials = load_campaign_trials(camp, views=False)   # only the deviations are read here
    chol = None
    if section.neighbourhood == "measured" and trials is not None and trials.deviation is not None:
        if trials.n_views != len(path):
            raise InputError(camp, f"campaign has {trials.n_views} viewpoints, the path {len(path)}")
        chol = offset_cholesky(trials.deviation)
    if section.sample_radius == "campaign":
        if trials is not None:
            if trials.n_views != len(path):
                raise InputError(camp, f"campaign has {trials.n_views} viewpoints, the path {len(path)}")
            if trials.deviation is None:
                raise InputError(camp, "the trials have no flown - commanded offsets to take r_s from")
            measured = sample_radii(trials.deviation, section.sample_radius_quantile)
            ok = np.isfinite(measured) & (measured > 0)
            radius = np.where(ok, measured, section.sample_radius_m)
            source = (f"campaign {camp}: {section.sample_radius_quantile:g} quantile of |flown - commanded| over "
                      f"{trials.n_trials} trials ({int((~ok).sum())} viewpoints fell back to "
                      f"{section.sample_radius_m} m)")
        else:
            source = f"fixed {section.sample_radius_m} m (no campaign at {camp})"
    if chol is not None and trials is not None:
        source += f"; neighbourhoods: the measured position-offset covariance of {trials.n_trials} trials"
    return WrpInputs(path, surrogate, camp, radius, source, chol)


def safety_constraints(ctx: ExperimentContext, path: FlightPath) -> dict:
    """The planner's flight-safety constraints for moved viewpoints: minimum altitude and the no-fly box."""
    return {"base_positions": np.asarray(path.positions, dtype=float),
            "min_altitude_m": float(ctx.config.planning.min_altitude_m),
            "no_fly_bounds": ctx.flight_proxy.no_fly_bounds()}


def model_of(inputs: WrpInputs) -> Surrogate:
    """The surrogate of ``inputs`` (an optimisation needs one)."""
    if inputs.surrogate is None:
        raise ValueError("an ISWRP / SWRP optimisation needs a surrogate (resolve_inputs(need_surrogate=True))")
    return inputs.surrogate


def step_from_surrogate(surrogate: Surrogate, section: WrpSection) -> float:
    """The position move bound: ``step_m``, else the training offsets' smallest position half-range."""
    if section.step_m is not None:
        return float(section.step_m)
    low, high = surrogate.meta.offset_low, surrogate.meta.offset_high
    if low is None or high is None:
        return float(section.step_fallback_m)
    return float(min(min(-low[k], high[k]) for k in range(3)))


def wind_free_error(ctx: ExperimentContext, inputs: WrpInputs, section: WrpSection,
                    e_original: float | None) -> tuple[float, str]:
    """E_original (m) and where it came from: given, the surrogate at zero offsets, or the oracle."""
    if e_original is not None:
        return float(e_original), "given"
    if section.e_original_m is not None:
        return float(section.e_original_m), "given"
    if section.e_original_source == "surrogate":
        return float(model_of(inputs).predict(np.zeros((1, len(inputs.path), 4)))[0]), "surrogate at zero offsets"
    verdict = oracle_error(ctx.scored_ship, inputs.path)
    if verdict["error_m"] is None:
        raise InputError("wrp", f"the oracle could not score the wind-free path ({verdict['reason']}); "
                                "give wrp.e_original_m")
    return float(verdict["error_m"]), f"oracle ({verdict['oracle']}) on the wind-free path"


def run_optimize(ctx: ExperimentContext, section: WrpSection, out: Path, inputs: WrpInputs, *,
                 e_original: float | None = None, use_oracle: bool = True) -> dict:
    """One ISWRP / SWRP optimisation of ``inputs`` by ``section`` into ``out``; returns wrp_metrics.json."""
    torch.set_num_threads(section.threads)
    path, surrogate = inputs.path, model_of(inputs)
    e0, e0_source = wind_free_error(ctx, inputs, section, e_original)
    threshold = section.threshold_m if section.threshold_m is not None else section.threshold_fraction * e0
    params = wrp_params(ctx, section, inputs, float(threshold), float(e0))
    seed = section.seed if section.seed is not None else ctx.run_seed
    result = interval_optimise(surrogate, params, seed=seed)
    rounds: list[dict] = []
    if params.acceptance == "validated" and result.moved.any() and use_oracle:
        result, rounds = _confirmed(ctx, section, inputs, params, result, seed)
    table = result.table3()
    if rounds:
        table = replace(table, oracle_confirm_s=sum(r["seconds"] for r in rounds))
    wrp_path = apply_offsets(path, result.offsets, {"wrp": {"kind": section.kind, "threshold_m": threshold,
                                                            "seed": seed}})
    if use_oracle and section.oracle_error:
        verdict = oracle_error(ctx.scored_ship, wrp_path)
        table = replace(table, oracle_error_m=verdict["error_m"], oracle=verdict)
    out.mkdir(parents=True, exist_ok=True)
    wrp_path.save(out / "path.json")
    doc = _metrics_doc(table, e0_source, inputs, params, section, seed, rounds, result)
    write_json_atomic(out / "wrp_metrics.json", doc)
    err = table.oracle_error_m
    progress_log.info(f"{section.kind} t={threshold:.4g} m: {table.offset_rate_pct:.1f} % viewpoints moved, "
                      f"position offset {table.position_offset_m:.2f} m, rotation offset "
                      f"{table.rotation_offset_deg:.1f} deg, {table.time_s:.2f} s; error: oracle "
                      + (f"{err:.4f} m" if err is not None else "n/a")
                      + f", surrogate {table.surrogate_error_m:.4f} m (E_original {e0:.4f} m) -> {out}")
    return doc


def wrp_params(ctx: ExperimentContext, section: WrpSection, inputs: WrpInputs, threshold_m: float,
               e_original_m: float) -> WrpParams:
    """The optimiser's parameters: the ``wrp:`` section's, with what the inputs measured (sampling radius,
    step, the surrogate's validated error, the measured neighbourhood) and the planner's flight-safety box."""
    surrogate = model_of(inputs)
    return WrpParams.of(section, threshold_m=threshold_m, e_original_m=e_original_m, sample_radius_m=inputs.radius_m,
                        step_m=step_from_surrogate(surrogate, section), validated_error_m=validated_error(surrogate),
                        neighbour_cholesky=inputs.neighbour_cholesky, **safety_constraints(ctx, inputs.path))


def _confirmed(ctx: ExperimentContext, section: WrpSection, inputs: WrpInputs, params: WrpParams, result, seed: int):
    """Confirm the moves with the oracle, revert the rejected ones, and confirm the rest again against what
    remains (a move confirmed beside one that was then reverted is judged anew), until nothing more is rejected;
    returns (the result, the rounds' documents)."""
    rounds = []
    for _ in range(CONFIRM_ROUNDS):
        confirmation = confirm_moves(ctx.scored_ship, inputs.path, result.offsets, result.moved, params, seed,
                                     section.confirm_samples, forecast_blur(model_of(inputs)))
        rounds.append(confirmation.to_json_dict())
        result = revert(result, confirmation.rejected, model_of(inputs))
        if not confirmation.rejected.any() or not result.moved.any():
            break
    return result, rounds


def _metrics_doc(table: Table3Row, e0_source: str, inputs: WrpInputs, params: WrpParams, section: WrpSection, seed: int,
                 rounds: list[dict], result) -> dict:
    """wrp_metrics.json: the Table 3 row, the settings used and every viewpoint's move."""
    surrogate = model_of(inputs)
    margin = params.improvement_margin_m()
    return {"table3": table.to_json_dict(), "e_original_source": e0_source,
            "sample_radius_source": inputs.radius_source,
            "sample_radius_m": inputs.radius_m.tolist(), "step_m": params.step_m, "seed": seed,
            "yaw_range_deg": section.yaw_range_deg, "iterations": params.iterations,
            "attitude_samples": params.attitude_samples, "neighbourhood_samples": params.neighbourhood_samples,
            "neighbourhood": "measured" if params.neighbour_cholesky is not None else "ball",
            "swrp_spread": params.swrp_spread, "acceptance": params.acceptance,
            "min_improvement_fraction": params.min_improvement_fraction,
            "validated_single_view_error_m": params.validated_error_m,
            "improvement_margin_m": margin if params.acceptance != "paper" and np.isfinite(margin) else None,
            "risk_measure": params.risk_measure,
            "confirmation": rounds or ("not run: moves NOT confirmed by the oracle (no oracle in this run)"
                                       if params.acceptance == "validated" and result.moved.any() else None),
            "surrogate": {"path_digest": surrogate.meta.path_digest, "metrics": surrogate.meta.metrics.get("test")},
            "viewpoints": [{"index": i, "moved": bool(result.moved[i]), "dx_m": float(o[0]), "dy_m": float(o[1]),
                            "dz_m": float(o[2]), "dyaw_deg": float(np.degrees(o[3])),
                            "accepted_iteration": int(result.accepted_iteration[i])}
                           for i, o in enumerate(result.offsets)]}


def validated_error(surrogate: Surrogate) -> float | None:
    """The surrogate's validated single-view error (m): the RMSE of its one-viewpoint changes against the
    jitter-averaged oracle, measured after training (``surrogate.validation_moves``); None if not measured."""
    value = (surrogate.meta.metrics.get("single_view") or {}).get("rmse_m")
    return float(value) if value is not None and np.isfinite(value) else None


def forecast_blur(surrogate: Surrogate) -> np.ndarray | None:
    """(n,) px: the blur the surrogate's forecast expects at each view (None: offsets-only surrogate)."""
    return None if surrogate.views is None else np.asarray(surrogate.views.condition_reference[:, 0], float)


def revert(result: WrpResult, rejected: np.ndarray, surrogate: Surrogate) -> WrpResult:
    """``result`` with the ``rejected`` (n,) viewpoints back at their planned pose (and its predicted error)."""
    if not rejected.any():
        return result
    offsets = np.where(rejected[:, None], 0.0, result.offsets)
    keep = ~rejected
    return replace(result, offsets=offsets, moved=result.moved & keep,
                   accepted_iteration=np.where(keep, result.accepted_iteration, -1),
                   stage1_error=np.where(keep, result.stage1_error, np.nan),
                   neighbourhood_stat=np.where(keep, result.neighbourhood_stat, np.nan),
                   predicted_error_m=float(surrogate.predict(offsets[None])[0]))


def with_kind(section: WrpSection, kind: str | None = None, threshold_m: float | None = None) -> WrpSection:
    """``section`` with another kind and / or threshold (validated for the new values)."""
    update: dict[str, Any] = {}
    if kind is not None:
        update["kind"] = kind
    if threshold_m is not None:
        update["threshold_m"] = threshold_m
    return WrpSection.model_validate({**section.model_dump(), **update}) if update else section


def optimize_job(ctx: ExperimentContext, *, kind: str | None = None, threshold_m: float | None = None,
                 out: Path | None = None, checkpoint=None, campaign=None, e_original: float | None = None,
                 use_oracle: bool = True) -> dict:
    """``wrp-eval optimize``: the config's ``wrp:`` section with the command line's kind and threshold (kind
    robust: :func:`wrp_eval.wrp.robust.robust_job`, levers.json instead of wrp_metrics.json)."""
    section = with_kind(ctx.config.wrp, kind, threshold_m)
    if section.kind == "robust":
        return robust_job(ctx, section, Path(out) if out else ctx.folders.wrp(section.kind), campaign)
    inputs = resolve_inputs(ctx, section, checkpoint, campaign)
    return run_optimize(ctx, section, Path(out) if out else ctx.folders.wrp(section.kind), inputs,
                        e_original=e_original, use_oracle=use_oracle)


def evaluate_job(ctx: ExperimentContext, out: Path | None = None, *, n_trials: int | None = None, checkpoint=None,
                 campaign=None, e_original: float | None = None,
                 evaluator: str | None = None, surrogate: Surrogate | None = None,
                 trials: TrialData | None = None, forecast: bool = True) -> EvaluationResult:
    """``wrp-eval evaluate``: the WRPs of ``wrp.evaluate.kinds`` (ISWRP and SWRP) optimised from one set of
    inputs, the flown levers of ``wrp.evaluate`` (robust, direction, capture_stops, slow_legs) built, then the
    initial path and every other path flown as campaigns with the same seed (common random numbers), with the
    placebos of each that changed anything; returns the evaluate.json document (written as its ``to_json_dict``).
    ``evaluator``: the campaign's trial evaluator ("module:function"; default the MuJoCo flight + oracle);
    ``surrogate`` / ``trials``: already loaded by the caller (the checkpoint and campaign are then not read);
    ``forecast`` False: no forecast flights (``wrp-eval run`` reads the go / no-go off its envelope instead)."""
    section, ev = ctx.config.wrp, ctx.config.wrp.evaluate
    out = Path(out) if out is not None else ctx.folders.evaluate
    if ev.thresholds_m is not None and len(ev.thresholds_m) != 2:
        raise InputError("wrp.evaluate.thresholds_m", "give two thresholds: [iswrp, swrp]")
    inputs = resolve_inputs(ctx, section, checkpoint, campaign, surrogate=surrogate, trials=trials,
                            need_surrogate=bool(ev.kinds))
    flown = evaluation_trial(ctx.trial_config, n_trials or ev.n_trials)
    # before the optimisation: a bad campaign or mode is reported at once
    capture = _capture_levers(ctx, out, inputs, flown.campaign.n_trials) if ev.capture_stops or ev.slow_legs else {}
    paths, optimised = _optimise_both(ctx, out, inputs, e_original)
    placebo_paths, infeasible, unmoved = _placebos(ctx, out, inputs, paths, optimised, capture)

    def fly(name: str, path: FlightPath, trial=flown) -> PathTrials:
        folder = evaluated_campaign_dir(out, name)
        summary = run_campaign(trial, path, folder, root_seed=ctx.campaign_seed, config_dir=ctx.config_dir,
                               evaluator=evaluator or DEFAULT_EVALUATOR)
        progress_log.info(f"{name}: {summary.done} trials in {folder} ({summary.failed} failed)")
        return read_trials(name, folder)

    flown_trials = [fly(name, path) for name, path in paths.items()]
    placebo_trials = {kind: [fly(name, path) for name, path in named.items()]
                      for kind, named in placebo_paths.items()}
    windfree = windfree_errors(ctx, paths, placebo_paths)
    spec = (ev.spec_error_m if ev.spec_error_m is not None else SPEC_ERROR_FACTOR * windfree["initial"],
            ev.spec_completeness)
    result = summarise(flown_trials, ctx.campaign_seed, ev.bootstrap, ev.confidence, spec, windfree, placebo_trials,
                       unmoved)
    placebos = PlaceboControl(ev.placebos, tuple(unmoved), infeasible, PLACEBO_DESCRIPTION)
    verdict = None
    if forecast and ev.forecast_trials > 0:
        chosen = result.recommended_path
        if chosen is None:
            raise RuntimeError("the evaluation recommended no path to fly in the forecast wind")
        fly("forecast", paths[chosen], forecast_config(flown, ctx.config.wind, ev.forecast_trials))
        verdict = forecast_verdict(read_trials(chosen, evaluated_campaign_dir(out, "forecast")), ev, spec,
                                   ctx.campaign_seed, ctx.config.wind)
    result = replace(result, placebos=placebos, forecast=verdict,
                     wrp={kind: Table3Row.from_json_dict(d["table3"]) for kind, d in optimised.items()},
                     common_random_numbers=f"every path flown with campaign seed {ctx.campaign_seed}: trial k of "
                                           "every path draws the same wind" + (
                                               " (a placebo of the reversed tour: the same mean wind, its own "
                                               "errors drawn again)" if ev.direction else ""))
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "evaluate.json", result.to_json_dict())
    box_plot(flown_trials, out / "boxplot.png")
    _log_evaluation(result)
    return result


PLACEBO_DESCRIPTION = ("as many viewpoints as the WRP moved, chosen at random, moved by the WRP's move magnitudes in "
                       "random directions with its yaw offsets (wrp/placebo.py); robust: its levers at as many "
                       "viewpoints chosen at random (wrp/robust.py); reversed: the initial tour flown again in the "
                       "same weather with its flights' own errors drawn again (wrp/direction.py); stops / slow-legs: "
                       "as many stop-and-shoot views / slowed legs at as many views chosen at random "
                       "(wrp/capture_lever.py)")


def _placebos(ctx: ExperimentContext, out: Path, inputs: WrpInputs, paths: dict[str, FlightPath],
              optimised: dict[str, dict], capture: dict[str, tuple[FlightPath, dict[str, FlightPath]] | None]
              ) -> tuple[dict[str, dict[str, FlightPath]], int, list[str]]:
    """The placebo paths of every WRP that moved (WRP -> {name -> path}), the placebo moves without a flyable
    direction, and the WRPs that moved nothing; with ``wrp.evaluate.robust`` the robust kind is optimised
    into ``paths`` first, with ``wrp.evaluate.direction`` the reversed tour added (wrp/direction.py), then the
    ``capture`` levers (:func:`_capture_levers`; None: it would change nothing, not flown)."""
    ev = ctx.config.wrp.evaluate
    unmoved = [kind for kind in optimised if not Table3Row.from_json_dict(optimised[kind]["table3"]).moved]
    # a WRP that moved nothing is the initial path: its placebos would all be the initial path too
    placebo_paths, infeasible = placebo_paths_of(ctx, {k: p for k, p in paths.items() if k not in unmoved},
                                                 ev.placebos)
    if ev.robust:
        paths["robust"], robust_placebos = _robust_and_placebos(ctx, out, inputs)
        if robust_placebos is None:
            unmoved.append("robust")
        else:
            placebo_paths["robust"] = robust_placebos
    if ev.direction:
        paths["reversed"] = inputs.path.reversed()
        evaluated_wrp_dir(out, "reversed").mkdir(parents=True, exist_ok=True)
        paths["reversed"].save(evaluated_wrp_dir(out, "reversed") / "path.json")      # where a chosen WRP is read
        placebo_paths["reversed"] = direction_placebos(inputs.path, ev.placebos)
    for name, lever in capture.items():
        if lever is None:
            unmoved.append(name)
        else:
            paths[name], placebo_paths[name] = lever
    return placebo_paths, infeasible, unmoved


def _capture_levers(ctx: ExperimentContext, out: Path, inputs: WrpInputs, n_flown: int
                    ) -> dict[str, tuple[FlightPath, dict[str, FlightPath]] | None]:
    """The capture levers of ``wrp.evaluate`` (wrp/capture_lever.py) at the views where the campaign's flights
    beyond the ``n_flown`` the evaluation flies blur: "stops" (stop-and-shoot there) and / or "slow-legs" (their
    legs slowed), each with its placebos seeded from the campaign seed and saved where a chosen WRP is read; None
    for a lever that would change nothing (no view blurs, or no leg is faster than the slow speed)."""
    ev = ctx.config.wrp.evaluate
    if ctx.config.sim.capture.mode != FLY_THROUGH:
        raise InputError("wrp.evaluate.capture_stops / slow_legs", "the capture levers need sim.capture.mode "
                                                                  "fly-through (a stop mission stops at every view "
                                                                  "already, its photos do not blur)")
    blur = held_out_blur(inputs.campaign_dir, n_flown, inputs.path)
    views = blurred_views(blur, ev.capture_blur_limit_px)
    progress_log.info(f"capture levers: {int(views.sum())} of {len(views)} views blur (95th percentile over "
                      f"{len(blur)} held-out campaign flights above {ev.capture_blur_limit_px:g} px)")
    levers: dict[str, tuple[FlightPath, dict[str, FlightPath]] | None] = {}
    if ev.capture_stops:
        rng = np.random.default_rng(np.random.SeedSequence(ctx.campaign_seed, spawn_key=(11, len(WRP_KINDS) + 1)))
        levers["stops"] = capture_lever_paths(inputs.path, views, ev.placebos, rng) if views.any() else None
    if ev.slow_legs:
        rng = np.random.default_rng(np.random.SeedSequence(ctx.campaign_seed, spawn_key=(11, len(WRP_KINDS) + 2)))
        slows = bool((inputs.path.leg_speeds()[legs_at(views)] > ev.slow_leg_speed_m_s).any())
        levers["slow-legs"] = (slow_leg_paths(inputs.path, views, ev.slow_leg_speed_m_s, ev.placebos, rng)
                               if slows else None)
    for name, lever in levers.items():
        if lever is None:
            progress_log.info(f"capture lever {name}: it would change nothing; not flown")
            continue
        folder = evaluated_wrp_dir(out, name)
        folder.mkdir(parents=True, exist_ok=True)
        lever[0].save(folder / "path.json")
    return levers


def _robust_and_placebos(ctx: ExperimentContext, out: Path, inputs: WrpInputs
                         ) -> tuple[FlightPath, dict[str, FlightPath] | None]:
    """The robust kind of ``inputs`` into ``out`` and its placebo paths (None when it applied no lever), seeded from
    the campaign seed."""
    section, robust_dir = ctx.config.wrp, evaluated_wrp_dir(out, "robust")
    levers = robust_job(ctx, section, robust_dir, inputs.campaign_dir)
    path = FlightPath.load(robust_dir / "path.json")
    if not levers["moved"]:
        return path, None
    rng = np.random.default_rng(np.random.SeedSequence(ctx.campaign_seed, spawn_key=(11, len(WRP_KINDS))))
    return path, robust_placebo_paths(inputs.path, levers, section.evaluate.placebos,
                                      view_depths(inputs.path, ctx.flight_proxy.bounds),
                                      section.robust.standoff_fraction, rng)


def _optimise_both(ctx: ExperimentContext, out: Path, inputs: WrpInputs,
                   e_original: float | None) -> tuple[dict[str, FlightPath], dict[str, dict]]:
    """The ISWRP and SWRP of ``inputs`` (those of ``wrp.evaluate.kinds``) into ``out``: (name -> path with
    "initial" first, kind -> wrp_metrics)."""
    section, thresholds = ctx.config.wrp, ctx.config.wrp.evaluate.thresholds_m
    paths: dict[str, FlightPath] = {"initial": inputs.path}
    optimised: dict[str, dict] = {}
    for kind in ctx.config.wrp.evaluate.kinds:
        i = WRP_KINDS.index(kind)
        kind_section = with_kind(section, kind, thresholds[i] if thresholds is not None else None)
        folder = evaluated_wrp_dir(out, kind)
        optimised[kind] = run_optimize(ctx, kind_section, folder, inputs, e_original=e_original)
        paths[kind] = FlightPath.load(folder / "path.json")
    return paths, optimised


def evaluation_trial(trial, n_trials: int):
    """The experiment's trial config with every path flown as planned: the flight makes the offsets
    (``physical`` design) and nothing else (no training-data targets), ``n_trials`` trials, no recording."""
    doc = trial.campaign.model_dump()
    doc.update({"n_trials": n_trials, "path": None})
    doc["perturbation"]["design"] = "physical"
    doc["perturbation"]["targeted_share"] = 0.0
    doc["outputs"].update({"dir": None, "rerun": False})
    return trial.model_copy(update={"campaign": type(trial.campaign).model_validate(doc)})


def _log_evaluation(result: EvaluationResult) -> None:
    for row in result.paths:
        progress_log.info(f"{row.path:8s} mean {row.mean_error_m:.4f} m  std {row.std_error_m:.4f}  "
                          f"p95 {row.p95_error_m:.4f}  failed {100 * row.failure_rate:.1f} %")
    for pair in result.paired:
        ci = pair.mean_error_diff_ci
        progress_log.info(f"{pair.path} - initial: mean error {pair.mean_error_diff_m:+.4f} m "
                          + (f"[{ci[0]:+.4f}, {ci[1]:+.4f}]" if ci else "") + f" over {pair.both_succeeded} pairs, "
                          f"failure rate {100 * pair.failure_rate_diff:+.1f} points")
    for kind, verdict in (result.robustness or {}).items():
        progress_log.info(f"{kind}: robustness gain {1e3 * verdict.gain_m:+.2f} mm, placebo p95 "
                          f"{1e3 * verdict.placebo_gain_p95_m:+.2f} mm: "
                          + ("RECOMMENDED" if verdict.recommended else f"not recommended ({verdict.reason})"))
    progress_log.info(f"recommended path: {result.recommended_path}")
    if result.forecast is not None:
        progress_log.info(result.forecast.summary)


def forecast_config(flown, wind, n_trials: int):
    """The evaluation's trial config with every trial in the forecast wind (the ``wind:`` section's speed and
    direction; turbulence and the rest as the campaign draws them) and ``n_trials`` trials."""
    doc = flown.campaign.model_dump()
    doc["n_trials"] = n_trials
    doc["wind"].update({"speed_10m_m_s": float(wind.speed_10m_m_s), "direction_deg": float(wind.direction_deg)})
    return flown.model_copy(update={"campaign": type(flown.campaign).model_validate(doc)})


SPEC_ERROR_FACTOR = 1.1   # wrp.evaluate.spec_error_m unset: 1.1 x the initial path's wind-free error


def windfree_errors(ctx: ExperimentContext, paths: dict[str, FlightPath],
                    placebo_paths: dict[str, dict[str, FlightPath]]) -> dict[str, float]:
    """E_windfree (m) of every path and placebo path by name (``paths`` has "initial"): a placebo that only draws
    its flights' errors again flies the initial path's plan, and takes its wind-free error."""
    windfree = {name: windfree_error(ctx, path) for name, path in paths.items()}
    initial_digest = paths["initial"].digest()
    windfree.update({name: windfree["initial"] if path.noise_draw and path.redrawn(0).digest() == initial_digest
                     else windfree_error(ctx, path)
                     for named in placebo_paths.values() for name, path in named.items()})
    return windfree


def windfree_error(ctx: ExperimentContext, path: FlightPath) -> float:
    """E_windfree (m): the oracle's error of ``path`` flown exactly as planned (NaN when it cannot score)."""
    error = oracle_error(ctx.scored_ship, path)["error_m"]
    return float("nan") if error is None else float(error)


def placebo_paths_of(ctx: ExperimentContext, paths: dict[str, FlightPath],
                     count: int) -> tuple[dict[str, dict[str, FlightPath]], int]:
    """``count`` placebo paths per WRP of ``paths`` (name -> path; "initial" is the base), seeded from the
    campaign seed and the WRP's index: WRP name -> {placebo name -> path}; and how many placebo moves found no
    flyable direction."""
    initial = paths["initial"]
    safety = safety_constraints(ctx, initial)
    out, infeasible = {}, 0
    for kind, wrp in ((k, p) for k, p in paths.items() if k != "initial"):
        index = WRP_KINDS.index(kind)    # a fixed stream per kind, whichever other WRPs are flown
        offsets = np.concatenate([np.asarray(wrp.positions) - np.asarray(initial.positions),
                                  np.angle(np.exp(1j * (np.asarray(wrp.yaw) - np.asarray(initial.yaw))))[:, None]],
                                 axis=1)
        rng = np.random.default_rng(np.random.SeedSequence(ctx.campaign_seed, spawn_key=(11, index)))
        placebo, bad = placebo_offsets(offsets, count, rng, safety["base_positions"],
                                       lambda pts: flyable(pts, safety["no_fly_bounds"], safety["min_altitude_m"]))
        infeasible += bad
        out[kind] = {f"placebo-{kind}-{k:02d}": apply_offsets(initial, placebo[k], {"placebo_of": kind})
                     for k in range(count)}
    return out, infeasible
