"""The config plumbing: one clear line naming the file, the key and the problem."""

import pytest
from pydantic import Field

from wrp_eval.errors import InputError
from wrp_eval.schema import StrictModel, load_model, parse_model, read_yaml


class Inner(StrictModel):
    length_m: float = Field(1.0, gt=0)


class Outer(StrictModel):
    inner: Inner = Inner()
    name: str = "x"


def test_defaults_from_empty_document(tmp_path):
    f = tmp_path / "empty.yaml"
    f.write_text("")
    assert load_model(Outer, f) == Outer()


def test_unknown_key_named_with_its_path(tmp_path):
    f = tmp_path / "c.yaml"
    f.write_text("inner:\n  lenght_m: 3\n")
    with pytest.raises(InputError) as err:
        load_model(Outer, f)
    assert str(err.value) == f"{f}: key 'inner.lenght_m': unknown key"


def test_impossible_value_names_key_and_problem(tmp_path):
    f = tmp_path / "c.yaml"
    f.write_text("inner:\n  length_m: -2\n")
    with pytest.raises(InputError) as err:
        load_model(Outer, f)
    msg = str(err.value)
    assert "inner.length_m" in msg and "greater than 0" in msg and "\n" not in msg


def test_malformed_yaml_gives_line_and_column(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text("inner: [1, 2\nname: x\n")
    with pytest.raises(InputError) as err:
        read_yaml(f)
    assert "invalid YAML at line" in str(err.value)


def test_missing_file_and_non_mapping(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_yaml(tmp_path / "nope.yaml")
    with pytest.raises(InputError, match="expected a mapping"):
        parse_model(Outer, [1, 2], "list.yaml")


def test_input_error_survives_pickling_between_processes():
    import pickle
    err = pickle.loads(pickle.dumps(InputError("cfg.yaml", "key 'x': bad")))
    assert isinstance(err, InputError) and str(err) == "cfg.yaml: key 'x': bad" and err.source == "cfg.yaml"


def test_an_old_m_s_key_is_read_as_the_new_one_with_one_deprecation_line(caplog):
    """wind.speed_10m_mps (and the other *_mps keys) were renamed *_m_s: old configs and stored campaigns keep
    working, with a warning; both names at once is one clear error."""
    import logging

    from wrp_eval.campaign.config import TurbulenceSpec
    from wrp_eval.config import ExperimentConfig
    from wrp_eval.schema import _warn_renamed
    _warn_renamed.cache_clear()
    with caplog.at_level(logging.WARNING, logger="wrp_eval"):
        cfg = ExperimentConfig.model_validate({"wind": {"speed_10m_mps": 9.0, "turbulence": {"sigma_w_mps": 1.5},
                                                        "gusts": {"amplitude_mps": 2.0}}})
    assert (cfg.wind.speed_10m_m_s, cfg.wind.turbulence.sigma_w_m_s, cfg.wind.gusts.amplitude_m_s) == (9.0, 1.5, 2.0)
    assert sum("deprecated key" in m for m in caplog.messages) == 3
    assert "wind.speed_10m_mps" in caplog.text
    assert TurbulenceSpec.model_validate({"sigma_w_mps": 0.7}).sigma_w_m_s == 0.7
    with pytest.raises(ValueError, match="deprecated name"):
        ExperimentConfig.model_validate({"wind": {"speed_10m_mps": 9.0, "speed_10m_m_s": 8.0}})
