"""``wrp-eval envelope``: the forecast from a real WRF file, and one line with exit status 2 for a bad grid or a
bad forecast file or time (nothing is flown before the inputs are checked)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.campaign.conftest import tiny_path
from wrp_eval.cli import main
from wrp_eval.envelope.forecast import forecast_from_file, forecast_of
from wrp_eval.frames import wind_velocity
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.field import build_mean_grid
from wrp_eval.wind.grid import interpolate

WRF = Path(__file__).parents[1] / "wind" / "data" / "wrfout_katrina_sample.nc"
SHIP = ShipParticulars(length_bp_m=100.0, breadth_m=16.0, depth_m=9.0, superstructure_height_m=12.0, draft_m=6.0,
                       lat_deg=24.5, lon_deg=-90.0, heading_deg=30.0)


@pytest.fixture
def config(tmp_path) -> Path:
    tiny_path().save(tmp_path / "path.json")
    file = tmp_path / "cfg.yaml"
    file.write_text(f"ship:\n  particulars: {{lat_deg: 24.5, lon_deg: -90.0, heading_deg: 30}}\n"
                    f"campaign:\n  path: {tmp_path / 'path.json'}\n")
    return file


@pytest.mark.parametrize("args, names", [
    (["--speeds", "4,2"], "speeds_m_s"),
    (["--speeds", "4,x"], "--speeds"),
    (["--directions", "0"], "directions"),
    (["--flights", "8", "--look", "16"], "look_flights"),
    (["--forecast", "missing.nc"], "missing.nc"),
    (["--forecast", str(WRF), "--time", "1999-01-01T00:00:00"], "1999"),
    (["--time", "2005-08-28T12:00:00"], "--forecast"),
])
def test_bad_grid_or_forecast_is_one_line_and_exit_2(config, tmp_path, capsys, args, names):
    assert main(["envelope", str(config), "--out", str(tmp_path / "env"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and names in err[0]
    assert not (tmp_path / "env").exists()


def test_the_forecast_from_a_wrf_file_is_the_mean_wind_at_the_ship():
    ship = SHIP
    forecast = forecast_from_file(WindSection(), ship, WRF, "2005-08-28T15:00:00")
    section = WindSection(source="wrf", file=str(WRF), time="2005-08-28T15:00:00")
    velocity = interpolate(build_mean_grid(section, ship), np.array([[0.0, 0.0, 10.0]]), clamp=True)[0]
    # the speed and the direction FROM, put back through the frames module, give the file's wind
    back = wind_velocity(forecast.speed_m_s, np.radians(forecast.compass_from_deg), np.radians(30.0))
    assert forecast.speed_m_s > 1.0
    np.testing.assert_allclose(back[:2], velocity[:2], atol=1e-9)
    assert forecast.relative_deg == pytest.approx((forecast.compass_from_deg - 30.0) % 360.0)
    assert "2005-08-28T15:00:00" in forecast.source
    later = forecast_from_file(WindSection(), ship, WRF, "2005-08-28T21:00:00")
    assert later.speed_m_s != forecast.speed_m_s          # the time is read, not ignored


def test_the_synthetic_forecast_is_the_wind_section_relative_to_the_bow():
    ship = SHIP
    forecast = forecast_of(WindSection(speed_10m_m_s=7.0, direction_deg=10.0), ship, None, "wind")
    assert (forecast.speed_m_s, forecast.compass_from_deg, forecast.relative_deg) == (7.0, 10.0, 340.0)
