import numpy as np

from wrp_eval.surrogate.features import flown_geometry


def test_flown_geometry_hand_computed():
    """A camera 10 m in front of a wall (normal +x), looking at it: standoff 10, incidence 0, pointing 0; moved
    back 10 m and sideways 10 m (yaw kept) the sight line is 45 deg off the normal and off the optical axis."""
    position = np.array([[10.0, 0.0, 0.0]])
    yaw, pitch = np.array([np.pi]), np.array([0.0])
    target, normal = np.zeros((1, 3)), np.array([[1.0, 0.0, 0.0]])
    offsets = np.array([[[0.0, 0.0, 0.0, 0.0]], [[10.0, 10.0, 0.0, 0.0]], [[0.0, 0.0, 0.0, np.pi / 2]]])
    g = flown_geometry(position, yaw, pitch, target, normal, offsets)
    assert g.shape == (3, 1, 3)
    np.testing.assert_allclose(g[0, 0], [10.0, 0.0, 0.0], atol=1e-7)
    np.testing.assert_allclose(g[1, 0], [np.hypot(20, 10), np.arctan2(10, 20), np.arctan2(10, 20)], atol=1e-7)
    np.testing.assert_allclose(g[2, 0], [10.0, 0.0, np.pi / 2], atol=1e-7)   # turned 90 deg: pointing only
