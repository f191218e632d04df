import math

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from wrp_eval.config import ExperimentConfig, load_experiment
from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.particulars import ShipType
from wrp_eval.ship.resolve import resolve_particulars

from .conftest import type1, type5


def test_defaults_are_the_papers_stylized_ship():
    section = ExperimentConfig().ship
    p, provenance = resolve_particulars(section)
    assert (p.length_bp_m, p.breadth_m) == (140.0, 20.0)
    assert p.height_above_water_m == pytest.approx(25.0)
    assert p.depth_m == pytest.approx(12.0) and p.draft_m == pytest.approx(8.0)
    assert provenance["length_bp_m"] == "type default" and provenance["depth_m"].startswith("derived")


def test_every_type_has_consistent_defaults():
    for t in ShipType:
        p, _ = resolve_particulars(ShipSection(type=t))
        assert 0 < p.draft_m < p.depth_m and p.breadth_m < p.length_bp_m
        assert 9.7 - 1e-9 <= p.length_bp_m / p.depth_m <= 13.2 + 1e-9
        assert 0.63 - 1e-9 <= p.draft_m / p.depth_m <= 0.78 + 1e-9


def test_overrides_and_ais_in_config(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump({"ship": {"ais": type5() + type1(), "particulars": {"depth_m": 15.0}}}))
    p, provenance = resolve_particulars(load_experiment(cfg).ship, tmp_path, str(cfg))
    assert p.ship_type is ShipType.CONTAINER and p.depth_m == 15.0 and provenance["draft_m"] == "ais"
    assert provenance["depth_m"] == "config" and p.derived == {"superstructure_height_m"}


def test_ais_file_relative_to_config(tmp_path):
    (tmp_path / "ship.nmea").write_text("# recorded\n" + "\n".join(type5()) + "\n\n")
    cfg = tmp_path / "c.yaml"
    cfg.write_text("ship:\n  type: tanker\n  ais_file: ship.nmea\n")
    p, provenance = resolve_particulars(load_experiment(cfg).ship, tmp_path, str(cfg))
    assert p.ship_type is ShipType.TANKER and provenance["ship_type"] == "config" and p.length_bp_m == 140


def test_bad_ais_line_in_file_is_named(tmp_path):
    (tmp_path / "ship.nmea").write_text(type5()[0] + "\nnonsense\n")
    section = ShipSection(ais_file="ship.nmea")
    with pytest.raises(InputError, match=r"ship.nmea line 2: not an NMEA sentence"):
        resolve_particulars(section, tmp_path)


@pytest.mark.parametrize("ship,key,problem", [
    ({"particulars": {"length_bp_m": -3}}, "ship.particulars.length_bp_m", "greater than 0"),
    ({"particulars": {"draft_m": 12, "depth_m": 10}}, "ship.particulars", "draft_m"),
    ({"particulars": {"breadth_m": 50, "length_bp_m": 40}}, "ship.particulars", "exceeds"),
    ({"particulars": {"heading_deg": 360}}, "ship.particulars.heading_deg", "less than 360"),
    ({"particulars": {"draft_m": ".nan"}}, "ship.particulars.draft_m", ""),
    ({"type": "submarine"}, "ship.type", "Input should be"),
    ({"colour": "red"}, "ship.colour", "unknown key"),
    ({"mesh": "castle"}, "ship.mesh", "procedural"),
    ({"mesh": {"path": "a.stl", "up_axis": "w"}}, "ship.mesh.up_axis", "Input should be"),
    ({"mesh": {"path": "a.stl", "scale": 0}}, "ship.mesh.scale", "greater than 0"),
    ({"ais": ["x"], "ais_file": "y"}, "ship", "either ais or ais_file"),
    ({"no_fly_margin_m": -1}, "ship.no_fly_margin_m", "greater than or equal"),
])
def test_impossible_values_are_one_line(tmp_path, ship, key, problem):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump({"ship": ship}).replace("'.nan'", ".nan"))
    with pytest.raises(InputError) as info:
        load_experiment(cfg)
    message = str(info.value)
    assert message.startswith(f"{cfg}: key '{key}'") and problem in message and "\n" not in message


def test_config_depth_shallower_than_ais_draught_is_caught_at_resolve():
    section = ShipSection(ais=type5(draught=8.5), particulars={"depth_m": 8.0})
    with pytest.raises(InputError, match=r"c.yaml ship: draft 8.5 m must be less than the moulded depth 8 m"):
        resolve_particulars(section, source="c.yaml")


_scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=True),
                     st.text(max_size=12), st.sampled_from(["stylized", "cruise", "procedural", "z", "y"]))
_keys = st.sampled_from(["type", "particulars", "ais", "ais_file", "mesh", "no_fly_margin_m", "length_bp_m",
                         "breadth_m", "depth_m", "draft_m", "superstructure_height_m", "heading_deg", "lat_deg",
                         "path", "scale", "up_axis", "offset_m", "bogus"])
_values = st.recursive(_scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                         st.dictionaries(_keys, inner, max_size=5)), max_leaves=12)


@settings(max_examples=200, deadline=None)
@given(st.dictionaries(st.sampled_from(["ship", "run", "other"]), _values, max_size=3))
def test_fuzz_config_parses_or_input_error(data):
    try:
        config = parse_model(ExperimentConfig, data, "fuzz.yaml")
    except InputError as err:
        assert str(err).startswith("fuzz.yaml: ") and "\n" not in str(err)
        return
    try:  # what parses must also resolve or give an InputError (never another exception)
        p, _ = resolve_particulars(config.ship, ".", "fuzz.yaml")
        assert math.isfinite(p.height_above_water_m)
    except InputError as err:
        assert "\n" not in str(err)
