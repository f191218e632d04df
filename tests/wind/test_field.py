"""The composed WindField and its builder."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.validation import parse_model
from wrp_eval.wind.base import WindModel
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.dryden import severity_w20_mps
from wrp_eval.wind.field import TWENTY_FT_M, build_wind_field

SHIP = (23.7, -89.5, 45.0)


def test_field_is_mean_plus_turbulence_plus_gusts():
    section = parse_model(WindSection, {"gusts": {"enabled": True, "rate_per_min": 6}}, "test")
    field = build_wind_field(section, SHIP, n_flights=3, rng=4, dt_s=0.05)
    assert isinstance(field, WindModel)
    pts = np.array([[0.0, 0.0, 20.0], [50.0, -20.0, 40.0], [-100.0, 30.0, 8.0]])
    for k in range(5):
        t = 0.05 * k
        total = field.velocity(pts, t)
        mean = field.mean.velocity(pts, t)
        turb = field.turbulence.output(field.turbulence.parameters(pts[:, 2], np.linalg.norm(mean, axis=1))[4])
        from wrp_eval.wind.dryden import rotate_to_world
        np.testing.assert_allclose(total, mean + rotate_to_world(turb, mean) + field.gusts.velocity(pts, t))


def test_w20_from_mean_and_presets():
    section = WindSection(speed_10m_mps=8.0)
    field = build_wind_field(section, SHIP, 2, 0, 0.01)
    at20 = field.mean.velocity(np.array([[0.0, 0.0, TWENTY_FT_M]]), 0)[0]
    assert field.turbulence.w20_mps[0] == pytest.approx(np.hypot(*at20[:2]))
    assert 7.0 < field.turbulence.w20_mps[0] < 8.0        # 6.1 m is a little below 10 m
    severe = build_wind_field(parse_model(WindSection, {"turbulence": {"severity": "severe"}}, "t"), SHIP, 2, 0)
    assert severe.turbulence.w20_mps[0] == pytest.approx(severity_w20_mps("severe"))
    none = build_wind_field(parse_model(WindSection, {"turbulence": {"severity": "none"}}, "t"), SHIP, 2, 0)
    assert none.turbulence is None and none.gusts is None


def test_same_seed_same_wind_and_ship_particulars_accepted():
    ship = ShipParticulars(140, 20, 12, 15, 6, lat_deg=23.7, lon_deg=-89.5, heading_deg=45.0)
    pts = np.array([[0.0, 0.0, 20.0], [10.0, 5.0, 30.0]])
    a = build_wind_field(WindSection(), ship, 2, np.random.default_rng(8), 0.02)
    b = build_wind_field(WindSection(), SHIP, 2, np.random.default_rng(8), 0.02)
    for k in range(3):
        np.testing.assert_array_equal(a.velocity(pts, 0.02 * k), b.velocity(pts, 0.02 * k))


def test_wrf_source_through_the_builder(wrf_path):
    section = parse_model(WindSection, {"source": "wrf", "file": wrf_path.name, "interpolation": "trilinear",
                                        "turbulence": {"severity": "none"}}, "test")
    field = build_wind_field(section, SHIP, 1, 0, base_dir=wrf_path.parent)
    v = field.velocity(np.array([[0.0, 0.0, 30.0]]), 0.0)
    assert 5.0 < np.linalg.norm(v) < 60.0
    with pytest.raises(InputError, match="wind.file is required"):
        parse_model(WindSection, {"source": "wrf"}, "test")
    with pytest.raises(InputError, match="no such file"):
        build_wind_field(parse_model(WindSection, {"source": "mm5", "file": "nope.nc"}, "t"), SHIP)
