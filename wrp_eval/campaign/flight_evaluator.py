"""The real trial evaluator: batched MuJoCo flights of the (perturbed) path through each trial's wind, then
the reconstruction oracle on each trial's capture poses.

Per batch of trials: one wind field for the batch (the wind stage's ``build_wind_field``), one
``FlightSimulator.fly`` call with the commanded offsets, around the ship (its box for the compass and the
views' depth, its motion), each trial's navigation errors and ship motion drawn from its own ``flight_seed``
(its wind's turbulence and gusts from its wind seed; a path's ``noise_draw`` > 0 draws both again);
then per trial the paper's extra disturbance of the wind-induced deviation, the capture set (with the
gimbal's roll and the navigation's positions as priors) and one oracle call. Offsets are measured from the planned
viewpoints:
    flown = commanded + disturbance * (sim_offset - commanded)
(``sim_offset`` = the simulator's actual capture pose minus the plan). With the ``physical`` design (commanded 0,
no extra disturbance) the capture poses are exactly the simulator's.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from wrp_eval.campaign.evaluators import CampaignContext
from wrp_eval.campaign.records import TrialOutcome
from wrp_eval.campaign.sampling import TrialInputs, trial_wind_rng, trial_wind_section
from wrp_eval.errors import InputError
from wrp_eval.recon.scored_ship import scored_ship
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.sim.flight import FlightSimulator
from wrp_eval.sim.flight_state import COMPLETED, OUTCOME_NAMES
from wrp_eval.sim.onboard import ShipInScene
from wrp_eval.streams import redrawn_seed
from wrp_eval.wind.field import build_wind_field


def trajectory_until(times: np.ndarray, positions: np.ndarray, end_s: np.ndarray, points: int) -> list[np.ndarray]:
    """Per flight, its recorded positions up to its own end time (last photo or failure; a batch keeps
    recording until its last flight ends), down-sampled to at most ``points`` evenly spaced samples
    including the first and the last. times (T,) s; positions (batch, T, 3); end_s (batch,)."""
    out = []
    for i in range(positions.shape[0]):  # per trial, not per sample: a handful of slices
        count = max(1, int(np.searchsorted(times, end_s[i], side="right")))
        idx = np.round(np.linspace(0, count - 1, min(count, points))).astype(int)
        out.append(positions[i, idx])
    return out


def values_at_times(times: np.ndarray, series: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Nearest-earlier samples of ``series`` (batch, T, k) recorded at ``times`` (T,) at ``query`` (batch, n);
    NaN where the query is NaN."""
    idx = np.clip(np.searchsorted(times, np.nan_to_num(query, nan=0.0), side="right") - 1, 0, times.size - 1)
    out = np.take_along_axis(series, idx[..., None], axis=1)
    out[~np.isfinite(query)] = np.nan
    return out


