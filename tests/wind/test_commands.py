"""The wind CLI: wind turbulence, wind field."""

from __future__ import annotations

import numpy as np

from wrp_eval.cli import main
from wrp_eval.wind.dryden import dryden_parameters


def test_turbulence_command_writes_the_series(tmp_path):
    out = tmp_path / "t.npz"
    assert main(["wind", "turbulence", "--altitude", "30", "--w20", "10", "--dt", "0.05", "--duration", "100",
                 "--seed", "3", "--out", str(out)]) == 0
    with np.load(out) as data:
        assert set(data.files) == {"t", "uvw", "sigma_uvw", "length_uvw", "airspeed"}
        assert data["uvw"].shape == (2000, 3) and data["t"][1] == 0.05
        sigma, length = dryden_parameters(30.0, 10.0)
        np.testing.assert_allclose(data["sigma_uvw"], sigma)
        np.testing.assert_allclose(data["length_uvw"], length)
        assert float(data["airspeed"]) > 10.0          # MIL shear: faster at 30 m than at 20 ft
    assert main(["wind", "turbulence", "--altitude", "30", "--w20", "10", "--dt", "0", "--out", str(out)]) == 2


def test_field_command_on_the_wrf_sample(tmp_path, wrf_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(f"ship:\n  particulars: {{lat_deg: 23.7, lon_deg: -89.5, heading_deg: 45}}\n"
                   f"wind:\n  source: wrf\n  file: {wrf_path}\n  grid: {{spacing_m: 50, z_levels_m: [0, 10, 50]}}\n")
    out = tmp_path / "out"
    assert main(["wind", "field", str(cfg), "--out", str(out), "--rerun", str(out / "w.rrd")]) == 0
    with np.load(out / "wind_field.npz") as data:
        assert data["velocity_mps"].shape == (13, 13, 2, 3)
        assert np.all(np.isfinite(data["velocity_mps"]))
    assert (out / "wind_field.png").stat().st_size > 1000 and (out / "w.rrd").stat().st_size > 100
    bad = tmp_path / "bad.yaml"
    bad.write_text("wind:\n  source: wrf\n  file: missing.nc\n")
    assert main(["wind", "field", str(bad), "--out", str(out), "--lat", "0", "--lon", "0"]) == 2
