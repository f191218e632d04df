import numpy as np
import pytest

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.planning.visibility import ProxyRaycaster, overlap_matrix, overlap_ratio, visibility


def test_first_hit_distance_against_the_cuboid(stylized_proxy):
    rc = ProxyRaycaster(stylized_proxy)
    origins = np.array([[0.0, 50.0, 10.0], [100.0, 0.0, 10.0], [0.0, 0.0, 100.0], [0.0, 50.0, 10.0]])
    dirs = np.array([[0, -1.0, 0], [-1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    np.testing.assert_allclose(rc.first_hit(origins, dirs)[:3], [40.0, 30.0, 75.0], rtol=1e-5)
    assert np.isinf(rc.first_hit(origins, dirs)[3])


def _vis(proxy, points, normals, positions, targets, d_max=100.0, cam=Camera()):
    yaw, pitch = yaw_pitch_towards(positions, targets)
    return visibility(points, normals, positions, yaw, pitch, cam, ProxyRaycaster(proxy), d_max,
                      np.radians(85.0))


def test_each_visibility_condition(stylized_proxy):
    s = np.array([[0.0, 10.0, 12.5]])                   # port face centre
    n = np.array([[0.0, 1.0, 0.0]])
    positions = np.array([
        [0.0, 50.0, 12.5],     # in front, looking at it: visible
        [0.0, -50.0, 12.5],    # behind the ship: back side, occluded
        [0.0, 150.0, 12.5],    # beyond d_max = 100 m
        [400.0, 10.5, 12.5],   # grazing: theta > 85 deg (and beyond d_max)
        [30.0, 50.0, 12.5],    # in front but looking 30 m to the side: outside the image
    ])
    targets = np.array([s[0], s[0], s[0], s[0], [60.0, 10.0, 12.5]])
    vis = _vis(stylized_proxy, s, n, positions, targets, d_max=100.0)
    assert vis[:, 0].tolist() == [True, False, False, False, False]


def test_incidence_limit_alone(stylized_proxy):
    s = np.array([[0.0, 10.0, 12.5]])
    n = np.array([[0.0, 1.0, 0.0]])
    for angle, seen in ((84.0, True), (86.0, False)):
        a = np.radians(angle)
        pos = s + 30.0 * np.array([[np.sin(a), np.cos(a), 0.0]])
        assert _vis(stylized_proxy, s, n, pos, s, d_max=1000.0)[0, 0] == seen


def test_overlap_ratio_hand_computed():
    a = np.array([[1, 1, 1, 0]], dtype=bool)
    b = np.array([[0, 1, 1, 1]], dtype=bool)
    assert overlap_ratio(a, b)[0] == pytest.approx(2 / 3)          # 2 / ((3 + 3) / 2)
    w = np.array([1.0, 1.0, 1.0, 3.0])
    assert overlap_ratio(a, b, w)[0] == pytest.approx(2 / 4)       # 2 / ((3 + 5) / 2)
    m = overlap_matrix(np.concatenate([a, b, np.zeros((1, 4), bool)]))
    np.testing.assert_allclose(m, [[1, 2 / 3, 0], [2 / 3, 1, 0], [0, 0, 0]])


def _cheap_tests_numpy(pts, nrm, pos, rot, f, half_w, half_h, d_max, cos_max):
    """The dense float32 numpy tests visibility() ran before the compiled pass (reference)."""
    rel = pts[None, :, :] - pos[:, None, :]
    dist = np.sqrt(np.einsum("cmi,cmi->cm", rel, rel))
    cam = np.einsum("cij,cmi->cmj", rot, rel)
    depth = cam[..., 2]
    in_img = (depth > 0) & (np.abs(cam[..., 0]) * f <= half_w * depth) & (np.abs(cam[..., 1]) * f <= half_h * depth)
    cos_theta = -np.einsum("cmi,mi->cm", rel, nrm) / np.maximum(dist, 1e-9)
    return in_img & (dist <= d_max) & (cos_theta >= cos_max)


def test_compiled_cheap_tests_match_the_dense_numpy_tests():
    from wrp_eval.camera import camera_rotations
    from wrp_eval.planning.visibility import _cheap_tests

    rng = np.random.default_rng(5)
    pts = rng.uniform(-50, 50, (1500, 3)).astype(np.float32)
    nrm = rng.standard_normal((1500, 3))
    nrm = (nrm / np.linalg.norm(nrm, axis=1, keepdims=True)).astype(np.float32)
    pos = rng.uniform(-80, 80, (40, 3)).astype(np.float32)
    rot = camera_rotations(rng.uniform(-np.pi, np.pi, 40), rng.uniform(-1.3, 0.3, 40)).astype(np.float32)
    args = (pts, nrm, pos, rot, np.float32(1200.0), np.float32(1000.0), np.float32(660.0), np.float32(90.0),
            np.float32(np.cos(np.radians(85.0))))
    dense = _cheap_tests_numpy(*args)
    assert 0.01 < dense.mean() < 0.5
    np.testing.assert_array_equal(_cheap_tests(*args), dense)
