"""The synthetic MVS oracle on small scenes whose answer is known by construction."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.errors import InputError
from wrp_eval.recon.config import OracleSection, SyntheticOracleSection
from wrp_eval.recon.synthetic import SyntheticOracle, observe, ray_grid
from wrp_eval.sim.captures import CaptureSet

from .conftest import make_box, ring_views


def _views_at(positions, targets, camera=Camera()) -> CaptureSet:
    positions = np.asarray(positions, dtype=float)
    yaw, pitch = yaw_pitch_towards(positions, np.asarray(targets, dtype=float))
    return CaptureSet(positions, yaw, pitch, np.arange(len(positions)), camera)


def test_ray_grid_centre_ray_is_the_optical_axis():
    cam = Camera()
    dirs, spacing = ray_grid(cam, 5, 3)  # odd grid: the middle ray goes through the principal point
    np.testing.assert_allclose(dirs[1 * 5 + 2], [0.0, 0.0, 1.0], atol=1e-12)
    assert spacing == pytest.approx(cam.image_width_px / 5)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0)


def test_observe_hits_a_wall_at_the_known_distance(box_on_water, fast_section):
    oracle = SyntheticOracle(fast_section)
    gt = oracle.ground_truth(box_on_water)
    # a camera 20 m off the +x face (x = 5), level, looking at -x: the centre ray hits at 20 m, incidence 0
    cs = _views_at([[25.0, 0.0, 1.0]], [[0.0, 0.0, 1.0]])
    obs = observe(cs, gt, 41, 27, 1e4, np.radians(80))
    centre = obs.ray == 13 * 41 + 20
    assert obs.dist[centre] == pytest.approx([20.0], abs=1e-4)
    np.testing.assert_allclose(obs.normals[centre], [[1.0, 0.0, 0.0]], atol=1e-6)
    assert obs.points[:, 2].min() > -1e-4  # the sea hides the hull below the waterline


def test_box_seen_by_good_views_is_reconstructed(box_on_water, fast_section):
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 16, target=(0, 0, 1.5))
    result = SyntheticOracle(fast_section).evaluate(cs, box_on_water, seed=0)
    assert not result.failed and result.reason == ""
    assert result.registered_views == result.total_views == 32
    assert result.completeness > 0.95
    assert result.error_m < 0.05
    assert result.accuracy_m < 0.01
    assert result.scale == pytest.approx(1.0, abs=1e-3)


def test_face_seen_by_one_view_only_is_missing(box_on_water, fast_section):
    # a fan of views on the -x side only (azimuths 110..250 deg) sees the -x face and the long sides;
    # one extra view looks straight at the +x face, which no other view sees
    az = np.radians(np.linspace(110, 250, 12))
    fan = np.concatenate([np.column_stack([22 * np.cos(az), 22 * np.sin(az), np.full(12, h)])
                          for h in (3.0, 14.0)])
    positions = np.vstack([fan, [[25.0, 0.0, 2.0]]])
    targets = np.vstack([np.tile([0.0, 0.0, 1.5], (len(fan), 1)), [[0.0, 0.0, 2.0]]])
    cs = _views_at(positions, targets)
    oracle = SyntheticOracle(fast_section)
    result = oracle.evaluate(cs, box_on_water, seed=0)
    assert not result.failed
    gt = oracle.ground_truth(box_on_water)
    fused, _, _, _ = oracle.reconstruct(cs, gt, seed=0)
    interior = (np.abs(gt.samples[:, 1]) < 2.5) & (gt.samples[:, 2] < 3.5)
    plus_x = (gt.sample_normals[:, 0] > 0.9) & interior
    minus_x = (gt.sample_normals[:, 0] < -0.9) & interior
    assert plus_x.sum() > 20
    assert fused.existence[plus_x].max() == 0.0        # seen once: never triangulated
    assert fused.existence[minus_x].mean() > 0.9       # seen by many: reconstructed
    assert result.completeness < 0.95
    assert result.hole_part_m > result.accuracy_part_m  # the missing face dominates the error


@pytest.mark.parametrize("registration, detail", [("components", "3 disconnected view groups"),
                                                   ("incremental", "incremental registration stopped")])
def test_disconnected_view_groups_fail(registration, detail):
    long_box = make_box((90.0, 6.0, 6.0), (0.0, 0.0, 1.0))
    # three groups of three views 15 m off the port side, each group photographing its own 10 m patch
    positions = [[x + dx, 15.0, h] for x in (-40.0, 0.0, 40.0) for dx, h in ((-4, 3.0), (0, 6.0), (4, 3.0))]
    targets = [[p[0] - dx, 3.0, 1.5] for p, dx in zip(positions, [-4, 0, 4] * 3, strict=True)]
    section = OracleSection(synthetic=SyntheticOracleSection(rays_x=40, rays_y=27, registration=registration))
    result = SyntheticOracle(section).evaluate(_views_at(positions, targets), long_box, seed=0)
    assert result.failed
    assert result.registered_views == 3 and result.total_views == 9
    assert "3 of 9 views registered" in result.reason and detail in result.reason


def test_fewer_than_three_views_fail(box_on_water, fast_section):
    cs = ring_views((0, 0, 0), 22.0, (3.0,), 16, target=(0, 0, 1.5))
    two = CaptureSet(cs.positions[:2], cs.yaw[:2], cs.pitch[:2], cs.planned_index[:2], cs.camera)
    result = SyntheticOracle(fast_section).evaluate(two, box_on_water, seed=0)
    assert result.failed and "fewer than 3" in result.reason


def test_same_seed_same_result_other_seed_other_noise(box_on_water, fast_section):
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 12, target=(0, 0, 1.5))
    oracle = SyntheticOracle(fast_section)
    a = oracle.evaluate(cs, box_on_water, seed=7)
    b = SyntheticOracle(fast_section).evaluate(cs, box_on_water, seed=7)
    c = oracle.evaluate(cs, box_on_water, seed=8)
    for field in ("error_m", "accuracy_m", "completeness", "fscore", "scale", "n_points"):
        assert getattr(a, field) == getattr(b, field)
    gt = oracle.ground_truth(box_on_water)
    pa = oracle.reconstruct(cs, gt, seed=7)[0].estimates
    pc = oracle.reconstruct(cs, gt, seed=8)[0].estimates
    assert pa.shape == pc.shape and not np.array_equal(pa, pc)
    assert c.accuracy_m == pytest.approx(a.accuracy_m, rel=0.3)  # same noise level, other draw


def test_more_distant_views_give_larger_error(box_on_water):
    # same angular layout (the cameras' geometry scaled about the box), 3x the distance
    section = OracleSection(tau_m=0.02, synthetic=SyntheticOracleSection(rays_x=40, rays_y=27))
    oracle = SyntheticOracle(section)
    near = oracle.evaluate(ring_views((0, 0, 0), 20.0, (3.0, 14.0), 16, target=(0, 0, 1.5)), box_on_water)
    far = oracle.evaluate(ring_views((0, 0, 0), 60.0, (3.0, 40.0), 16, target=(0, 0, 1.5)), box_on_water)
    assert not near.failed and not far.failed
    assert far.accuracy_m > 2.0 * near.accuracy_m
    assert far.error_m > near.error_m


def test_parallax_window_and_noise_follow_the_config(box_on_water):
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 16, target=(0, 0, 1.5))
    # without the model floor the triangulation noise scales with the pixel noise
    base = SyntheticOracle(OracleSection(synthetic=SyntheticOracleSection(rays_x=40, rays_y=27, noise_floor_gsd=0)))
    noisy = SyntheticOracle(OracleSection(synthetic=SyntheticOracleSection(rays_x=40, rays_y=27, sigma_px=4.0,
                                                                           noise_floor_gsd=0)))
    a = base.evaluate(cs, box_on_water)
    b = noisy.evaluate(cs, box_on_water)
    assert b.extra["median_sigma_n_m"] == pytest.approx(8 * a.extra["median_sigma_n_m"], rel=0.05)
    assert b.extra["median_pose_sigma_m"] == pytest.approx(8 * a.extra["median_pose_sigma_m"], rel=0.05)
    # a parallax window no pair of this ring satisfies: nothing triangulates
    none = SyntheticOracle(OracleSection(synthetic=SyntheticOracleSection(
        rays_x=40, rays_y=27, parallax_min_deg=0.0, parallax_max_deg=0.5)))
    c = none.evaluate(cs, box_on_water)
    assert c.n_points == 0 and c.completeness == 0.0 and c.failed


def test_bad_capture_set_is_an_input_error(box_on_water):
    bad = CaptureSet(np.zeros((3, 2)), np.zeros(3), np.zeros(3), np.arange(3))
    with pytest.raises(InputError, match="positions has shape"):
        SyntheticOracle().evaluate(bad, box_on_water)
    nan = CaptureSet(np.full((3, 3), np.nan), np.zeros(3), np.zeros(3), np.arange(3))
    with pytest.raises(InputError, match="not all finite"):
        SyntheticOracle().evaluate(nan, box_on_water)
    twice = CaptureSet(np.zeros((3, 3)), np.zeros(3), np.zeros(3), np.arange(3), view_id=np.array([2, 0, 2]))
    with pytest.raises(InputError, match="view_id must be distinct"):
        SyntheticOracle().evaluate(twice, box_on_water)


def test_partner_cap_keeps_the_views_connected_and_bounds_the_work(box_on_water):
    # two rings: each view has ~9 candidate partners; a cap of 4 (plus the co-visibility spanning tree)
    # still registers every view and reconstructs nearly as much
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 16, target=(0, 0, 1.5))
    wide = SyntheticOracle(OracleSection(synthetic=SyntheticOracleSection(rays_x=40, rays_y=27)))
    capped = SyntheticOracle(OracleSection(synthetic=SyntheticOracleSection(rays_x=40, rays_y=27,
                                                                            max_partners=4)))
    a = wide.evaluate(cs, box_on_water)
    b = capped.evaluate(cs, box_on_water)
    assert a.registered_views == b.registered_views == 32
    assert b.extra["candidate_pairs"] < 0.8 * a.extra["candidate_pairs"]
    assert b.completeness > 0.95 * a.completeness
