"""Camera conventions shared by every stage, against hand-computed values."""

import numpy as np

from wrp_eval.camera import (
    Camera,
    camera_angles,
    camera_rotations,
    in_image,
    optical_axes,
    project,
    yaw_pitch_towards,
)


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


def _level_rotations(yaw, pitch):
    """The roll-free matrices as the camera model built them before roll existed (same operations)."""
    yaw, pitch = np.asarray(yaw, dtype=float), np.asarray(pitch, dtype=float)
    z = optical_axes(yaw, pitch)
    x = np.stack([np.sin(yaw), -np.cos(yaw), np.zeros_like(yaw)], axis=-1)
    return np.stack([x, np.cross(z, x), z], axis=-1)


def _rz(a):
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


def _ry(a):
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def _rx(a):
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


def test_no_roll_is_bit_identical_to_the_level_camera():
    rng = np.random.default_rng(1)
    yaw, pitch = rng.uniform(-np.pi, np.pi, 50), rng.uniform(-np.pi / 2, np.pi / 2, 50)
    level = _level_rotations(yaw, pitch)
    assert np.array_equal(camera_rotations(yaw, pitch), level)
    assert np.array_equal(camera_rotations(yaw, pitch, None), level)
    assert np.array_equal(camera_rotations(yaw, pitch, np.zeros(50)), level)
    mixed = np.where(np.arange(50) % 2 == 0, 0.0, 0.3)  # zero-roll rows untouched in a mixed batch
    assert np.array_equal(camera_rotations(yaw, pitch, mixed)[::2], level[::2])


def test_roll_is_the_zyx_composition_yaw_pitch_roll():
    # level camera at yaw = pitch = 0 (columns right = -y, down = -z, axis = +x), turned by Rx(roll) about the
    # forward axis (right-handed: positive lowers the right side), then Ry(-pitch), then Rz(yaw)
    c0 = np.array([[0, 0, 1], [-1, 0, 0], [0, -1, 0]], dtype=float)
    yaw, pitch, roll = 0.8, -0.5, 0.3
    expected = _rz(yaw) @ _ry(-pitch) @ _rx(roll) @ c0
    np.testing.assert_allclose(camera_rotations([yaw], [pitch], [roll])[0], expected, atol=1e-14)
    # positive roll: the camera's right axis points below the horizon, by sin(roll) for a level optical axis
    right = camera_rotations([0.0], [0.0], [roll])[0, :, 0]
    assert np.isclose(right[2], -np.sin(roll))


def test_rolled_camera_turns_the_image_about_the_principal_point():
    cam = Camera()
    pos = np.zeros((1, 3))
    point = np.array([[30.0, -4.0, 2.5]])  # ahead, to the right, above the optical axis
    uv0, d0 = project(point, pos, camera_rotations([0.0], [0.0]), cam)
    roll = np.radians(10.0)
    uv1, d1 = project(point, pos, camera_rotations([0.0], [0.0], [roll]), cam)
    centre = np.array([cam.image_width_px / 2, cam.image_height_px / 2])
    r0, r1 = uv0[0, 0] - centre, uv1[0, 0] - centre
    assert np.isclose(d0[0, 0], d1[0, 0])  # roll does not change the depth along the optical axis
    assert np.isclose(np.hypot(*r0), np.hypot(*r1))  # nor the distance from the principal point
    # turning the camera clockwise (seen from behind) turns the image of the world anticlockwise on screen
    # (v down): the image angle atan2(dv, du) drops by the roll
    assert np.isclose(np.arctan2(r1[1], r1[0]), np.arctan2(r0[1], r0[0]) - roll)


def test_camera_angles_round_trip():
    rng = np.random.default_rng(2)
    yaw = rng.uniform(-np.pi, np.pi, 200)
    pitch = rng.uniform(-np.pi / 2 + 1e-3, np.pi / 2 - 1e-3, 200)
    roll = rng.uniform(-np.pi, np.pi, 200)
    y2, p2, r2 = camera_angles(camera_rotations(yaw, pitch, roll))
    np.testing.assert_allclose(y2, yaw, atol=1e-9)
    np.testing.assert_allclose(p2, pitch, atol=1e-12)
    np.testing.assert_allclose(r2, roll, atol=1e-9)
    # nadir (gimbal lock): yaw and roll turn about the same axis; the matrix is still reproduced
    nadir = camera_rotations(yaw[:5], np.full(5, -np.pi / 2), roll[:5])
    y3, p3, r3 = camera_angles(nadir)
    np.testing.assert_allclose(p3, -np.pi / 2)
    np.testing.assert_allclose(camera_rotations(y3, p3, r3), nadir, atol=1e-12)


def test_a_nadir_photo_tipped_past_the_vertical_keeps_the_form_near_its_plan():
    from scipy.spatial.transform import Rotation

    from wrp_eval.camera import angles_near_plan, camera_angles, camera_rotations

    # planned: heading 10 deg, straight down; flown: turned 2 deg about the vertical and tipped 0.1 deg past it.
    # A side view (pitch -30 deg) turned 3 deg keeps its angles whatever its plan.
    plan_yaw, plan_pitch = np.radians([10.0, 10.0]), np.radians([-90.0, -30.0])
    nadir = Rotation.from_rotvec([0.0, 0.0, np.radians(2.0)]).as_matrix() @ camera_rotations(
        plan_yaw[:1], plan_pitch[:1])[0] @ Rotation.from_rotvec([np.radians(-0.1), 0.0, 0.0]).as_matrix()
    side = camera_rotations(plan_yaw[1:] + np.radians(3.0), plan_pitch[1:])[0]
    flown = np.stack([nadir, side])
    yaw, pitch, roll = camera_angles(flown)
    assert abs(np.degrees(yaw[0] - plan_yaw[0])) > 170.0 and abs(np.degrees(roll[0])) > 170.0   # the other form
    near = angles_near_plan(yaw, pitch, roll, plan_yaw, plan_pitch)
    np.testing.assert_allclose(np.degrees(near[0][0] - plan_yaw[0]), 2.0, atol=0.05)
    np.testing.assert_allclose(np.degrees(near[1][0]), -90.1, atol=0.01)      # tipped past nadir
    np.testing.assert_allclose(np.degrees(near[2][0]), 0.0, atol=0.05)
    np.testing.assert_allclose(camera_rotations(*near), flown, atol=1e-12)     # the same rotations
    assert (near[0][1], near[1][1], near[2][1]) == (yaw[1], pitch[1], roll[1])
    # a nadir photo genuinely turned 120 deg keeps its own form (the other would need a 180 deg roll)
    turned = camera_rotations(plan_yaw[:1] + np.radians(120.0), np.radians([-89.9]))
    kept = angles_near_plan(*camera_angles(turned), plan_yaw[:1], plan_pitch[:1])
    np.testing.assert_allclose(np.degrees(kept[0] - plan_yaw[:1]), 120.0, atol=1e-9)


def test_world_rays_turn_each_direction_by_each_rotation():
    from scipy.spatial.transform import Rotation

    from wrp_eval.camera import world_rays

    rot = Rotation.random(7, random_state=3).as_matrix()
    dirs = np.random.default_rng(4).normal(size=(11, 3))
    out = world_rays(rot, dirs)
    assert out.shape == (7, 11, 3)
    np.testing.assert_allclose(out, np.einsum("nij,rj->nri", rot, dirs), rtol=0, atol=1e-15)
    assert np.array_equal(out[2, 5], rot[2, :, 0] * dirs[5, 0] + rot[2, :, 1] * dirs[5, 1] + rot[2, :, 2] * dirs[5, 2])
