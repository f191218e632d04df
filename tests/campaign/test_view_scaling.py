"""The view-count scaling records (no planning or flying: the record builder on given points)."""

from __future__ import annotations

import pytest

from wrp_eval.campaign.view_scaling import PLAN_STAGES, view_count_records


def _point(views: int) -> dict:
    scale = views / 100.0
    return {"gsd_mm": 400.0 / views, "views": views, "plan_s": 2.0 * scale ** 1.5,
            **{stage: 0.1 * scale ** 2 for stage in PLAN_STAGES}, "oracle_s": 0.5 * scale,
            "trials_per_min": 60.0 / scale, "flights": 32, "trial_flight_s": 0.4 * scale,
            "trial_oracle_s": 0.6 * scale, "trial_trial_s": 1.0 * scale}


def test_exponents_and_targets_follow_the_points():
    records = {r.name: r for r in view_count_records([_point(v) for v in (46, 143, 330, 600)])}
    assert records["scaling.views.plan_exponent"].value == pytest.approx(1.5)
    assert records["scaling.views.oracle_exponent"].value == pytest.approx(1.0)
    assert records["scaling.views.campaign_exponent"].value == pytest.approx(1.0)
    assert records["scaling.views.plan_tsp_exponent"].value == pytest.approx(2.0)
    assert records["scaling.views.plan_s.v330"].anchor_value == 5.0
    assert records["scaling.views.plan_s.v143"].anchor_value is None
    assert records["scaling.views.campaign_trials_per_min.v143"].anchor_value == 150.0
    assert records["scaling.views.oracle_ms_per_view.v143"].value == pytest.approx(1e3 * 0.5 * 1.43 / 143)
    assert "oracle share 60%" in records["scaling.views.campaign_trials_per_min.v600"].note
