"""Discrete 1-cosine gusts."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.wind.gusts import OneMinusCosineGusts


def test_single_gust_shape():
    g = OneMinusCosineGusts(1, 0, horizon_s=100.0, rate_per_min=0.0, amplitude_m_s=4.0, duration_s=5.0)
    g.start_s = np.array([[10.0]])          # place one gust by hand: A/2 (1 - cos(2 pi (t - t0)/T))
    g.azimuth_rad = np.array([[np.pi / 2]])
    p = np.zeros((1, 3))
    np.testing.assert_allclose(g.velocity(p, 12.5)[0], [0.0, 4.0, 0.0], atol=1e-12)   # peak at mid-gust
    np.testing.assert_allclose(g.velocity(p, 11.25)[0], [0.0, 2.0, 0.0], atol=1e-12)  # quarter: A/2
    assert np.all(g.velocity(p, 9.99) == 0) and np.all(g.velocity(p, 15.01) == 0)
    assert np.linalg.norm(g.velocity(p, 10.0)) == pytest.approx(0.0, abs=1e-12)


def test_drawn_gusts_sum_and_determinism():
    g = OneMinusCosineGusts(4, 9, horizon_s=600.0, rate_per_min=2.0, amplitude_m_s=4.0, duration_s=5.0,
                            mean_azimuth_rad=0.5, direction_spread_deg=20.0)
    h = OneMinusCosineGusts(4, 9, 600.0, 2.0, 4.0, 5.0, 0.5, 20.0)
    np.testing.assert_array_equal(g.start_s, h.start_s)
    counts = np.isfinite(g.start_s).sum(axis=1)
    assert 5 <= counts.mean() <= 40                                         # ~ Poisson(20)
    assert np.all(np.abs(g.azimuth_rad[np.isfinite(g.start_s)] - 0.5) <= np.deg2rad(20.0))
    for t in np.linspace(0, 600, 97):
        expect = np.zeros((4, 3))
        for i in range(4):
            for s, a in zip(g.start_s[i], g.azimuth_rad[i], strict=True):
                if s <= t <= s + 5.0:
                    m = 2.0 * (1 - np.cos(2 * np.pi * (t - s) / 5.0))
                    expect[i, :2] += m * np.array([np.cos(a), np.sin(a)])
        np.testing.assert_allclose(g.velocity(np.zeros((4, 3)), t), expect, atol=1e-12)


def test_no_gusts_at_zero_rate():
    g = OneMinusCosineGusts(3, 0, 100.0, 0.0, 4.0, 5.0)
    assert np.all(g.velocity(np.zeros((3, 3)), 50.0) == 0)
