"""Shared fixtures of the wind-stage tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wrp_eval.wind.grid import WindGrid

DATA = Path(__file__).parent / "data"
WRF_SAMPLE = DATA / "wrfout_katrina_sample.nc"


@pytest.fixture(scope="session")
def wrf_path() -> Path:
    assert WRF_SAMPLE.is_file()
    return WRF_SAMPLE


@pytest.fixture(scope="session")
def wrf_dataset(wrf_path):
    import xarray as xr
    with xr.open_dataset(wrf_path, decode_times=False) as ds:
        yield ds.load()


@pytest.fixture
def random_grid() -> WindGrid:
    """A small irregular grid with random values and per-column (terrain-following) heights."""
    rng = np.random.default_rng(3)
    x = np.array([-20.0, -5.0, 0.0, 12.0, 30.0])
    y = np.array([-10.0, 0.0, 8.0, 20.0])
    base = np.array([0.0, 3.0, 9.0, 20.0, 40.0])
    heights = base[None, None, :] + rng.uniform(0.0, 0.8, (5, 4, 1)) * np.array([0, 1, 1, 1, 1])
    velocity = rng.normal(0.0, 3.0, (5, 4, 5, 3))
    return WindGrid(x, y, heights, velocity, grid_yaw_rad=0.3, source="test grid")

