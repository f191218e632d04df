"""Per-view coverage from the oracle's observation model: twins share, a lone view owns its patch; the scarce coverage
a view's move takes away."""

import pickle

import numpy as np

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.coverage import scarce_coverage, view_coverage
from wrp_eval.recon.fusion import observe_samples
from wrp_eval.recon.oracle import prepare_ground_truth
from wrp_eval.sim.captures import CaptureSet

from .conftest import make_box, ring_views


def test_twin_views_share_their_patch_and_a_lone_view_owns_its_own():
    mesh = make_box((40.0, 6.0, 6.0), (0.0, 0.0, 1.0))            # a long wall facing +y and -y
    gt = prepare_ground_truth(mesh, density_per_m2=2.0, seed=0)
    # views 0 and 1 look at the +y face near x = -12 from almost the same place; view 2 at the -y face, x = +12
    pos = np.array([[-12.0, 25.0, 2.0], [-12.3, 25.0, 2.0], [12.0, -25.0, 2.0]])
    target = np.array([[-12.0, 3.0, 2.0], [-12.3, 3.0, 2.0], [12.0, -3.0, 2.0]])
    yaw, pitch = yaw_pitch_towards(pos, target)
    cs = CaptureSet(pos, yaw, pitch, np.arange(3), Camera())
    cover = view_coverage(cs, gt, OracleSection())
    assert cover.partners.tolist() == [1.0, 1.0, 0.0]
    np.testing.assert_allclose(cover.unique_share[:2], 0.5, atol=0.05)
    np.testing.assert_allclose(cover.unique_share[2], 1.0, atol=1e-9)
    np.testing.assert_allclose(cover.normal[0], [0, 1, 0], atol=1e-6)
    np.testing.assert_allclose(cover.normal[2], [0, -1, 0], atol=1e-6)
    assert abs(cover.target[0, 1] - 3.0) < 1e-6 and abs(cover.target[0, 0] + 12.0) < 3.0   # on the wall it faces


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


def test_scarce_coverage_is_the_whole_set_reobserved_with_one_view_moved(hull_with_house):
    # 10 views, fewer than the oracle's cap of views per sample: the one-view bookkeeping is then exact
    cs = ring_views((0.0, 0.0, 3.0), 22.0, [3.0, 9.0], 5)
    section = OracleSection()
    gt = prepare_ground_truth(hull_with_house, section.gt_density_per_m2, section.gt_seed)
    scarce = scarce_coverage(cs, hull_with_house, section, gt, level=2.0)
    rng = np.random.default_rng(3)
    moves = rng.uniform(-1, 1, (30, 4)) * [3.0, 3.0, 3.0, 0.4]
    for view in (0, 4, 7):
        lost = scarce.lost(view, moves)          # 30 candidates: two calls of at most the cap
        exact = [_exact_loss(cs, gt, section, view, m, 2.0) for m in moves]
        np.testing.assert_allclose(lost, exact, atol=1e-9)
        assert np.ptp(exact) > 1.0              # the moves do change the scarce coverage
    np.testing.assert_allclose(scarce.lost_views(np.zeros((1, len(cs), 4))), 0.0, atol=1e-9)
    both = scarce.lost_views(np.stack([np.zeros((len(cs), 4)), np.tile(moves[0], (len(cs), 1))]))
    np.testing.assert_allclose(both[1], [scarce.lost(v, moves[:1])[0] for v in range(len(cs))])


def test_scarce_coverage_survives_pickling_and_its_digest_tells_plans_apart(hull_with_house):
    cs = ring_views((0.0, 0.0, 3.0), 22.0, [3.0, 9.0], 5)
    section = OracleSection()
    gt = prepare_ground_truth(hull_with_house, section.gt_density_per_m2, section.gt_seed)
    scarce = scarce_coverage(cs, hull_with_house, section, gt)
    copy = pickle.loads(pickle.dumps(scarce))         # a training fold's process: the scenes are prepared again
    moves = np.random.default_rng(0).uniform(-2, 2, (12, 4)) * [1, 1, 1, 0.1]
    np.testing.assert_array_equal(copy.lost(2, moves), scarce.lost(2, moves))
    assert copy.digest() == scarce.digest()
    assert scarce_coverage(cs, hull_with_house, section, gt, level=3.0).digest() != scarce.digest()
    other = ring_views((0.0, 0.0, 3.0), 24.0, [3.0, 9.0], 5)
    assert scarce_coverage(other, hull_with_house, section, gt).digest() != scarce.digest()
