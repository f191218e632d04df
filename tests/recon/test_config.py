"""The oracle: config section."""

from __future__ import annotations

import pytest

from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.scored_ship import make_oracle
from wrp_eval.recon.synthetic import SyntheticOracle
from wrp_eval.schema import parse_model


def test_defaults_are_valid_and_registered():
    cfg = ExperimentConfig()
    assert cfg.oracle.kind == "synthetic"
    assert cfg.oracle.synthetic.rays_x == 64 and cfg.oracle.synthetic.rays_y == 43
    assert isinstance(make_oracle(cfg.oracle), SyntheticOracle)


def test_bad_values_are_one_line_input_errors():
    with pytest.raises(InputError, match="oracle.tau_m"):
        parse_model(ExperimentConfig, {"oracle": {"tau_m": -1}}, "cfg.yaml")
    with pytest.raises(InputError, match="unknown key"):
        parse_model(ExperimentConfig, {"oracle": {"synthetic": {"rays": 3}}}, "cfg.yaml")
    with pytest.raises(InputError, match="parallax_min_deg must be below"):
        parse_model(OracleSection, {"synthetic": {"parallax_min_deg": 50, "parallax_max_deg": 40}}, "cfg.yaml")
    with pytest.raises(InputError, match="unknown oracle kind"):
        make_oracle(OracleSection(), "contextcapture")
