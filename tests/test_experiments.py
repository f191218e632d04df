"""The experiment configs shipped in experiments/: each one loads, and the inspection case is close range."""

from __future__ import annotations

from pathlib import Path

import pytest

from wrp_eval.experiment import ExperimentContext

EXPERIMENTS = Path(__file__).resolve().parents[1] / "experiments"


@pytest.mark.parametrize("file", sorted(EXPERIMENTS.rglob("*.yaml")), ids=lambda f: f.name)
def test_every_shipped_experiment_loads(file):
    ctx = ExperimentContext.load(file)
    assert ctx.config.run.name


def test_inspection_is_the_quickstart_ship_at_close_range():
    quick = ExperimentContext.load(EXPERIMENTS / "quickstart.yaml")
    close = ExperimentContext.load(EXPERIMENTS / "inspection.yaml")
    assert close.config.ship == quick.config.ship and close.config.wind == quick.config.wind
    standoff = close.config.planning.planned_distance_m()
    assert 25.0 < standoff < 35.0 < quick.config.planning.planned_distance_m()
    assert len(close.campaign_path) > 3 * len(quick.campaign_path)
