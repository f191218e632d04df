"""The oracle-response yardstick (issue 17): roughness under pose jitter, single-view effects, their retest."""

import numpy as np
import pytest

from wrp_eval.recon.response import box_single_view_moves, oracle_response, shifted
from wrp_eval.recon.scenarios import reference_capture_set, ship_like_mesh
from wrp_eval.recon.synthetic import SyntheticOracle


def test_moves_touch_one_view_each_within_the_box():
    offsets = box_single_view_moves(10, 50, np.random.default_rng(1))
    moved = np.count_nonzero(np.any(offsets != 0.0, axis=2), axis=1)
    assert moved.tolist() == [1] * 50
    assert np.abs(offsets[..., :3]).max() <= 2.0 and np.abs(offsets[..., 3]).max() <= np.radians(20.0)


def test_without_jitter_there_is_no_roughness_and_the_retest_repeats_itself():
    captures = reference_capture_set(16)
    response = oracle_response(SyntheticOracle(), ship_like_mesh(), captures, draws=3, moves=6, seed=2,
                               jitter_position_m=0.0, jitter_yaw_rad=0.0)
    assert response.roughness_m == pytest.approx(0.0, abs=1e-12)  # identical errors (std of equal floats ~1 ulp)
    assert response.single_view_effect_m > 0.0                 # moving one view of 16 changes the error
    assert response.retest_spearman == pytest.approx(1.0)       # the same moves, measured twice, identically
    assert response.ratio == pytest.approx(0.0, abs=1e-12) and response.draws == 3 and response.moves == 6


def test_shifted_moves_positions_and_yaw_only():
    captures = reference_capture_set(4)
    offsets = np.tile([1.0, -2.0, 0.5, 0.1], (4, 1))
    moved = shifted(captures, offsets)
    np.testing.assert_allclose(moved.positions, captures.positions + offsets[:, :3])
    np.testing.assert_allclose(moved.yaw, captures.yaw + 0.1)
    assert np.array_equal(moved.pitch, captures.pitch)
