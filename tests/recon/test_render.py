"""The offscreen renderer of the photogrammetric oracle: textured ship, flat sea, grey sky."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.recon.oracle import prepare_ground_truth
from wrp_eval.recon.render import SEA_RGB, SKY_RGB, SolidTexture, render_views

from .conftest import ring_views


def test_render_shows_textured_ship_flat_sea_and_sky(box_on_water):
    gt = prepare_ground_truth(box_on_water, 1.0, 0)
    cs = ring_views((0, 0, 0), 25.0, (3.0,), 2, target=(0, 0, 1.0))
    images, cam = render_views(cs, gt, 120, SolidTexture(seed=0))
    assert images.shape == (2, 80, 120, 3) and images.dtype == np.uint8
    assert cam.image_width_px == 120 and cam.focal_mm == cs.camera.focal_mm
    img = images[0].reshape(-1, 3).astype(int)
    sky = np.all(np.abs(img - np.round(255 * SKY_RGB)) <= 1, axis=1)
    sea = np.all(np.abs(img - np.round(255 * SEA_RGB)) <= 1, axis=1)
    ship = ~(sky | sea)
    # level camera at 3 m looking at the box: sky above the horizon, sea below, the box in the middle
    assert sky.mean() > 0.2 and sea.mean() > 0.05 and ship.mean() > 0.1
    assert np.all(np.abs(images[0][0].astype(int) - 255 * SKY_RGB) <= 1)  # the top row is all sky
    assert img[ship].std() > 20  # the solid texture has contrast (SIFT needs it)


def test_solid_texture_is_deterministic_and_varies_in_space():
    pts = np.random.default_rng(0).uniform(-20, 20, (500, 3))
    a = SolidTexture(seed=1).albedo(pts)
    b = SolidTexture(seed=1).albedo(pts)
    c = SolidTexture(seed=2).albedo(pts)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    assert a.min() >= 0 and a.max() <= 1 and a.std() > 0.05


def test_motion_blur_kernel_is_a_normalised_segment():
    from wrp_eval.recon.render import motion_blur_kernel

    for length in (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.3, 12.7):
        k = motion_blur_kernel(length)
        assert k.sum() == pytest.approx(1.0) and len(k) % 2 == 1 and np.allclose(k, k[::-1])
        assert np.all(k >= 0)
    np.testing.assert_allclose(motion_blur_kernel(1.0), [1.0])
    np.testing.assert_allclose(motion_blur_kernel(2.0), [0.25, 0.5, 0.25])  # end taps carry the half pixels
    np.testing.assert_allclose(motion_blur_kernel(3.0), [1 / 3] * 3)
    k = motion_blur_kernel(4.3)
    # the segment's second moment: a centred box of length L has variance L^2 / 12 (+ the end taps' rounding)
    x = np.arange(len(k)) - len(k) // 2
    assert np.sqrt((k * x ** 2).sum()) == pytest.approx(4.3 / np.sqrt(12), rel=0.1)


def test_motion_blur_spreads_a_bright_column_along_the_rows():
    from wrp_eval.recon.render import motion_blur

    img = np.zeros((5, 41, 3), np.uint8)
    img[:, 20] = 240
    for length in (3.0, 7.0, 11.0):
        out = motion_blur(img, length)
        lit = np.flatnonzero(out[2, :, 0] > 0)
        assert len(lit) == int(length) and lit.mean() == pytest.approx(20.0)  # ~L columns, centred
        assert int(out[:, :, 0].sum()) == pytest.approx(int(img[:, :, 0].sum()), rel=0.02)  # energy kept (rounding)
        np.testing.assert_array_equal(out[0], out[4])  # rows only: no vertical spread
    assert motion_blur(img, 0.0) is img and motion_blur(img, 0.8) is img


def test_render_blurs_only_the_blurred_views_by_their_scaled_length(box_on_water):
    from dataclasses import replace

    from wrp_eval.recon.render import motion_blur, render_blur_px

    gt = prepare_ground_truth(box_on_water, 1.0, 0)
    cs = ring_views((0, 0, 0), 25.0, (3.0,), 2, target=(0, 0, 1.0))
    sharp, _ = render_views(cs, gt, 120, SolidTexture(seed=0))
    blur_px = np.array([0.0, 300.0])  # capture-camera pixels: 300 * 120 / 6000 = 6 render pixels
    blurred, _ = render_views(replace(cs, blur_px=blur_px), gt, 120, SolidTexture(seed=0))
    np.testing.assert_allclose(render_blur_px(replace(cs, blur_px=blur_px), 120),
                               blur_px * 120 / cs.camera.image_width_px)
    np.testing.assert_array_equal(blurred[0], sharp[0])  # zero blur: unchanged
    np.testing.assert_array_equal(blurred[1], motion_blur(sharp[1], 6.0))
    assert not np.array_equal(blurred[1], sharp[1])
