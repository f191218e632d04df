"""The wind: config section."""

from __future__ import annotations

import pytest

from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model
from wrp_eval.wind.config import WindSection


def test_defaults_are_a_synthetic_field():
    cfg = parse_model(ExperimentConfig, {}, "test")
    assert cfg.wind.source == "synthetic" and cfg.wind.interpolation == "idw"


@pytest.mark.parametrize("data, message", [
    ({"speed_10m_m_s": -1}, "speed_10m_m_s"),
    ({"direction_deg": 360}, "direction_deg"),
    ({"interpolation": "cubic"}, "interpolation"),
    ({"grid": {"z_levels_m": [0, 10, 5]}}, "strictly increasing"),
    ({"turbulence": {"severity": "extreme"}}, "severity"),
    ({"bogus": 1}, "unknown key"),
])
def test_bad_sections_are_refused(data, message):
    with pytest.raises(InputError, match=message):
        parse_model(WindSection, data, "cfg.yaml")
