"""A batch of trials flies, row by row, exactly the wind the wind stage builds for each trial alone."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.campaign.config import CampaignSection
from wrp_eval.campaign.sampling import draw_wind, trial_wind_rng, trial_wind_section
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.field import build_wind_field
from wrp_eval.wind.grid import OutsideWindGridError

SHIP = (0.0, 0.0, 0.0)  # lat, lon, heading
GRID = {"x_range_m": [-100, 100], "y_range_m": [-60, 60], "spacing_m": 20}


def _batch(base, draws, dt_s=0.02):
    return build_wind_field([trial_wind_section(base, d) for d in draws], SHIP, [trial_wind_rng(d) for d in draws],
                            dt_s=dt_s)


@pytest.mark.parametrize("turbulence, gusts", [
    ({"severity": {"dist": "choice", "values": ["none", "light", "severe", "from_mean"]}}, False),
    ({"severity": "none", "sigma_w_m_s": {"dist": "uniform", "low": 0.2, "high": 1.0}}, False),
    ({"severity": {"dist": "choice", "values": ["none", "moderate"]}}, True),
])
def test_each_row_equals_the_wind_stage_field_of_that_trial_alone(turbulence, gusts):
    section = CampaignSection.model_validate({"wind": {"turbulence": turbulence}})
    # frequent long gusts, so that several overlap and the rows carry different gust counts
    base = WindSection(grid=GRID, gusts={"enabled": gusts, "rate_per_min": 30.0, "duration_s": 8.0})
    n, steps, dt = (12, 300, 2.0) if gusts else (4, 30, 0.02)   # gusts: many overlaps over their horizon
    draws = [draw_wind(section, 4, k) for k in range(n)]
    batched = _batch(base, draws, dt)
    alone = [build_wind_field([trial_wind_section(base, d)], SHIP, [trial_wind_rng(d)], dt_s=dt) for d in draws]
    rng = np.random.default_rng(0)
    for step in range(steps):
        points = np.column_stack([rng.uniform(-95, 95, n), rng.uniform(-55, 55, n), rng.uniform(3, 60, n)])
        got = batched.velocity(points, dt * step)
        want = np.concatenate([w.velocity(points[i:i + 1], dt * step) for i, w in enumerate(alone)])
        np.testing.assert_array_equal(got, want)   # bit-identical: batching never changes a trial
    speeds = [np.linalg.norm(w.mean.velocity(np.array([[0.0, 0.0, 10.0]]))) for w in alone]
    np.testing.assert_allclose(speeds, [d.speed_10m_m_s for d in draws], rtol=1e-6)  # the drawn 10 m speed
    if gusts:
        assert len({np.isfinite(g.gusts.start_s).sum() for g in alone}) > 1   # the case is not trivial


def test_points_outside_the_grid_are_refused_as_by_the_wind_stage():
    base = WindSection(grid=GRID)
    draws = [draw_wind(CampaignSection(), 1, k) for k in range(2)]
    batched = _batch(base, draws)
    with pytest.raises(OutsideWindGridError):
        batched.velocity(np.array([[0.0, 0.0, 10.0], [150.0, 0.0, 10.0]]), 0.0)
    with pytest.raises(OutsideWindGridError):
        batched.velocity(np.array([[0.0, 80.0, 10.0], [0.0, 0.0, 10.0]]), 0.0)
    with pytest.raises(OutsideWindGridError):
        batched.velocity(np.array([[0.0, 0.0, 10.0], [0.0, 0.0, 500.0]]), 0.0)
