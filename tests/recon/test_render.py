"""The offscreen renderer of the photogrammetric oracle: textured ship, flat sea, grey sky."""

from __future__ import annotations

import numpy as np

from wrp_eval.recon.base import prepare_ground_truth
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
