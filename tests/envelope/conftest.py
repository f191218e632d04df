"""Envelopes of a tiny path flown by the analytic stand-in evaluator (the machinery, not flights): a flight
fails when U10 exceeds ``FAIL_SPEED``, so every direction's boundary lies between 9 and 10 m/s."""

from __future__ import annotations

import json

import pytest

from tests.campaign.conftest import tiny_path
from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
from wrp_eval.config import ExperimentConfig
from wrp_eval.envelope.config import EnvelopeGrid
from wrp_eval.envelope.jobs import envelope_job
from wrp_eval.experiment import ExperimentContext

FAIL_SPEED = 9.0
GRID = EnvelopeGrid(speeds_m_s=(0.0, 4.0, 8.0, 12.0), directions=2, max_flights=24, look_flights=8,
                    resolution_m_s=1.0)


def envelope_context(tmp_path) -> ExperimentContext:
    path_file = tmp_path / "path.json"
    if not path_file.exists():
        tiny_path().save(path_file)
    return ExperimentContext(ExperimentConfig.model_validate({
        "campaign": {"path": str(path_file), "seed": 7, "batch_size": 8, "backend": {"workers": 0}},
        "wrp": {"evaluate": {"spec_error_m": 0.6, "spec_completeness": 0.5}},
        "wind": {"speed_10m_m_s": 6.0, "direction_deg": 270.0}}))


def fly(tmp_path, out: str = "env", grid: EnvelopeGrid = GRID, backend: str | None = None, workers: int | None = None,
        **options):
    return envelope_job(envelope_context(tmp_path), grid, out_dir=tmp_path / out, evaluator=ANALYTIC_EVALUATOR,
                        evaluator_options={"fail_speed_m_s": FAIL_SPEED, **options}, backend=backend,
                        workers=workers)


def cells_without_folders(envelope) -> str:
    return json.dumps([{k: v for k, v in c.items() if k != "folder"} for c in envelope.to_json_dict()["cells"]],
                      sort_keys=True)


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("envelope")
    return tmp, fly(tmp)
