"""The image-quality laws of the synthetic oracle: blur, texture, dense matching, border and angle ramps."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.recon.image_effects import (
    SIFT_BASE_SCALE_PX,
    blur_keypoint_fraction,
    border_weight,
    incidence_weight,
    keypoint_fraction,
    parallax_weights,
    patch_match_probability,
    pixel_noise_px,
    texture_keypoint_fraction,
)


def test_sharp_image_keeps_everything_and_half_a_pixel_changes_almost_nothing():
    assert blur_keypoint_fraction(0.0) == 1.0 and pixel_noise_px(0.5, 0.0) == 0.5
    assert blur_keypoint_fraction(0.5) > 0.99                  # the half-pixel rule
    assert pixel_noise_px(0.5, 0.5) < 0.5 * 1.005


def test_blur_costs_keypoints_and_precision_gradually():
    blur = np.arange(0.0, 101.0)
    kept = blur_keypoint_fraction(blur)
    noise = pixel_noise_px(0.5, blur)
    assert np.all(np.diff(kept) < 0) and np.all(np.diff(noise) > 0)
    assert np.all(kept[1:] / kept[:-1] > 0.8)                   # no cliff: one more pixel never costs 20 %
    # the scale law: the smear's std b / sqrt(12) adds in quadrature to the base scale
    assert kept[25] == pytest.approx(SIFT_BASE_SCALE_PX ** 2 / (SIFT_BASE_SCALE_PX ** 2 + 625 / 12))
    assert noise[25] / noise[0] == pytest.approx(kept[25] ** -0.5)


def test_texture_binds_only_for_views_finer_than_the_texture():
    texture = 0.005
    fine = texture / SIFT_BASE_SCALE_PX                         # GSD at which a base-scale feature spans it
    assert texture_keypoint_fraction(2 * fine, texture) == 1.0
    assert texture_keypoint_fraction(fine / 2, texture) == pytest.approx(0.25)
    assert keypoint_fraction(10.0, fine / 2, texture) == pytest.approx(0.25 * blur_keypoint_fraction(10.0))


def test_dense_matching_needs_texture_windows():
    p = patch_match_probability(np.array([0.0, 121.0, 121.0 * 20]))
    assert p[0] == 0.0 and p[1] == pytest.approx(1 - np.exp(-1)) and p[2] > 0.999


def test_border_and_angle_ramps_are_continuous_and_half_at_the_limits():
    w = border_weight(np.array([0.0, 60.0, 120.0, 3000.0]), np.full(4, 2000.0), 6000.0, 4000.0)
    np.testing.assert_allclose(w, [0.0, 0.5, 1.0, 1.0])
    limit = np.radians(80.0)
    assert incidence_weight(np.cos(limit), limit) == pytest.approx(0.5, abs=0.02)
    assert incidence_weight(np.cos(np.radians(70.0)), limit) == 1.0
    assert incidence_weight(np.cos(np.radians(86.0)), limit) == 0.0
    alpha = np.radians(np.array([0.0, 5.0, 10.0, 60.0, 70.0]))
    match, tri = parallax_weights(alpha, np.radians(5.0), np.radians(60.0))
    np.testing.assert_allclose(match, [1.0, 1.0, 1.0, 0.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(tri, [0.0, 0.5, 1.0, 0.5, 0.0], atol=1e-12)
