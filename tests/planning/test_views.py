import numpy as np

from wrp_eval.camera import optical_axes
from wrp_eval.planning.sampling import Samples
from wrp_eval.planning.views import candidate_views, make_safe
from wrp_eval.ship.nofly import flyable


def _one_sample(proxy, face, uv):
    p = proxy.face_points(face, np.array([uv]))
    return Samples(p, proxy.normals[face][None], np.array([face]))


def test_normal_candidate_sits_on_the_normal_and_looks_back(stylized_proxy):
    s = _one_sample(stylized_proxy, 2, (10.0, 2.0))    # port face, 2 m above its mid-height
    v = candidate_views(s, stylized_proxy, 40.0, tilt_rad=0.0, n_tilts=0, min_altitude_m=5.0)
    np.testing.assert_allclose(v.positions[0], s.points[0] + 40.0 * np.array([0, 1, 0]))
    np.testing.assert_allclose(optical_axes(v.yaw, v.pitch)[0], [0, -1, 0], atol=1e-12)


def test_tilted_candidates_keep_distance_and_tilt(stylized_proxy):
    s = _one_sample(stylized_proxy, 4, (0.0, 0.0))     # centre of the deck
    tilt = np.radians(25.0)
    v = candidate_views(s, stylized_proxy, 40.0, tilt_rad=tilt, n_tilts=4, min_altitude_m=5.0)
    assert len(v) == 5 and list(v.tilt) == [0, 1, 2, 3, 4]
    rel = v.positions - s.points[0]
    np.testing.assert_allclose(np.linalg.norm(rel, axis=1), 40.0)
    np.testing.assert_allclose(np.degrees(np.arccos(rel[1:, 2] / 40.0)), 25.0)
    # every candidate looks at its sample
    axes = optical_axes(v.yaw, v.pitch)
    np.testing.assert_allclose(axes, -rel / 40.0, atol=1e-12)


def test_low_views_are_lifted_to_five_metres_and_still_look_at_the_sample(stylized_proxy):
    s = _one_sample(stylized_proxy, 3, (0.0, -12.0))   # starboard face, 0.5 m above the sea
    v = candidate_views(s, stylized_proxy, 40.0, tilt_rad=0.0, n_tilts=0, min_altitude_m=5.0)
    assert v.positions[0, 2] == 5.0
    d = s.points[0] - v.positions[0]
    np.testing.assert_allclose(optical_axes(v.yaw, v.pitch)[0], d / np.linalg.norm(d), atol=1e-12)


def test_views_inside_the_no_fly_box_are_pushed_out_along_their_ray(stylized_proxy):
    anchor = np.array([[70.0, 0.0, 12.5]])                   # bow face centre
    inside = anchor + np.array([[2.0, 0.0, 0.0]])            # 2 m in front, inside the 5 m margin
    out = make_safe(inside, anchor, stylized_proxy, 5.0)
    assert flyable(out, stylized_proxy.no_fly_bounds(), 5.0).all()
    np.testing.assert_allclose(out[0, 1:], anchor[0, 1:])    # moved along +x only
    assert 75.0 < out[0, 0] <= 75.5 + 1e-9


def test_every_candidate_is_safe(plans, proxies):
    for (ship, _method), result in plans.items():
        if result.candidates is not None:
            assert flyable(result.candidates.positions, proxies[ship].no_fly_bounds(), 5.0).all()
