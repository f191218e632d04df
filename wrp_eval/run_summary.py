"""The typed run summary of ``wrp-eval run`` (run_summary.json): what each stage of the job produced, in the
order the stages ran. Frozen dataclasses with ``to_json_dict``; the evaluation is
:class:`~wrp_eval.wrp.evaluation.EvaluationResult`. The plan's metrics stay the planner's own document
(plan_metrics.json)."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from wrp_eval.wrp.evaluation import EvaluationResult


@dataclass(frozen=True)
class CampaignRun:
    """The campaign stage: its folder, trials stored and failed, its rate (trials/min), and the stress-test
    note when a turbulence preset is far above what the trials' mean winds imply (None: none)."""

    dir: str
    trials: int
    failed: int
    trials_per_min: float
    turbulence_stress: str | None

    def to_json_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class SurrogateFit:
    """The surrogate's held-out test figures (R^2, RMSE m, MAE m, trials; the failure output's Brier score when
    it has one) and the share of the flown offsets' variance the flights made (position, yaw; None without)."""

    r2: float
    rmse: float
    mae: float
    n: int
    physical_variance_share: dict[str, float] | None
    failure_brier: float | None = None

    @classmethod
    def of(cls, test_metrics: dict, physical_variance_share: dict | None) -> "SurrogateFit":
        return cls(test_metrics["r2"], test_metrics["rmse"], test_metrics["mae"], test_metrics["n"],
                   physical_variance_share, test_metrics.get("failure_brier"))

    def to_json_dict(self) -> dict:
        doc: dict[str, Any] = {"r2": self.r2, "rmse": self.rmse, "mae": self.mae, "n": self.n}
        if self.failure_brier is not None:
            doc["failure_brier"] = self.failure_brier
        doc["physical_variance_share"] = self.physical_variance_share
        return doc


@dataclass(frozen=True)
class EnvelopeRun:
    """The wind envelope of the recommended path: the path's name, the go / no-go in the forecast wind (None:
    no forecast), the files written (name -> path), the U10 boundary (m/s) per direction, the flights flown."""

    path: str
    go: bool | None
    files: dict[str, str]
    boundaries_m_s: dict[str, float | None]
    flights: int

    def to_json_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class RunSummary:
    """run_summary.json: the config file, the run's seed and folder; the plan's metrics; the campaign; the
    surrogate; the evaluation; the envelope (None without ``envelope.run_grid``); the missions written (path
    name -> files); the per-view risk (risk_m, p_missed, loss_m per view, base_error_m); the wall time of each
    step (s); and the report's path (not in the JSON: the report is written from the summary)."""

    config: str
    seed: int
    out: str
    plan: dict
    campaign: CampaignRun
    surrogate: SurrogateFit
    evaluate: EvaluationResult
    envelope: EnvelopeRun | None
    missions: dict[str, list[str]]
    view_risk: dict
    timings_s: dict[str, float]
    report: str | None = None

    def to_json_dict(self) -> dict:
        doc = {"config": self.config, "seed": self.seed, "out": self.out, "plan": self.plan,
               "campaign": self.campaign.to_json_dict(), "surrogate": self.surrogate.to_json_dict(),
               "evaluate": self.evaluate.to_json_dict()}
        if self.envelope is not None:
            doc["envelope"] = self.envelope.to_json_dict()
        doc.update(missions=self.missions, view_risk=self.view_risk, timings_s=self.timings_s)
        return doc
