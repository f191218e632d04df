"""The synthetic oracle's reconstruction: estimated poses, fused points, the two parts of the error, smoothness."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from wrp_eval.recon.config import OracleSection, SyntheticOracleSection
from wrp_eval.recon.fusion import _best_per_sample, _pair_evidence
from wrp_eval.recon.image_effects import PARALLAX_MAX_RAMP_DEG, PARALLAX_MIN_RAMP_DEG, parallax_weights
from wrp_eval.recon.synthetic import SyntheticOracle

from .conftest import ring_views


def _ring():
    return ring_views((0, 0, 0), 22.0, (3.0, 16.0), 16, target=(0, 0, 1.5))


def _pairs(sample: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every unordered pair (a, b), a < b, of observations of the same sample (sorted): the reference listing."""
    pairs = [(a, b) for a in range(len(sample)) for b in range(a + 1, len(sample)) if sample[a] == sample[b]]
    return np.array([p[0] for p in pairs], dtype=int), np.array([p[1] for p in pairs], dtype=int)


@pytest.mark.parametrize("p_min_deg, p_max_deg", [(5.0, 40.0), (1.0, 178.0), (20.0, 22.0)])
def test_pair_evidence_matches_the_pairwise_numpy_formulas(p_min_deg, p_max_deg):
    """The compiled pass over each sample's pairs against the vectorised formulas it replaced (session 18):
    parallax_weights on every pair, the log-sums by bincount. Same terms; only the rounding of arccos / log1p
    and the order of the three-term dot product may differ: equal to 1e-12. Also with ramps reaching past 0 or
    pi and with overlapping ramps (the cosine shortcuts must not decide there)."""
    rng = np.random.default_rng(3)
    sample = np.sort(rng.integers(0, 40, 300))
    rel = rng.normal(size=(300, 3)) * 20.0
    dist = np.linalg.norm(rel, axis=1)
    weight = rng.uniform(0.0, 1.0, 300)
    weight[::7] = 0.0
    p_min, p_max = np.radians(p_min_deg), np.radians(p_max_deg)
    a, b = _pairs(sample)
    alpha = np.arccos(np.clip(np.einsum("kj,kj->k", rel[a], rel[b]) / (dist[a] * dist[b]), -1.0, 1.0))
    m_pair, t_pair = parallax_weights(alpha, p_min, p_max)
    both = weight[a] * weight[b]

    def log_none(prob, groups, n):
        return np.bincount(groups, weights=np.log1p(-np.minimum(prob, 1.0 - 1e-12)), minlength=n)

    tri, unmatched = _pair_evidence(sample, rel, dist, weight, p_min, p_max, np.radians(PARALLAX_MIN_RAMP_DEG),
                                    np.radians(PARALLAX_MAX_RAMP_DEG), 45)
    assert len(a) > 1000 and np.ptp(t_pair) > 0.1 and np.ptp(m_pair) > 0.1      # both ramps are crossed
    np.testing.assert_allclose(tri, log_none(both * t_pair, sample[a], 45), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(unmatched, log_none(np.r_[both * m_pair, both * m_pair], np.r_[a, b], 300),
                               rtol=1e-12, atol=1e-15)
    assert np.all(tri[np.setdiff1d(np.arange(45), sample)] == 0.0)         # samples without observations


def test_best_per_sample_is_the_lexsort_selection_it_replaced():
    """The compiled selection against the numpy one it replaced (session 18): the usable observations sorted by
    sample, then by decreasing weight, ties in index order (np.lexsort is stable), the first ``max_views`` of
    each sample. Identical indices, ties included."""
    rng = np.random.default_rng(5)
    sample = np.sort(rng.integers(0, 50, 2000))
    weight = rng.choice([0.0, 0.25, 0.5, 0.75, 1.0], 2000)            # many ties
    usable = rng.random(2000) > 0.3
    idx = np.flatnonzero(usable)
    order = idx[np.lexsort((-weight[idx], sample[idx]))]
    first = np.searchsorted(sample[order], sample[order], side="left")
    expected = order[np.arange(len(order)) - first < 24]
    got = _best_per_sample(sample, usable, weight, 24)
    assert np.bincount(sample[usable]).max() > 24                      # the cap bites
    np.testing.assert_array_equal(got, expected)


def test_error_is_its_hole_part_plus_its_accuracy_part(box_on_water, fast_section):
    r = SyntheticOracle(fast_section).evaluate(_ring(), box_on_water, seed=0)
    assert r.error_m == pytest.approx(r.hole_part_m + r.accuracy_part_m, rel=1e-12)
    assert r.accuracy_part_m > 0 and r.hole_part_m >= 0


def test_blur_costs_precision_and_pose_but_a_good_ring_still_registers(box_on_water, fast_section):
    oracle = SyntheticOracle(fast_section)
    ring = _ring()
    sharp = oracle.evaluate(ring, box_on_water, seed=0)
    results = [oracle.evaluate(dataclasses.replace(ring, blur_px=np.full(len(ring), b)), box_on_water, seed=0)
               for b in (5.0, 15.0, 30.0)]
    acc = [sharp.accuracy_part_m] + [r.accuracy_part_m for r in results]
    pose = [sharp.extra["median_pose_sigma_m"]] + [r.extra["median_pose_sigma_m"] for r in results]
    assert np.all(np.diff(acc) > 0) and np.all(np.diff(pose) > 0)
    assert all(r.registered_views == len(ring) for r in results)


def test_one_blurred_view_costs_less_than_all_blurred(box_on_water, fast_section):
    oracle = SyntheticOracle(fast_section)
    ring = _ring()
    one = np.zeros(len(ring))
    one[3] = 30.0
    sharp = oracle.evaluate(ring, box_on_water, seed=0)
    single = oracle.evaluate(dataclasses.replace(ring, blur_px=one), box_on_water, seed=0)
    every = oracle.evaluate(dataclasses.replace(ring, blur_px=np.full(len(ring), 30.0)), box_on_water, seed=0)
    assert sharp.error_m < single.error_m < every.error_m


def test_weakly_constrained_views_follow_their_position_priors(box_on_water):
    # with almost no keypoints the bundle adjustment keeps each camera near its GNSS prior; with the default
    # keypoint density the images decide and a 0.5 m prior error hardly moves the estimate
    ring = _ring()
    offset = np.random.default_rng(3).normal(0.0, 0.5, ring.positions.shape)
    off = dataclasses.replace(ring, prior_positions=ring.positions + offset)

    def camera_errors(keypoints_per_mpx):
        oracle = SyntheticOracle(OracleSection(synthetic=SyntheticOracleSection(
            rays_x=40, rays_y=27, keypoints_per_mpx=keypoints_per_mpx)))
        gt = oracle.ground_truth(box_on_water)
        return (oracle.reconstruct(off, gt, seed=0)[0].camera_position_error
                - oracle.reconstruct(ring, gt, seed=0)[0].camera_position_error)  # same draws: the pull alone

    weak, strong = camera_errors(1e-7), camera_errors(100.0)
    slope = np.sum(weak * offset) / np.sum(offset * offset)
    assert 0.5 < slope <= 1.0                                   # pulled most of the way to the prior
    assert np.abs(strong).max() < 0.05 * np.abs(offset).max()   # the images hold the camera


def test_error_changes_smoothly_with_one_views_position(box_on_water, fast_section):
    oracle = SyntheticOracle(fast_section)
    ring = _ring()
    errors = []
    for dx in np.linspace(-2.0, 2.0, 21):
        positions = ring.positions.copy()
        positions[5, 0] += dx
        errors.append(oracle.evaluate(dataclasses.replace(ring, positions=positions), box_on_water, seed=0).error_m)
    steps = np.abs(np.diff(errors))
    span = max(errors) - min(errors)
    assert span > 0
    assert steps.max() < 0.35 * span   # no jump: 20 steps of 0.2 m, none carries a third of the change


def test_missing_view_leaves_the_other_draws_in_place(box_on_water, fast_section):
    # common random numbers: the draws belong to ground-truth samples and planned views, not to positions
    oracle = SyntheticOracle(fast_section)
    ring = _ring()
    gt = oracle.ground_truth(box_on_water)
    full = oracle.reconstruct(ring, gt, seed=4)[0]
    again = oracle.reconstruct(ring, gt, seed=4)[0]
    np.testing.assert_array_equal(full.estimates, again.estimates)
    fewer = oracle.reconstruct(ring.subset(np.arange(len(ring)) != 7), gt, seed=4)[0]
    change = np.linalg.norm(fewer.estimates - full.estimates, axis=1)
    assert np.median(change) < 0.2 * np.median(full.sigma_n[np.isfinite(full.sigma_n)])


def test_colmap_conditions_coarser_pixels_and_fewer_points_raise_the_error(box_on_water, fast_section):
    from wrp_eval.recon.calibration import at_width, colmap_equivalent
    ring = dataclasses.replace(_ring(), blur_px=np.full(32, 6.0))
    small = at_width(ring, 800)
    assert small.camera.image_width_px == 800 and small.camera.image_height_px == 533
    assert small.camera.half_fov_x == pytest.approx(ring.camera.half_fov_x)
    np.testing.assert_allclose(small.blur_px, 0.8)
    oracle = SyntheticOracle(fast_section)
    full = oracle.evaluate(ring, box_on_water, seed=0)
    eq = colmap_equivalent(oracle, ring, box_on_water, n_points=60, width_px=800)
    assert full.error_m < eq["width_error_m"] < eq["sparse_error_m"]
    assert eq["sparse_completeness"] < full.completeness


def _in_view_numpy(samples, normals, centres, rot, focal_px, width, height, max_dist, cos_min):
    """The dense (S, V, 3) numpy test observe_samples used before the compiled scan (reference)."""
    rel = samples[:, None, :] - centres[None, :, :]
    cam = np.matmul(rel.transpose(1, 0, 2), rot).transpose(1, 0, 2)
    z = cam[..., 2]
    zs = np.where(z > 1e-9, z, 1e-9)
    u = focal_px * cam[..., 0] / zs + width / 2
    v = focal_px * cam[..., 1] / zs + height / 2
    dist = np.sqrt(np.sum(rel * rel, axis=2))
    cos_inc = np.abs(np.matmul(rel, normals[:, :, None])[..., 0]) / np.maximum(dist, 1e-9)
    return (z > 1e-9) & (u > 0) & (u < width) & (v > 0) & (v < height) & (dist <= max_dist) & (cos_inc > cos_min)


def test_compiled_view_test_keeps_the_pairs_the_dense_numpy_test_kept():
    from wrp_eval.camera import camera_rotations
    from wrp_eval.recon.fusion import _in_view

    rng = np.random.default_rng(3)
    samples = rng.uniform(-40, 40, (2000, 3))
    normals = rng.standard_normal((2000, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    centres = rng.uniform(-60, 60, (25, 3))
    rot = np.ascontiguousarray(camera_rotations(rng.uniform(-np.pi, np.pi, 25), rng.uniform(-1.2, 0.3, 25)))
    args = (samples, normals, centres, rot, 900.0, 1200.0, 800.0, 70.0, np.cos(np.radians(85.0)))
    dense = _in_view_numpy(*args)
    assert 0.02 < dense.mean() < 0.5  # a mix of kept and rejected pairs
    np.testing.assert_array_equal(_in_view(*args), dense)


def test_a_tour_flown_the_other_way_keeps_each_viewpoints_draws(box_on_water, fast_section):
    # the views listed in reverse flying order, each with its plan's view id: the same reconstruction; numbered by
    # flying order alone (no view ids) every view would draw another view's noise
    oracle = SyntheticOracle(fast_section)
    ring = _ring()
    gt = oracle.ground_truth(box_on_water)
    order = np.arange(len(ring))[::-1]
    flown_back = dataclasses.replace(ring.subset(order), planned_index=np.arange(len(ring)), view_id=order)
    np.testing.assert_array_equal(flown_back.view_ids(), order)
    full = oracle.reconstruct(ring, gt, seed=4)[0]
    back = oracle.reconstruct(flown_back, gt, seed=4)[0]
    np.testing.assert_allclose(back.estimates, full.estimates, rtol=0, atol=1e-9)
    renumbered = oracle.reconstruct(dataclasses.replace(flown_back, view_id=None), gt, seed=4)[0]
    assert np.abs(renumbered.estimates - full.estimates).max() > 1e-6
    ahead = oracle.evaluate(ring, box_on_water, seed=4)
    back_result = oracle.evaluate(flown_back, box_on_water, seed=4)      # scored in plan order: the same result
    assert back_result.error_m == ahead.error_m
    np.testing.assert_array_equal(back_result.registered_mask, ahead.registered_mask[order])
    # the registration order, given as positions in each set, names the same viewpoints
    back_ids = flown_back.view_ids()[back_result.extra["registration_order"]]
    np.testing.assert_array_equal(back_ids, np.asarray(ahead.extra["registration_order"]))
