import numpy as np
import pytest
from scipy.spatial.distance import pdist

from wrp_eval.camera import Camera
from wrp_eval.planning.sampling import base_radius_m, face_radii_m, poisson_samples


def test_base_radius_is_fifteen_percent_of_the_short_footprint_side():
    cam = Camera()  # 6000 x 4000 px, f = 44.7846 mm, 36 mm sensor
    distance = 56.0
    short_side = distance * 36.0 / (44.7846 * 6000) * 4000   # GSD * image height
    assert base_radius_m(cam, distance, 0.85) == pytest.approx(0.15 * short_side)


def test_radii_scale_inversely_with_complexity_and_are_capped():
    radii = face_radii_m(np.array([1.0, 1.0, 0.5, 0.25, 0.0]), base_radius=2.0, max_factor=3.0)
    np.testing.assert_allclose(radii, [2.0, 2.0, 4.0, 6.0, 6.0])


def test_bad_complexity_is_refused():
    with pytest.raises(ValueError):
        face_radii_m(np.zeros(5), 1.0, 2.0)


def test_samples_lie_on_their_faces_and_keep_the_disk_radius(stylized_proxy):
    radii = np.array([3.0, 4.0, 5.0, 5.0, 6.0])
    s = poisson_samples(stylized_proxy, radii, np.random.default_rng(1))
    lo, hi = stylized_proxy.bounds
    assert np.all(s.points >= lo - 1e-9) and np.all(s.points <= hi + 1e-9)
    for face in range(5):
        pts = s.points[s.face == face]
        n, c = stylized_proxy.normals[face], stylized_proxy.centers[face]
        np.testing.assert_allclose((pts - c) @ n, 0.0, atol=1e-9)        # on the face plane
        np.testing.assert_allclose(s.normals[s.face == face], np.broadcast_to(n, pts.shape))
        assert len(pts) > 1 and pdist(pts).min() >= radii[face] - 1e-9  # Poisson-disk property
    # density roughly one sample per ~1-2 r^2 of face area
    counts = s.counts_per_face()
    assert np.all(counts >= 0.3 * stylized_proxy.areas / radii ** 2)


def test_samples_are_reproducible_from_the_seed(stylized_proxy):
    radii = np.full(5, 5.0)
    a = poisson_samples(stylized_proxy, radii, np.random.default_rng(7))
    b = poisson_samples(stylized_proxy, radii, np.random.default_rng(7))
    np.testing.assert_array_equal(a.points, b.points)
