"""Pieces of the photogrammetric oracle that do not need a COLMAP run (that one is in bench / validate)."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.recon.colmap import _similarity_from_centres, rotation_errors_deg, sparse_surfels


def test_similarity_from_camera_centres_recovers_a_known_transform():
    rng = np.random.default_rng(0)
    src = rng.uniform(-50, 50, (20, 3))
    angle = np.radians(30)
    rot = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    dst = 2.5 * src @ rot.T + [10.0, -4.0, 3.0]
    t = _similarity_from_centres(src, dst)
    np.testing.assert_allclose(src @ t[:3, :3].T + t[:3, 3], dst, atol=1e-8)


def test_sparse_surfels_of_a_plane_have_plane_normals_and_neighbour_radii():
    xy = np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0)), -1).reshape(-1, 2)  # 1 m grid
    surfels = sparse_surfels(np.column_stack([xy, np.full(len(xy), 2.0)]))
    np.testing.assert_allclose(np.abs(surfels.normals[:, 2]), 1.0, atol=1e-6)
    inner = (xy[:, 0] > 0) & (xy[:, 0] < 9) & (xy[:, 1] > 0) & (xy[:, 1] < 9)
    assert surfels.radii[inner] == pytest.approx(1.0)  # the 4th neighbour of a grid point is 1 m away


def test_rotation_errors_measure_the_angle_after_the_similarity():
    from wrp_eval.camera import camera_rotations

    truth = camera_rotations([0.3, -1.0], [-0.4, -0.2], [0.05, 0.0])
    spin = np.radians(40.0)
    q = np.array([[np.cos(spin), -np.sin(spin), 0], [np.sin(spin), np.cos(spin), 0], [0, 0, 1]])
    model = np.einsum("ij,kjl->kil", q.T, truth)  # the same cameras in a model frame turned by -40 deg
    sim = np.eye(4)
    sim[:3, :3] = 3.0 * q  # the similarity back, with a scale
    np.testing.assert_allclose(rotation_errors_deg(model, sim, truth), 0.0, atol=1e-6)
    # one camera rolled 5 deg more in the model: 5 deg off
    extra = camera_rotations([0.3], [-0.4], [0.05 + np.radians(5.0)])
    off = rotation_errors_deg(np.einsum("ij,kjl->kil", q.T, extra), sim, truth[:1])
    np.testing.assert_allclose(off, 5.0, atol=1e-6)


def test_database_fingerprint_changes_with_blur_but_not_for_a_sharp_set():
    from dataclasses import replace

    from wrp_eval.recon.colmap import database_fingerprint
    from wrp_eval.recon.config import OracleSection
    from wrp_eval.recon.scenarios import reference_capture_set

    cs = reference_capture_set(12)
    section = OracleSection()
    sharp = database_fingerprint(cs, "mesh", section, 0)
    assert database_fingerprint(replace(cs, blur_px=np.zeros(len(cs))), "mesh", section, 0) == sharp
    blurred = database_fingerprint(replace(cs, blur_px=np.full(len(cs), 8.0)), "mesh", section, 0)
    assert blurred != sharp
    assert database_fingerprint(replace(cs, blur_px=np.full(len(cs), 25.0)), "mesh", section, 0) != blurred
