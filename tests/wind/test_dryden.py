"""Dryden turbulence: MIL-F-8785C parameters, exact ZOH, PSD and sigma validation, determinism."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.signal import cont2discrete, welch

from wrp_eval.wind.dryden import (
    FT_M,
    DrydenTurbulence,
    _zoh,
    continuous_filters,
    dryden_parameters,
    dryden_psd,
    rotate_to_world,
    severity_w20_mps,
)


def test_parameters_hand_computed_at_100_ft():
    h = 100 * FT_M
    sigma, length = dryden_parameters(h, 10.0)
    base = 0.177 + 0.000823 * 100
    assert length[2] == pytest.approx(h)
    assert length[0] == length[1] == pytest.approx(100 / base**1.2 * FT_M)
    assert sigma[2] == pytest.approx(1.0)
    assert sigma[0] == sigma[1] == pytest.approx(1.0 / base**0.4)
    assert severity_w20_mps("moderate") == pytest.approx(30 * 0.514444, rel=1e-5)


def test_psd_integrates_to_sigma_squared_and_matches_filters():
    sigma, length, V = np.array([1.3, 1.3, 0.8]), np.array([150.0, 150.0, 30.0]), 7.0
    for axis in range(3):
        total, _ = quad(lambda w, a=axis: dryden_psd(np.array([w]), sigma, length, V)[0, a], 0, np.inf, limit=400)
        assert total == pytest.approx(sigma[axis] ** 2, rel=1e-6)
    w = np.logspace(-3, 2, 50)
    for axis, (A, B, C, D) in enumerate(continuous_filters(sigma, length, V)):
        H = np.array([(C @ np.linalg.solve(1j * x * np.eye(len(A)) - A, B) + D)[0, 0] for x in w])
        np.testing.assert_allclose(np.abs(H) ** 2, dryden_psd(w, sigma, length, V)[:, axis], rtol=1e-10)


@pytest.mark.parametrize("tau, dt", [(3.0, 0.01), (0.4, 0.05), (20.0, 0.1)])
def test_closed_form_zoh_equals_scipy(tau, dt):
    a, ar, c1, c2 = _zoh(np.array(tau), dt)
    for A, B, C, D in continuous_filters([1, 1, 1], [tau, tau, tau], 1.0)[:2]:
        Ad, Bd, *_ = cont2discrete((A, B, C, D), dt, "zoh")
        if A.shape == (1, 1):
            np.testing.assert_allclose([Ad[0, 0], Bd[0, 0]], [a, c2], rtol=1e-12)
        else:
            np.testing.assert_allclose(Ad, [[a, ar], [0, a]], rtol=1e-12, atol=1e-15)
            np.testing.assert_allclose(Bd[:, 0], [c1, c2], rtol=1e-10, atol=1e-15)


@pytest.mark.parametrize("altitude_m", [10.0, 60.0])
@pytest.mark.parametrize("w20_mps", [5.0, 12.0])
def test_series_reproduce_the_dryden_psd_and_sigma(altitude_m, w20_mps):
    """64 flights x 20k steps at 20 Hz: Welch PSD within 1 dB (mean |diff|) over 0.01 Hz..fs/5 and std
    within 5 % of sigma (>= 1000 correlation times over the batch)."""
    dt, n_flights, n_steps = 0.05, 64, 20_000
    turb = DrydenTurbulence(n_flights, dt, 7, w20_mps)
    series = turb.generate(n_steps, altitude_m, w20_mps)
    sigma, length = dryden_parameters(altitude_m, w20_mps)
    assert (n_flights * n_steps * dt) / (length.max() / w20_mps) >= 1000
    f, psd = welch(series, fs=1 / dt, nperseg=4096, axis=1)
    band = (f >= 0.01) & (f <= 0.2 / dt)
    analytic = dryden_psd(2 * np.pi * f[band], sigma, length, w20_mps) * 2 * np.pi
    db = np.abs(10 * np.log10(psd.mean(axis=0)[band] / analytic)).mean(axis=0)
    assert np.all(db < 1.0), db
    std = series.reshape(-1, 3).std(axis=0)
    np.testing.assert_allclose(std, sigma, rtol=0.05)


def test_unscaled_noise_would_fail():
    """The pi/dt scaling matters: the same filters with unit-variance noise give a far smaller std."""
    dt = 0.01
    turb = DrydenTurbulence(32, dt, 1, 10.0)
    series = turb.generate(5000, 30.0, 10.0)
    sigma, _ = dryden_parameters(30.0, 10.0)
    assert series.reshape(-1, 3).std(axis=0)[2] / np.sqrt(np.pi / dt) < 0.1 * sigma[2]


def test_generate_equals_stepping_and_is_deterministic():
    a = DrydenTurbulence(5, 0.02, 11, 8.0, block_steps=7)
    b = DrydenTurbulence(5, 0.02, 11, 8.0, block_steps=64)
    series = a.generate(300, 25.0, 8.0)
    # a mean wind of 8 m/s along +x: the world frame is the along/across/vertical one
    points, mean = np.tile([0.0, 0.0, 25.0], (5, 1)), np.tile([8.0, 0.0, 0.0], (5, 1))
    stepped = np.stack([b.velocity(points, k * 0.02, mean) for k in range(300)], 1)
    np.testing.assert_allclose(series, stepped, rtol=1e-10, atol=1e-12)
    c = DrydenTurbulence(5, 0.02, 11, 8.0)
    np.testing.assert_array_equal(c.generate(300, 25.0, 8.0), series)


def test_flights_are_independent_of_the_batch_size():
    rngs = np.random.default_rng(5).spawn(8)
    big = DrydenTurbulence(8, 0.05, rngs, 10.0).generate(200, 30.0, 10.0)
    rngs = np.random.default_rng(5).spawn(8)
    small = DrydenTurbulence(3, 0.05, rngs[:3], 10.0).generate(200, 30.0, 10.0)
    np.testing.assert_array_equal(big[:3], small)
    assert not np.allclose(big[0], big[1])


def test_velocity_rotates_u_along_the_mean_wind_and_uses_the_airspeed_floor():
    turb = DrydenTurbulence(2, 0.05, 3, 10.0, airspeed_floor_m_s=2.0)
    mean = np.array([[0.0, 5.0, 0.0], [0.0, 0.0, 0.0]])        # flight 0: wind toward +y; flight 1: calm
    pts = np.array([[0.0, 0.0, 30.0], [0.0, 0.0, 30.0]])
    world = turb.velocity(pts, 0.0, mean)
    sigma, length, v, tau, gain = turb.parameters(pts[:, 2], np.linalg.norm(mean, axis=1))
    local = turb.output(gain)
    np.testing.assert_allclose(world[0], [-local[0, 1], local[0, 0], local[0, 2]])   # u -> +y, v -> -x
    np.testing.assert_allclose(world[1], local[1])                                     # calm: u along x
    np.testing.assert_allclose(v, [5.0, 2.0])
    with pytest.raises(ValueError, match="time must not decrease"):
        turb.velocity(pts, 1.0, mean), turb.velocity(pts, 0.5, mean)
    np.testing.assert_allclose(rotate_to_world(np.array([[1.0, 0, 0]]), np.array([[-3.0, 0, 0]])), [[-1, 0, 0]],
                               atol=1e-15)


def test_intensity_override():
    turb = DrydenTurbulence(1, 0.05, 0, w20_mps=10.0, sigma_w_override_mps=0.7)
    sigma, *_ = turb.parameters(30.0, 5.0)
    assert sigma[0, 2] == pytest.approx(0.7)
