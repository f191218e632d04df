"""Charnock roughness, the log law and the synthetic marine field (frames: tests/test_frames.py)."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.wind.boundary_layer import (
    GRAVITY_MPS2,
    VON_KARMAN,
    charnock_roughness,
    log_law_factor,
    synthetic_marine_grid,
)
from wrp_eval.wind.grid import interpolate


@pytest.mark.parametrize("u10", [2.0, 8.0, 20.0])
def test_charnock_is_a_fixed_point(u10):
    z0, ustar = charnock_roughness(u10, 0.011)
    assert z0 == pytest.approx(0.011 * ustar**2 / GRAVITY_MPS2, rel=1e-9)
    assert u10 == pytest.approx(ustar / VON_KARMAN * np.log(10 / z0), rel=1e-9)
    assert 1e-6 < z0 < 1e-2          # open-sea roughness is sub-centimetre


def test_log_law_factor():
    assert log_law_factor(10.0, 2e-4) == pytest.approx(1.0)
    assert log_law_factor(0.0, 2e-4) == 0.0
    assert log_law_factor(100.0, 2e-4) == pytest.approx(np.log(100 / 2e-4) / np.log(10 / 2e-4))


def test_synthetic_field_profile_and_direction():
    x, y, z = np.linspace(-100, 100, 11), np.linspace(-50, 50, 6), np.array([0.0, 5.0, 10.0, 50.0, 100.0])
    # wind from the bow: heading 30, from 30 -> blows toward -x
    grid = synthetic_marine_grid(8.0, 30.0, 30.0, x, y, z)
    v = interpolate(grid, np.array([[0.0, 0.0, 10.0], [0.0, 0.0, 100.0], [0.0, 0.0, 0.0]]), "trilinear")
    np.testing.assert_allclose(v[0], [-8.0, 0.0, 0.0], atol=1e-9)
    z0, _ = charnock_roughness(8.0)
    assert -v[1, 0] == pytest.approx(8.0 * np.log(100 / z0) / np.log(10 / z0))
    np.testing.assert_allclose(v[2], 0.0)


def test_synthetic_veer_and_gradient():
    x, y, z = np.linspace(-1000, 1000, 3), np.linspace(-1000, 1000, 3), np.array([0.0, 10.0, 110.0])
    grid = synthetic_marine_grid(10.0, 0.0, 90.0, x, y, z, veer_deg_per_100m=20.0, gradient_per_km=0.1)
    # heading east: bow = east, port = north. From north -> blows south = -y at 10 m, at the ship
    at10 = interpolate(grid, np.array([[0.0, 0.0, 10.0]]), "trilinear")[0]
    np.testing.assert_allclose(at10, [0.0, -10.0, 0.0], atol=1e-9)
    # 100 m higher the FROM direction has veered clockwise by 20 deg (from 020): toward 200 deg
    at110 = interpolate(grid, np.array([[0.0, 0.0, 110.0]]), "trilinear")[0]
    assert np.degrees(np.arctan2(at110[1], at110[0])) == pytest.approx(-90 - 20, abs=1e-9)
    # downwind (south = -y) 1 km: 10 % faster at 10 m
    south = interpolate(grid, np.array([[0.0, -1000.0, 10.0]]), "trilinear")[0]
    assert np.linalg.norm(south) == pytest.approx(11.0)
