"""The scaling bench's pieces that are not timings (the timings themselves are the bench's, never a test's)."""

import numpy as np
import pytest

from wrp_eval.campaign.scaling_bench import exponent, ring_captures, scaling_figure


def test_exponent_recovers_a_power_law():
    x = np.array([25, 50, 100, 200, 400])
    assert exponent(x, 0.003 * x ** 1.3) == pytest.approx(1.3)
    assert exponent(x, np.full(5, 2.0)) == pytest.approx(0.0, abs=1e-12)


def test_ring_views_face_the_ship_from_three_heights():
    cs = ring_captures(30)
    assert len(cs) == 30 and sorted(set(cs.positions[:, 2])) == [10.0, 20.0, 30.0]
    np.testing.assert_allclose(np.hypot(cs.positions[:, 0] / 110, cs.positions[:, 1] / 50), 1.0)
    # each optical axis points at the ship's centre line (x clipped to the 140 m hull, y = 0)
    to_ship = np.column_stack([np.clip(cs.positions[:, 0], -60, 60), np.zeros(30)]) - cs.positions[:, :2]
    heading = np.column_stack([np.cos(cs.yaw), np.sin(cs.yaw)])
    cosine = np.sum(heading * to_ship, axis=1) / np.linalg.norm(to_ship, axis=1)
    np.testing.assert_allclose(cosine, 1.0, atol=1e-9)
    high = cs.positions[:, 2] > 10.0
    assert np.all(cs.pitch[high] < 0) and np.allclose(cs.pitch[~high], 0.0)     # looking at the 10 m target height


def test_scaling_figure_writes_four_panels(tmp_path):
    curves = {name: ([1, 2, 4], [1.0, 2.0, 4.0], 1.0) for name in ("planning", "oracle", "flight", "campaign")}
    scaling_figure(curves, tmp_path / "scaling.png")
    assert (tmp_path / "scaling.png").stat().st_size > 5000
