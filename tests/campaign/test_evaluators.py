"""The analytic stand-in evaluator reads the drawn wind in the project's one convention (wrp_eval.frames)."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.campaign.config import TrialConfig
from wrp_eval.campaign.evaluators import AnalyticEvaluator, CampaignContext
from wrp_eval.campaign.sampling import TrialInputs, WindDraw

from .conftest import tiny_path


@pytest.mark.parametrize("heading, direction_from, toward", [
    (0.0, 0.0, (-1.0, 0.0)),      # bow north, wind from the north: pushed toward the stern (-x)
    (0.0, 90.0, (0.0, 1.0)),      # bow north, wind from the east (starboard): pushed to port (+y)
    (90.0, 90.0, (-1.0, 0.0)),    # bow east, wind from the east: from the bow
    (90.0, 0.0, (0.0, -1.0)),     # bow east, wind from the north (port): pushed to starboard (-y)
])
def test_deviation_and_wind_follow_the_compass_from_convention(heading, direction_from, toward):
    trial = TrialConfig.model_validate({"ship": {"particulars": {"heading_deg": heading}}})
    path = tiny_path(4)
    evaluator = AnalyticEvaluator(CampaignContext(trial, path, 0, "digest"), gain_m_per_m_s=0.1)
    wind = WindDraw(speed_10m_m_s=5.0, direction_deg=direction_from, severity="none", sigma_w_m_s=None, file=None,
                    time=None, seed=3)
    inputs = TrialInputs(0, wind, np.zeros((4, 4)), np.ones((4, 4)), 0, 0)
    outcome = evaluator.evaluate([inputs])[0]
    np.testing.assert_allclose(outcome.flown_offsets[:, :2], np.tile(0.5 * np.array(toward), (4, 1)), atol=1e-12)
    np.testing.assert_allclose(outcome.flown_offsets[:, 3], 0.1 * 5.0 * 0.02)
    np.testing.assert_allclose(outcome.wind_at_views, np.tile([5.0 * toward[0], 5.0 * toward[1], 0.0], (4, 1)),
                               atol=1e-12)
