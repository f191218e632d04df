import mujoco
import numpy as np

from wrp_eval.sim.controller import cross, quat_to_matrix, tilt_of, wrap_angle, yaw_of


def test_quat_to_matrix_matches_mujoco():
    rng = np.random.default_rng(3)
    q = rng.standard_normal((5, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    ours = quat_to_matrix(q)
    for i in range(5):
        ref = np.zeros(9)
        mujoco.mju_quat2Mat(ref, q[i])
        assert np.allclose(ours[i], ref.reshape(3, 3))


def test_yaw_and_tilt_of_zyx_rotation():
    yaw, pitch, roll = 0.7, 0.2, -0.1
    cz, sz, cy, sy, cx, sx = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    r = (rz @ ry @ rx)[None]
    assert np.isclose(yaw_of(r)[0], yaw)
    assert np.isclose(np.cos(tilt_of(r)[0]), cy * cx)


def test_cross_and_wrap():
    rng = np.random.default_rng(4)
    a, b = rng.standard_normal((2, 6, 3))
    assert np.allclose(cross(a, b), np.cross(a, b))
    assert np.allclose(wrap_angle(np.array([3 * np.pi, -np.pi / 2, 2 * np.pi + 0.1])), [-np.pi, -np.pi / 2, 0.1])
