"""The turbulence stress-test note: a preset stronger than the trial's wind implies is reported."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.campaign.config import CampaignSection
from wrp_eval.campaign.turbulence import STRESS_RATIO, preset_w20_mps, turbulence_ratios, turbulence_stress_note
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.dryden import severity_w20_mps
from wrp_eval.wind.field import TWENTY_FT_M, build_mean_wind

SHIP = (0.0, 0.0, 0.0)          # lat, lon, heading: a pose is enough for the mean wind


def _campaign(speed, severity, sigma=None) -> CampaignSection:
    return CampaignSection.model_validate({"wind": {"speed_10m_m_s": speed, "direction_deg": 270.0,
                                                    "turbulence": {"severity": severity, "sigma_w_m_s": sigma}}})


def test_the_default_turbulence_follows_the_wind_and_is_never_a_stress_test():
    campaign = CampaignSection()
    assert campaign.wind.turbulence.severity == "from_mean" and WindSection().turbulence.severity == "from_mean"
    ratios = turbulence_ratios(WindSection(), campaign, 0, 16, SHIP)
    assert np.isnan(ratios).all() and turbulence_stress_note(ratios) is None


def test_a_moderate_preset_in_a_6_m_s_wind_is_reported_with_its_ratio():
    ratios = turbulence_ratios(WindSection(), _campaign(6.0, "moderate"), 0, 4, SHIP)
    # the ratio is the preset's W20 over the trial's mean wind 20 ft above the sea
    section = WindSection(speed_10m_m_s=6.0, direction_deg=270.0)
    at_20ft = build_mean_wind([section], SHIP).velocity(np.array([[0.0, 0.0, TWENTY_FT_M]]), 0.0)[0]
    expected = severity_w20_mps("moderate") / np.hypot(at_20ft[0], at_20ft[1])
    assert ratios == pytest.approx(np.full(4, expected)) and expected > 2.0
    note = turbulence_stress_note(ratios)
    assert note.startswith("turbulence stress test: in 4 of 4 trials") and f"{expected:.1f}x" in note


def test_a_preset_matching_its_wind_is_not_reported():
    # light (W20 7.7 m/s) in a 9 m/s wind at 10 m: under the 1.5x threshold
    ratios = turbulence_ratios(WindSection(), _campaign(9.0, "light"), 0, 3, SHIP)
    assert np.all(ratios < STRESS_RATIO) and turbulence_stress_note(ratios) is None
    # an explicit sigma_w fixes W20 = 10 sigma_w
    assert preset_w20_mps("from_mean", 0.5) == 5.0 and preset_w20_mps("from_mean", None) is None
    assert preset_w20_mps("severe", None) == pytest.approx(severity_w20_mps("severe"))


def test_trials_over_a_calm_mean_wind_are_counted():
    ratios = np.array([np.nan, np.inf, 3.0, 1.2])
    note = turbulence_stress_note(ratios)
    assert note.startswith("turbulence stress test: in 2 of 4 trials") and "1 over a calm mean wind" in note
    assert turbulence_stress_note(np.array([np.inf, np.nan])).startswith("turbulence stress test: in 1 of 2")
