"""Camera conventions shared by every stage, against hand-computed values."""

import numpy as np

from wrp_eval.camera import (Camera, camera_rotations, in_image, optical_axes, project,
                             yaw_pitch_towards)


def test_gsd_formula_paper_camera():
    cam = Camera()
    # GSD = D * sensor_width / (f * image_width) = 30 * 36 / (44.7846 * 6000)
    assert np.isclose(cam.gsd_m(30.0), 30 * 36 / (44.7846 * 6000))
    assert np.isclose(cam.distance_for_gsd(cam.gsd_m(17.0)), 17.0)
    w, h = cam.footprint_m(30.0)
    assert np.isclose(w / h, 1.5)


def test_rotations_are_orthonormal_and_axes_point_right_and_down():
    yaw = np.array([0.0, 0.7, -2.0])
    pitch = np.array([0.0, -0.4, -np.pi / 2 + 0.01])
    R = camera_rotations(yaw, pitch)
    assert np.allclose(np.einsum("nij,nkj->nik", R, R), np.eye(3))
    assert np.allclose(np.linalg.det(R), 1.0)
    assert np.allclose(R[:, :, 2], optical_axes(yaw, pitch))
    # yaw 0, pitch 0: looking along +x, right is -y (starboard), down is -z
    assert np.allclose(R[0, :, 0], [0, -1, 0]) and np.allclose(R[0, :, 1], [0, 0, -1])


def test_projection_of_a_point_on_the_axis_lands_at_the_centre():
    cam = Camera()
    pos = np.array([[0.0, 0.0, 10.0]])
    target = np.array([[20.0, 5.0, 0.0]])
    yaw, pitch = yaw_pitch_towards(pos, target)
    uv, depth = project(target, pos, camera_rotations(yaw, pitch), cam)
    assert np.allclose(uv[0, 0], [3000, 2000])
    assert np.isclose(depth[0, 0], np.linalg.norm(target - pos))
    # a point 1 m to the camera's right at 10 m depth moves f_px / 10 pixels right
    pos2 = np.zeros((1, 3))
    uv2, _ = project(np.array([[10.0, -1.0, 0.0]]), pos2, camera_rotations([0.0], [0.0]), cam)
    assert np.isclose(uv2[0, 0, 0] - 3000, cam.focal_px / 10)
    assert in_image(uv2, _, cam)[0, 0]
    behind_uv, behind_d = project(np.array([[-10.0, 0, 0]]), pos2, camera_rotations([0.0], [0.0]), cam)
    assert not in_image(behind_uv, behind_d, cam)[0, 0]
