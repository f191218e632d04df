"""Motion blur of a photo against the closed forms of the image motion (Longuet-Higgins & Prazdny 1980: at the
image centre du/dt = f (-v_x / Z - w_y), dv/dt = f (-v_y / Z + w_x), camera frame x right, y down, z forward)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from wrp_eval.camera import Camera, camera_rotations
from wrp_eval.sim.blur import angular_velocity, motion_blur_px

CAMERA = Camera()
EXPOSURE_S = 1.0 / 500.0


def _looking_along_x(n: int) -> np.ndarray:
    """(n, 3, 3) world-from-camera of level cameras looking along +x (yaw 0, pitch 0)."""
    return camera_rotations(np.zeros(n), np.zeros(n))


def test_a_constant_velocity_pass_blurs_by_the_distance_flown_in_ground_pixels():
    # camera looking along +x at a wall 5 / 20 / 40 m away, flying sideways (y) or climbing (z) at 1..8 m/s: the
    # image moves by |v| t_e over one GSD = Z / f_px (camera.gsd_m), whatever the direction across the axis
    depth = np.array([5.0, 20.0, 40.0, 20.0])
    velocity = np.array([[0.0, 5.0, 0.0], [0.0, -1.0, 0.0], [0.0, 3.0, 4.0], [0.0, 0.0, -8.0]])
    blur = motion_blur_px(velocity, _looking_along_x(4), np.zeros((4, 3)), depth, EXPOSURE_S, CAMERA.focal_px)
    expected = np.linalg.norm(velocity, axis=1) * EXPOSURE_S / CAMERA.gsd_m(depth)
    assert blur == pytest.approx(expected, rel=0.02)
    assert blur == pytest.approx(expected, rel=1e-12)        # the same formula: exact up to rounding
    # 5 m/s at 5 m with a 1/500 s shutter: 10 mm of flight over 0.67 mm pixels, about 15 px
    assert 10.0 < blur[0] < 20.0


def test_flying_along_the_optical_axis_does_not_blur_the_image_centre():
    rot = camera_rotations(np.array([0.3, -2.0]), np.radians([-20.0, -90.0]))
    velocity = 6.0 * rot[:, :, 2]                            # along each optical axis
    blur = motion_blur_px(velocity, rot, np.zeros((2, 3)), np.array([10.0, 30.0]), EXPOSURE_S, CAMERA.focal_px)
    assert blur == pytest.approx([0.0, 0.0], abs=1e-9)


def test_a_pure_rotation_blurs_by_the_angle_turned_over_the_pixel_angle():
    # |w| t_e f_px, independent of the depth, for any rate across the optical axis (about x or y of the camera)
    omega = np.array([[0.0, 0.5, 0.0], [-0.2, 0.0, 0.0], [0.3, 0.4, 0.0]])
    blur = motion_blur_px(np.zeros((3, 3)), _looking_along_x(3), omega, np.array([3.0, 50.0, np.inf]), EXPOSURE_S,
                          CAMERA.focal_px)
    assert blur == pytest.approx(np.linalg.norm(omega, axis=1) * EXPOSURE_S * CAMERA.focal_px, rel=1e-12)
    # a roll about the optical axis does not move the image centre
    roll_only = motion_blur_px(np.zeros((1, 3)), _looking_along_x(1), np.array([[0.0, 0.0, 1.0]]), np.array([10.0]),
                               EXPOSURE_S, CAMERA.focal_px)
    assert roll_only == pytest.approx([0.0], abs=1e-12)


def test_panning_to_follow_the_centre_point_cancels_the_blur():
    # flying sideways at v while turning at w = v / Z keeps the centre point still: v_x / Z + w_y = 0
    rot = _looking_along_x(1)
    velocity = np.array([[0.0, 4.0, 0.0]])                   # world +y = camera -x (x right, looking along +x)
    v_cam = rot[0].T @ velocity[0]
    depth = 16.0
    omega = np.array([[0.0, -v_cam[0] / depth, 0.0]])
    assert motion_blur_px(velocity, rot, omega, np.array([depth]), EXPOSURE_S, CAMERA.focal_px) == pytest.approx(
        [0.0], abs=1e-9)
    # ... and turning the other way doubles it
    doubled = motion_blur_px(velocity, rot, -omega, np.array([depth]), EXPOSURE_S, CAMERA.focal_px)
    assert doubled[0] == pytest.approx(2.0 * 4.0 * EXPOSURE_S / CAMERA.gsd_m(depth))


def test_unknown_depth_gives_nan_blur():
    blur = motion_blur_px(np.array([[0.0, 1.0, 0.0]]), _looking_along_x(1), np.zeros((1, 3)), np.array([np.nan]),
                          EXPOSURE_S, CAMERA.focal_px)
    assert np.isnan(blur).all()


def test_angular_velocity_recovers_a_known_rate():
    # camera-frame rates w over dt: R_after = R_before exp([w] dt)
    rng = np.random.default_rng(3)
    before = camera_rotations(rng.uniform(-np.pi, np.pi, 4), rng.uniform(-1.2, 0.3, 4), rng.uniform(-0.3, 0.3, 4))
    omega = np.array([[0.0, 0.0, 0.0], [0.4, -0.1, 0.2], [0.0, 1.5, 0.0], [-2.0, 0.3, 0.7]])
    dt = 0.05
    after = before @ Rotation.from_rotvec(omega * dt).as_matrix()
    assert angular_velocity(before, after, dt) == pytest.approx(omega, abs=1e-12)


def test_a_camera_yawing_in_the_world_turns_about_its_own_down_axis():
    # a level camera yawing at +0.6 rad/s (counter-clockwise seen from above, world +z) turns about its -y axis
    # (y points down); the image centre sweeps at 0.6 rad/s, blur 0.6 t_e f_px
    dt, rate = 0.05, 0.6
    before = camera_rotations(np.array([1.0]), np.array([0.0]))
    after = camera_rotations(np.array([1.0 + rate * dt]), np.array([0.0]))
    omega = angular_velocity(before, after, dt)
    assert omega == pytest.approx(np.array([[0.0, -rate, 0.0]]), abs=1e-12)
    blur = motion_blur_px(np.zeros((1, 3)), after, omega, np.array([20.0]), EXPOSURE_S, CAMERA.focal_px)
    assert blur[0] == pytest.approx(rate * EXPOSURE_S * CAMERA.focal_px)
