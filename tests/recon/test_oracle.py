"""Ground truth preparation, surfel distances and the ICP-with-scale alignment."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from wrp_eval.recon.oracle import (
    Surfels,
    apply_similarity,
    prepare_ground_truth,
    score_reconstruction,
    surfel_distances,
)

from .conftest import make_box


def test_surfel_distance_hand_computed():
    surfels = Surfels(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.array([1.0]))
    queries = np.array([[0.5, 0.0, 0.3],   # above the disc: normal distance only
                        [2.0, 0.0, 0.0],   # in plane, 1 m beyond the rim
                        [0.0, 2.0, -1.0]])  # beyond the rim and below
    d = surfel_distances(queries, surfels)
    np.testing.assert_allclose(d, [0.3, 1.0, np.sqrt(2.0)], atol=1e-12)


def test_ground_truth_is_above_water_and_outside(box_on_water):
    gt = prepare_ground_truth(box_on_water, density_per_m2=4.0, seed=0)
    assert gt.samples[:, 2].min() > 0
    # above-water area: top 60 + sides 2 * (10 + 6) * 4 = 188 m^2 -> about 4 * 188 samples
    assert abs(len(gt.samples) - 4 * 188) < 0.1 * 4 * 188
    assert gt.area_m2 > 0


def test_enclosed_faces_are_not_ground_truth():
    lower = make_box((10.0, 10.0, 2.0), (0.0, 0.0, 1.0))
    upper = make_box((4.0, 4.0, 2.0), (0.0, 0.0, 3.0))  # its floor lies on the lower box's roof
    gt = prepare_ground_truth(trimesh.util.concatenate([lower, upper]), density_per_m2=8.0, seed=0)
    at_deck = np.abs(gt.samples[:, 2] - 2.0) < 1e-6
    under_house = at_deck & (np.abs(gt.samples[:, 0]) < 1.9) & (np.abs(gt.samples[:, 1]) < 1.9)
    assert at_deck.sum() > 100          # the exposed part of the roof is kept
    assert under_house.sum() == 0       # the roof under the house and the house floor are dropped


def test_same_seed_same_ground_truth(box_on_water):
    a = prepare_ground_truth(box_on_water, 2.0, seed=3)
    b = prepare_ground_truth(box_on_water, 2.0, seed=3)
    np.testing.assert_array_equal(a.samples, b.samples)


def _similarity(scale, angle_deg, translation):
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    t = np.eye(4)
    t[:3, :3] = scale * np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    t[:3, 3] = translation
    return t


def test_icp_with_scale_corrects_a_perturbed_reconstruction(box_on_water):
    gt = prepare_ground_truth(box_on_water, density_per_m2=20.0, seed=1)
    exact = Surfels(gt.samples.copy(), gt.sample_normals.copy(), np.full(len(gt.samples), 0.15))
    perturbed = apply_similarity(_similarity(1.02, 1.0, (0.15, -0.1, 0.1)), exact)
    unaligned = score_reconstruction(perturbed, gt, tau_m=0.05, max_correspondence_m=1.0, max_iterations=0)
    aligned = score_reconstruction(perturbed, gt, tau_m=0.05, max_correspondence_m=1.0, max_iterations=50)
    assert unaligned.accuracy_m > 0.08
    assert aligned.accuracy_m < 0.01
    assert aligned.scale == pytest.approx(1 / 1.02, abs=2e-3)
    assert aligned.completeness > 0.97 > unaligned.completeness
