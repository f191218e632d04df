"""The campaign: section validates distributions and refuses bad input with one line."""

from __future__ import annotations

import pytest

from wrp_eval.campaign.config import CampaignSection, Choice, Normal, Uniform
from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model


def test_embedded_defaults_are_valid():
    section = ExperimentConfig().campaign
    assert section.n_trials == 100 and section.backend.kind == "local"
    assert isinstance(section.wind.speed_10m_m_s, Uniform)


def test_fixed_values_and_each_distribution_parse():
    section = parse_model(CampaignSection, {"wind": {
        "speed_10m_m_s": 8,
        "direction_deg": {"dist": "normal", "mean": 90, "std": 10, "clip": [60, 120]},
        "turbulence": {"severity": {"dist": "choice", "values": ["light", "severe"], "weights": [1, 3]}},
        "mesoscale": {"time": {"dist": "choice", "values": ["2005-08-28T00:00", "2005-08-28T03:00"]}}}}, "test")
    assert section.wind.speed_10m_m_s == 8.0
    assert isinstance(section.wind.direction_deg, Normal) and section.wind.direction_deg.clip == (60, 120)
    assert isinstance(section.wind.turbulence.severity, Choice)


@pytest.mark.parametrize("campaign, needle", [
    ({"wind": {"speed_10m_m_s": {"dist": "uniform", "low": 5, "high": 2}}}, "high > low"),
    ({"wind": {"speed_10m_m_s": {"dist": "gamma", "k": 2}}}, "speed_10m_m_s"),
    ({"wind": {"direction_deg": {"dist": "normal", "mean": 0, "std": -1}}}, "std"),
    ({"wind": {"turbulence": {"severity": {"dist": "choice", "values": ["light", "hurricane"]}}}}, "hurricane"),
    ({"wind": {"turbulence": {"severity": {"dist": "choice", "values": ["light"], "weights": [1, 2]}}}},
     "weights"),
    ({"perturbation": {"design": "box", "sampler": "halton"}}, "sampler"),
    ({"backend": {"kind": "dask"}}, "backend.kind"),
    ({"n_trials": 0}, "n_trials"),
    ({"outputs": {"rerun": True, "colour": "red"}}, "unknown key"),
])
def test_bad_sections_are_one_line_input_errors(campaign, needle):
    with pytest.raises(InputError) as err:
        parse_model(ExperimentConfig, {"campaign": campaign}, "exp.yaml")
    text = str(err.value)
    assert text.startswith("exp.yaml:") and "\n" not in text and needle in text
