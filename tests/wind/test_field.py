"""The composed WindField and its builder."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.wind.base import WindModel
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.dryden import severity_w20_mps
from wrp_eval.wind.field import TWENTY_FT_M, build_wind_field, sample_mean_field

SHIP = (23.7, -89.5, 45.0)


def test_field_is_mean_plus_turbulence_plus_gusts():
    section = parse_model(WindSection, {"gusts": {"enabled": True, "rate_per_min": 6}}, "test")
    field = build_wind_field([section] * 3, SHIP, 4, dt_s=0.05)
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
    section = WindSection(speed_10m_m_s=8.0)
    field = build_wind_field([section] * 2, SHIP, 0, 0.01)
    at20 = field.mean.velocity(np.array([[0.0, 0.0, TWENTY_FT_M]]), 0)[0]
    assert field.turbulence.w20_mps[0] == pytest.approx(np.hypot(*at20[:2]))
    assert 7.0 < field.turbulence.w20_mps[0] < 8.0        # 6.1 m is a little below 10 m
    severe = build_wind_field([parse_model(WindSection, {"turbulence": {"severity": "severe"}}, "t")] * 2, SHIP, 0)
    assert severe.turbulence.w20_mps[0] == pytest.approx(severity_w20_mps("severe"))
    none = build_wind_field([parse_model(WindSection, {"turbulence": {"severity": "none"}}, "t")] * 2, SHIP, 0)
    assert none.turbulence is None and none.gusts is None


def test_same_seed_same_wind_and_ship_particulars_accepted():
    ship = ShipParticulars(140, 20, 12, 15, 6, lat_deg=23.7, lon_deg=-89.5, heading_deg=45.0)
    pts = np.array([[0.0, 0.0, 20.0], [10.0, 5.0, 30.0]])
    no_wake = WindSection(air_wake={"enabled": False})   # particulars also bring the hull's air wake
    a = build_wind_field([no_wake] * 2, ship, np.random.default_rng(8), 0.02)
    b = build_wind_field([WindSection()] * 2, SHIP, np.random.default_rng(8), 0.02)
    for k in range(3):
        np.testing.assert_array_equal(a.velocity(pts, 0.02 * k), b.velocity(pts, 0.02 * k))


def test_wrf_source_through_the_builder(wrf_path):
    section = parse_model(WindSection, {"source": "wrf", "file": wrf_path.name, "interpolation": "trilinear",
                                        "turbulence": {"severity": "none"}}, "test")
    field = build_wind_field([section], SHIP, 0, base_dir=wrf_path.parent)
    v = field.velocity(np.array([[0.0, 0.0, 30.0]]), 0.0)
    assert 5.0 < np.linalg.norm(v) < 60.0
    with pytest.raises(InputError, match="wind.file is required"):
        parse_model(WindSection, {"source": "wrf"}, "test")
    with pytest.raises(InputError, match="no such file"):
        build_wind_field([parse_model(WindSection, {"source": "mm5", "file": "nope.nc"}, "t")], SHIP, 0)


def test_each_flight_flies_the_field_it_would_fly_alone_across_sources_and_times(wrf_path):
    """One batch of flights in different mean fields: synthetic ones (one geometry) and WRF outputs at two times
    (another geometry each: the level heights move with time). Row i is bit-identical to flight i alone."""
    wrf = {"source": "wrf", "file": wrf_path.name, "clamp": True}
    sections = [parse_model(WindSection, d, "t") for d in (
        {"clamp": True, "turbulence": {"severity": "light"}},
        {**wrf, "turbulence": {"severity": "none"}},
        {"clamp": True, "speed_10m_m_s": 9.0, "direction_deg": 40.0, "turbulence": {"severity": "from_mean"}},
        {**wrf, "time": "2005-08-28T16:00:00", "turbulence": {"sigma_w_m_s": 0.7}},
        {**wrf, "turbulence": {"severity": "severe"}},
    )]
    batch = build_wind_field(sections, SHIP, np.random.default_rng(5).spawn(5), 0.05, wrf_path.parent)
    alone = [build_wind_field([s], SHIP, [g], 0.05, wrf_path.parent)
             for s, g in zip(sections, np.random.default_rng(5).spawn(5), strict=True)]
    assert len(batch.mean.grids) == 4          # flights 1 and 4 share one WRF field, built once
    rng = np.random.default_rng(1)
    for k in range(40):
        points = np.column_stack([rng.uniform(-250, 250, (5, 2)), rng.uniform(3, 150, 5)])
        want = np.concatenate([w.velocity(points[i:i + 1], 0.05 * k) for i, w in enumerate(alone)])
        np.testing.assert_array_equal(batch.velocity(points, 0.05 * k), want)
    assert not np.allclose(want[1], want[3])  # the two WRF times differ (the case is not trivial)


def test_flights_of_one_section_share_one_grid_and_the_mean_takes_any_points():
    field = build_wind_field([WindSection()] * 6, SHIP, 0, 0.05)
    assert len(field.mean.grids) == 1
    assert field.mean.velocity(np.array([[0.0, 0.0, 10.0]]), 0.0).shape == (1, 3)
    with pytest.raises(ValueError, match="interpolation"):
        build_wind_field([WindSection(), WindSection(interpolation="trilinear")], SHIP, 0)


def test_sample_mean_field_on_the_grid_nodes_above_the_sea():
    section = WindSection(speed_10m_m_s=7.0, grid={"x_range_m": [-40, 40], "y_range_m": [-20, 20],
                                                    "spacing_m": 20, "z_levels_m": [0, 10, 50]})
    x, y, z, velocity = sample_mean_field(section, SHIP)
    assert x.tolist() == [-40, -20, 0, 20, 40] and y.tolist() == [-20, 0, 20] and z.tolist() == [10, 50]
    assert velocity.shape == (5, 3, 2, 3)
    np.testing.assert_allclose(np.linalg.norm(velocity[..., 0, :], axis=-1), 7.0, rtol=1e-9)  # U10 at 10 m


def test_each_flights_sea_wind_is_its_own_mean_wind_at_10_m_over_the_ship():
    # what raises the sea under each flight (ship.motion from_wind): the mean field, not the turbulence
    from wrp_eval.wind.config import TurbulenceSection
    sections = [WindSection(speed_10m_m_s=s, direction_deg=d, turbulence=TurbulenceSection(severity="severe"))
                for s, d in ((4.0, 0.0), (11.0, 135.0))]
    field = build_wind_field(sections, (0.0, 0.0, 30.0), 0, 0.05)
    np.testing.assert_allclose(field.speed_10m_at_ship(2), [4.0, 11.0], rtol=1e-9)
