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
