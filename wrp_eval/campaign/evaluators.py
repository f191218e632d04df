"""The plug-in point of the campaign: an evaluator turns a batch of trial inputs into outcomes.

An evaluator is built once per worker process by a *factory* named ``"module:function"``, called as
``factory(context, **options)`` with the :class:`CampaignContext` (plain data: resolved config, path,
seed), and has ``evaluate(batch: list[TrialInputs]) -> list[TrialOutcome]``. Results must depend only on
each trial's inputs (not on the batch it shares), so that backends, batch sizes and resumes agree.

* ``wrp_eval.campaign.flight_evaluator:make_flight_evaluator`` (the default): MuJoCo flights + reconstruction oracle.
* ``wrp_eval.campaign.evaluators:make_analytic_evaluator``: a closed-form stand-in (no flight, no oracle) for
  testing and timing the campaign machinery itself -- it is NOT a model of the UAV.
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from wrp_eval.campaign.config import TrialConfig
from wrp_eval.campaign.records import TrialOutcome
from wrp_eval.campaign.sampling import TrialInputs
from wrp_eval.errors import InputError
from wrp_eval.frames import wind_velocity
from wrp_eval.planning.path import FlightPath
from wrp_eval.ship.resolve import resolve_particulars

DEFAULT_EVALUATOR = "wrp_eval.campaign.flight_evaluator:make_flight_evaluator"
ANALYTIC_EVALUATOR = "wrp_eval.campaign.evaluators:make_analytic_evaluator"
# evaluator names campaign folders stored before their module was renamed -> today's name (a stored campaign's
# fingerprint holds its evaluator's name: read through this, its trials stay resumable)
RENAMED_EVALUATORS = {"wrp_eval.campaign.flight:make_flight_evaluator": DEFAULT_EVALUATOR}


@dataclass(frozen=True)
class CampaignContext:
    """What every worker knows about the campaign (value types, pickled to a process or a Ray node as they are).

    trial: the sections a trial reads (validated once, in the calling process); path: the path flown;
    root_seed; path_digest; threads: CPU threads a worker may use; config_dir: the folder relative files of the
    config (ship mesh, AIS, netCDF) are resolved against (None: the working directory)."""

    trial: TrialConfig
    path: FlightPath
    root_seed: int
    path_digest: str
    threads: int = 1
    config_dir: str | None = None


class TrialEvaluator(Protocol):
    """The one-method plug-in interface of a campaign's trials: a factory ``"module:function"`` builds it from
    the :class:`CampaignContext` (once per worker process) and ``evaluate`` returns one outcome per input, in
    order (the MuJoCo flight + oracle, :class:`AnalyticEvaluator`, the tests' killing evaluators)."""

    def evaluate(self, batch: list[TrialInputs]) -> list[TrialOutcome]: ...


def resolve_factory(name: str):
    """Import ``"module:function"``; a bad name is an :class:`InputError`."""
    module_name, _, attr = RENAMED_EVALUATORS.get(name, name).partition(":")
    try:
        return getattr(importlib.import_module(module_name), attr)
    except (ImportError, AttributeError, ValueError) as err:
        raise InputError("evaluator", f"cannot load {name!r}: {err}") from None


class AnalyticEvaluator:
    """Closed-form stand-in evaluator: a pure function of each trial's inputs.

    Wind-induced deviation of view i = gain * (w_x, w_y, 0, 0.02 W) * disturbance_i + turbulence noise (seeded
    by the trial's wind seed, std grows with severity), with (w_x, w_y) the drawn wind of speed W in the ship
    frame (:func:`wrp_eval.frames.wind_velocity`: blowing FROM the drawn compass direction, the ship's heading
    from its ``ship:`` section; it read the compass direction d as (cos d, sin d), an angle counter-clockwise
    from the bow, until the frames module made the one convention); flown = commanded + deviation; error_m
    grows with the mean offset norm; a trial fails when W > fail_speed_m_s. ``fail_trial_ids`` raise (to
    exercise error recording); ``sleep_s`` per trial emulates work."""

    SEVERITY_STD = {"none": 0.0, "from_mean": 0.1, "light": 0.05, "moderate": 0.1, "severe": 0.2}

    def __init__(self, context: CampaignContext, gain_m_per_m_s: float = 0.05, fail_speed_m_s: float = 1e9,
                 fail_trial_ids: tuple[int, ...] = (), sleep_s: float = 0.0, trajectory_points: int = 20):
        self.n_views = len(context.path)
        self.gain = gain_m_per_m_s
        self.fail_speed = fail_speed_m_s
        self.fail_ids = frozenset(int(k) for k in fail_trial_ids)
        self.sleep_s = sleep_s
        self.planned = np.asarray(context.path.positions, dtype=float)
        self.trajectory_points = trajectory_points
        particulars, _ = resolve_particulars(context.trial.ship, context.config_dir or ".")
        self.heading_rad = float(np.radians(particulars.heading_deg))

    def evaluate(self, batch: list[TrialInputs]) -> list[TrialOutcome]:
        out = []
        for inputs in batch:
            if inputs.trial_id in self.fail_ids:
                raise RuntimeError(f"analytic evaluator told to fail trial {inputs.trial_id}")
            start = time.perf_counter()
            if self.sleep_s:
                time.sleep(self.sleep_s)
            w = inputs.wind
            v = wind_velocity(w.speed_10m_m_s, np.radians(w.direction_deg), self.heading_rad)   # (3,) ship frame
            mean = self.gain * np.array([v[0], v[1], 0.0, 0.02 * w.speed_10m_m_s])
            std = (self.SEVERITY_STD.get(w.severity, 0.1) if w.sigma_w_m_s is None else w.sigma_w_m_s) \
                * w.speed_10m_m_s * self.gain
            noise = np.random.default_rng(w.seed).normal(0.0, std, size=(self.n_views, 4))
            flown = inputs.commanded_offsets + (mean + noise) * inputs.disturbance
            norm = np.linalg.norm(flown[:, :3], axis=1)
            failed = w.speed_10m_m_s > self.fail_speed
            capture = self.planned + flown[:, :3]
            idx = np.linspace(0, self.n_views - 1, self.trajectory_points)
            trajectory = np.stack([np.interp(idx, np.arange(self.n_views), capture[:, j]) for j in range(3)], 1)
            wind = np.tile(v, (self.n_views, 1))
            metrics = {"error_m": 0.5 + 0.1 * float(norm.mean()), "accuracy_m": 0.3 + 0.05 * float(norm.mean()),
                       "completeness": float(np.exp(-0.1 * norm.mean())), "precision": 1.0,
                       "fscore": float(np.exp(-0.1 * norm.mean())), "registered_fraction": 1.0}
            if failed:
                metrics = {k: float("nan") for k in metrics}
            out.append(TrialOutcome(flown_offsets=flown, metrics=metrics, failed=bool(failed),
                                    reason="wind beyond capability (analytic)" if failed else "",
                                    trajectory=trajectory, wind_at_views=wind,
                                    timings={"flight_s": time.perf_counter() - start, "oracle_s": 0.0}))
        return out


def make_analytic_evaluator(context: CampaignContext, **options) -> AnalyticEvaluator:
    return AnalyticEvaluator(context, **options)