class FlightEvaluator:
    """Built once per worker: the ship, the path, the simulator and the oracle stay loaded between batches."""

    def __init__(self, context: CampaignContext):
        self.config = context.trial
        self.config_dir = context.config_dir or "."
        self.path = context.path
        self.ship = scored_ship(self.config.ship, self.config.oracle, self.config.campaign.oracle, self.config_dir)
        sim_section = self.config.sim.model_copy(update={"threads": max(1, int(context.threads))})
        self.sim = FlightSimulator(sim_section)
        self.dt_s = sim_section.timestep_s * sim_section.chunk_steps
        self.trajectory_points = self.config.campaign.outputs.trajectory_points
        self.in_scene = ShipInScene.of(self.ship.mesh, self.config.ship.motion, self.ship.particulars)

    def evaluate(self, batch: list[TrialInputs]) -> list[TrialOutcome]:
        start = time.perf_counter()
        wind = build_wind_field([trial_wind_section(self.config.wind, t.wind) for t in batch], self.ship.particulars,
                                [trial_wind_rng(t.wind, self.path.noise_draw) for t in batch], self.dt_s,
                                self.config_dir)
        commanded = np.stack([t.commanded_offsets for t in batch])           # (b, n, 4)
        ship = replace(self.in_scene, wind_speed_10m_m_s=wind.speed_10m_at_ship(len(batch)))
        result = self.sim.fly(self.path, wind, len(batch), view_offsets=commanded, ship=ship,
                              flight_rngs=[np.random.default_rng(redrawn_seed(t.flight_seed, self.path.noise_draw))
                                           for t in batch])
        flight_s = (time.perf_counter() - start) / len(batch)
        disturbance = np.stack([t.disturbance for t in batch])
        flown = commanded + disturbance * (result.offsets - commanded)         # NaN stays NaN (views not taken)
        traj = result.trajectory
        wind_at_views = values_at_times(traj.time, traj.wind, result.capture_time_s)
        trajectories = trajectory_until(traj.time, traj.position, result.flight_time_s, self.trajectory_points)
        planned = np.concatenate([self.path.positions, self.path.yaw[:, None]], axis=1)

        outcomes = []
        for i, inputs in enumerate(batch):
            t0 = time.perf_counter()
            taken = result.taken[i]
            pose = planned[taken] + flown[i, taken]
            prior = self.path.positions[taken] + result.estimated_offsets[i, taken, :3]
            captures = CaptureSet(pose[:, :3], pose[:, 3], result.camera_pitch[i, taken], np.flatnonzero(taken),
                                  self.path.camera, roll=result.camera_roll[i, taken], prior_positions=prior,
                                  blur_px=result.blur_px[i, taken],
                                  view_id=self.path.view_ids_of(taken))
            recon = self.ship.score(captures, inputs.oracle_seed)
            reasons = []
            if result.failed[i]:
                reasons.append(f"flight: {result.failure_reason[i]}")
            if recon.failed:
                reasons.append(f"reconstruction: {recon.reason}")
            metrics = {"error_m": recon.error_m, "hole_part_m": recon.hole_part_m,
                       "accuracy_part_m": recon.accuracy_part_m, "accuracy_m": recon.accuracy_m,
                       "completeness": recon.completeness, "precision": recon.precision, "fscore": recon.fscore,
                       "registered_fraction": recon.registered_views / max(1, len(self.path))}
            outcomes.append(TrialOutcome(
                flown_offsets=flown[i], camera_pitch=np.where(taken, result.camera_pitch[i], np.nan),
                metrics=metrics, failed=bool(result.failed[i] or recon.failed),
                reason="; ".join(reasons), trajectory=trajectories[i], wind_at_views=wind_at_views[i],
                timings={"flight_s": flight_s, "oracle_s": time.perf_counter() - t0},
                capture_time_s=result.capture_time_s[i], camera_roll=result.camera_roll[i],
                estimated_offsets=result.estimated_offsets[i],
                blur_px=result.blur_px[i], battery_charge=result.battery_charge[i], ship_motion=result.ship_motion[i],
                view_registered=view_registered(taken, recon.registered_mask),
                flight_outcome="completed" if result.outcome[i] == COMPLETED else result.outcome_reason[i],
                sorties=int(result.sorties[i]), view_sortie=result.view_sortie[i],
                mission_time_s=float(result.flight_time_s[i]), ending=OUTCOME_NAMES[int(result.outcome[i])]))
        return outcomes

    def close(self) -> None:
        self.sim.close()


def view_registered(taken: np.ndarray, registered_mask: np.ndarray | None) -> np.ndarray | None:
    """(n_views,) 1.0 / 0.0 where the oracle did / did not register a taken view, NaN where none was taken; None
    when the oracle does not say which views it registered."""
    if registered_mask is None:
        return None
    out = np.full(taken.shape, np.nan)
    out[taken] = registered_mask
    return out


def make_flight_evaluator(context: CampaignContext, **options) -> FlightEvaluator:
    if options:
        raise InputError("evaluator", f"the flight evaluator takes no options, got {sorted(options)}")
    return FlightEvaluator(context)
