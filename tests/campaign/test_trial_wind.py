"""A batch of trials flies, row by row, exactly the wind the wind stage builds for each trial alone."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.campaign.config import CampaignSection
from wrp_eval.campaign.sampling import draw_wind
from wrp_eval.campaign.trial_wind import build_trial_wind, trial_wind_section
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.field import build_wind_field
from wrp_eval.wind.grid import OutsideWindGridError

SHIP = (0.0, 0.0, 0.0)  # lat, lon, heading


@pytest.mark.parametrize("turbulence", [
    {"severity": {"dist": "choice", "values": ["none", "light", "severe", "from_mean"]}},
    {"severity": "none", "sigma_w_mps": {"dist": "uniform", "low": 0.2, "high": 1.0}},
])
def test_each_row_equals_the_wind_stage_field_of_that_trial_alone(turbulence):
    section = CampaignSection.model_validate({"wind": {"turbulence": turbulence}})
    base = WindSection(grid={"x_range_m": [-100, 100], "y_range_m": [-60, 60], "spacing_m": 20})
    draws = [draw_wind(section, 4, k) for k in range(4)]
    batched = build_trial_wind(base, draws, SHIP, dt_s=0.02)
    alone = [build_wind_field(trial_wind_section(base, d), SHIP, 1, d.seed, dt_s=0.02) for d in draws]
    rng = np.random.default_rng(0)
    for step in range(30):
        points = np.column_stack([rng.uniform(-95, 95, 4), rng.uniform(-55, 55, 4), rng.uniform(3, 60, 4)])
        got = batched.velocity(points, 0.02 * step)
        want = np.concatenate([w.velocity(points[i:i + 1], 0.02 * step) for i, w in enumerate(alone)])
        np.testing.assert_array_equal(got, want)   # bit-identical: batching never changes a trial
    speeds = [np.linalg.norm(w.mean.velocity(np.array([[0.0, 0.0, 10.0]]))) for w in alone]
    np.testing.assert_allclose(speeds, [d.speed_10m_m_s for d in draws], rtol=1e-6)  # the drawn 10 m speed


def test_points_outside_the_grid_are_refused_as_by_the_wind_stage():
    base = WindSection(grid={"x_range_m": [-100, 100], "y_range_m": [-60, 60], "spacing_m": 20})
    draws = [draw_wind(CampaignSection(), 1, k) for k in range(2)]
    batched = build_trial_wind(base, draws, SHIP, dt_s=0.02)
    with pytest.raises(OutsideWindGridError):
        batched.velocity(np.array([[0.0, 0.0, 10.0], [150.0, 0.0, 10.0]]), 0.0)
    with pytest.raises(OutsideWindGridError):
        batched.velocity(np.array([[0.0, 80.0, 10.0], [0.0, 0.0, 10.0]]), 0.0)
    with pytest.raises(OutsideWindGridError):
        batched.velocity(np.array([[0.0, 0.0, 10.0], [0.0, 0.0, 500.0]]), 0.0)
