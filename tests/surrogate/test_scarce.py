"""The scarce coverage a view's move takes away from a plan (the ``scarce`` input set's channel)."""

import pickle

import numpy as np
import pytest

from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.fusion import observe_samples
from wrp_eval.recon.oracle import prepare_ground_truth
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.surrogate.scarce import scarce_coverage

from .conftest import ring_mesh, ring_views


def _exact_loss(cs: CaptureSet, gt, section: OracleSection, view: int, offset: np.ndarray, level: float) -> float:
    """sum_s [min(W_s, c) - min(W'_s, c)] with W' from the whole set re-observed, ``view`` moved by ``offset``."""
    def weights(c: CaptureSet) -> np.ndarray:
        obs = observe_samples(c, gt, np.ones(len(c), bool), section, 1.0 / section.gt_density_per_m2)
        return np.bincount(obs.sample, weights=obs.weight, minlength=len(gt.samples))
    pos, yaw = cs.positions.copy(), cs.yaw.copy()
    pos[view] += offset[:3]
    yaw[view] += offset[3]
    moved = CaptureSet(pos, yaw, cs.pitch, cs.planned_index, cs.camera)
    return float(np.sum(np.minimum(weights(cs), level) - np.minimum(weights(moved), level)))


def test_scarce_coverage_is_the_whole_set_reobserved_with_one_view_moved():
    # 10 views, fewer than the oracle's cap of views per sample: the one-view bookkeeping is then exact
    mesh, cs = ring_mesh(), ring_views(10)
    section = OracleSection()
    gt = prepare_ground_truth(mesh, section.gt_density_per_m2, section.gt_seed)
    scarce = scarce_coverage(cs, mesh, section, gt, level=2.0)
    rng = np.random.default_rng(3)
    moves = rng.uniform(-1, 1, (30, 4)) * [3.0, 3.0, 3.0, 0.4]      # 30 candidates, more than the cap of 24
    for view in (0, 4, 7):
        exact = [_exact_loss(cs, gt, section, view, m, 2.0) for m in moves]
        np.testing.assert_allclose(scarce.lost(view, moves), exact, atol=1e-9)
        assert np.ptp(exact) > 1.0              # the moves do change the scarce coverage
    np.testing.assert_allclose(scarce.lost_views(np.zeros((1, len(cs), 4))), 0.0, atol=1e-9)
    both = scarce.lost_views(np.stack([np.zeros((len(cs), 4)), np.tile(moves[0], (len(cs), 1))]))
    np.testing.assert_allclose(both[1], [scarce.lost(v, moves[:1])[0] for v in range(len(cs))])
    np.testing.assert_array_equal(scarce.lost_views(moves[:2, None], views=[7])[:, 0], scarce.lost(7, moves[:2]))
    with pytest.raises(ValueError, match="offsets must be"):
        scarce.lost_views(np.zeros((2, len(cs) - 1, 4)))


def test_scarce_coverage_survives_pickling_and_its_digest_tells_plans_apart():
    mesh, cs = ring_mesh(), ring_views(10)
    section = OracleSection()
    gt = prepare_ground_truth(mesh, section.gt_density_per_m2, section.gt_seed)
    scarce = scarce_coverage(cs, mesh, section, gt)
    copy = pickle.loads(pickle.dumps(scarce))         # a training fold's process: the scenes are prepared again
    moves = np.random.default_rng(0).uniform(-2, 2, (12, 4)) * [1, 1, 1, 0.1]
    np.testing.assert_array_equal(copy.lost(2, moves), scarce.lost(2, moves))
    assert copy.digest == scarce.digest
    assert scarce_coverage(cs, mesh, section, gt, level=3.0).digest != scarce.digest
    assert scarce_coverage(ring_views(10, radius=24.0), mesh, section, gt).digest != scarce.digest
    coarse = section.model_copy(update={"gt_density_per_m2": 1.0})
    assert scarce_coverage(cs, mesh, coarse, prepare_ground_truth(mesh, 1.0, 0)).digest != scarce.digest
