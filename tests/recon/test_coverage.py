"""Per-view coverage from the oracle's observation model: twins share, a lone view owns its patch."""

import numpy as np

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.coverage import view_coverage
from wrp_eval.recon.oracle import prepare_ground_truth
from wrp_eval.sim.captures import CaptureSet

from .conftest import make_box


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
