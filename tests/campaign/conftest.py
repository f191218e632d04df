"""Shared fixtures of the campaign tests: a tiny path and configs that use the analytic stand-in evaluator
(tests of the campaign machinery -- store, seeding, backends, recording -- not of flights)."""

from __future__ import annotations

import json

import numpy as np
import pyarrow as pa
import pytest

from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
from wrp_eval.campaign.jobs import campaign_job
from wrp_eval.campaign.records import TIMING_COLUMNS
from wrp_eval.config import ExperimentConfig
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath


def tiny_path(n_views: int = 6) -> FlightPath:
    """n_views viewpoints on a line 30 m from the x axis, looking at it."""
    x = np.linspace(-20.0, 20.0, n_views)
    positions = np.stack([x, np.full(n_views, 30.0), np.full(n_views, 10.0)], axis=1)
    return FlightPath(positions=positions, yaw=np.full(n_views, -np.pi / 2), pitch=np.full(n_views, -0.2),
                      face_id=np.full(n_views, 2), kind=np.zeros(n_views, int), sortie=np.zeros(n_views, int))


@pytest.fixture
def path_file(tmp_path):
    file = tmp_path / "path.json"
    tiny_path().save(file)
    return file


def make_config(path_file, **campaign) -> ExperimentConfig:
    """An experiment config whose campaign flies ``path_file``; ``campaign`` entries override the section
    (nested dicts merge one level deep)."""
    section = {"path": str(path_file), "n_trials": 12, "batch_size": 3, "seed": 7,
               "backend": {"workers": 0}, "outputs": {"rerun": False, "chunk_trials": 4}}
    for key, value in campaign.items():
        if isinstance(value, dict) and isinstance(section.get(key), dict):
            section[key] = {**section[key], **value}
        else:
            section[key] = value
    return ExperimentConfig.model_validate({"campaign": section})


def comparable(table: pa.Table) -> str:
    """The records without timings, sorted by trial id, as canonical JSON (NaN-safe equality)."""
    table = table.drop_columns(list(TIMING_COLUMNS)).sort_by("trial_id")
    return json.dumps(table.to_pylist(), sort_keys=True)


EVALUATOR = ANALYTIC_EVALUATOR


@pytest.fixture(name="make_config")
def _make_config_fixture():
    return make_config


@pytest.fixture(name="comparable")
def _comparable_fixture():
    return comparable


@pytest.fixture(name="tiny_path")
def _tiny_path_fixture():
    return tiny_path


@pytest.fixture
def run_analytic():
    """run_analytic(config, out, overrides=None, **evaluator_options) -> CampaignSummary, with the analytic
    evaluator; ``overrides``: the command line's campaign overrides (n_trials, backend, workers, rerun)."""

    def run(config, out, overrides=None, **options):
        return campaign_job(ExperimentContext(config), out_dir=out, evaluator=EVALUATOR, evaluator_options=options,
                            **(overrides or {}))
    return run
