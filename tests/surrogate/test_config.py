import pytest

from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model


def test_sections_have_working_defaults():
    config = ExperimentConfig()
    assert config.surrogate.kernel % 2 == 1 and config.wrp.iterations == 1000
    assert config.wrp.attitude_samples == 50 and config.wrp.yaw_range_deg == 20


@pytest.mark.parametrize("doc,match", [
    ({"surrogate": {"kernel": 4}}, "odd"),
    ({"surrogate": {"val_fraction": 0.5, "test_fraction": 0.45}}, "10 %"),
    ({"surrogate": {"epochs": 0}}, "surrogate.epochs"),
    ({"wrp": {"kind": "other"}}, "wrp.kind"),
    ({"wrp": {"threshold_m": -1}}, "wrp.threshold_m"),
    ({"wrp": {"unknown": 1}}, "unknown key"),
])
def test_bad_sections_are_one_line_input_errors(doc, match):
    with pytest.raises(InputError, match=match) as err:
        parse_model(ExperimentConfig, doc, "cfg.yaml")
    assert "\n" not in str(err.value)
