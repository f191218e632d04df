"""The photogrammetric oracle end to end on a small box (skipped where pycolmap is not installed).

Known by construction: a ring of views round a textured box reconstructs with every view registered and the
cameras where the position priors put them; a repeat gives the same numbers (seeded RANSAC, single-threaded
mapping) from the kept database, which is rebuilt only when the capture set or the settings that make the
features change; view groups that see no common surface register separately and the capture set fails.
"""

from __future__ import annotations

import dataclasses
import shutil

import numpy as np
import pytest

pycolmap = pytest.importorskip("pycolmap")

from wrp_eval.camera import Camera, yaw_pitch_towards  # noqa: E402
from wrp_eval.recon.colmap import ColmapOracle, database_fingerprint  # noqa: E402
from wrp_eval.recon.config import ColmapOracleSection, OracleSection  # noqa: E402
from wrp_eval.sim.captures import CaptureSet  # noqa: E402

from .conftest import make_box, ring_views  # noqa: E402

# small images and few features keep a run at a few seconds on 2 cores
SMALL = OracleSection(colmap=ColmapOracleSection(image_width_px=480, max_num_features=1000))


@pytest.fixture(scope="module")
def box():
    return make_box((8.0, 8.0, 6.0), (0.0, 0.0, 1.0))  # z in [-2, 4]


@pytest.fixture(scope="module")
def ring():
    # two rings of 12 (30 deg apart) 14 m out, above the box top: every view sees the top and two sides
    return ring_views((0.0, 0.0, 1.0), 14.0, (6.0, 12.0), 12)


@pytest.fixture(scope="module")
def first_run(box, ring, tmp_path_factory):
    work = tmp_path_factory.mktemp("colmap")
    return ColmapOracle(SMALL, work_dir=work).evaluate(ring, box, seed=3), work


def test_ring_round_a_box_registers_every_view_at_its_prior(first_run, ring):
    result, _ = first_run
    assert not result.failed and result.registered_views == len(ring)
    # position-prior bundle adjustment leaves the model in the capture frame: the cameras sit where the
    # priors (sigma 1 m) say before any similarity, and the points land on the box after ICP
    assert result.extra["camera_residual_before_m"] < 0.5
    assert result.accuracy_m < 0.05 and result.error_m < 0.1 and result.completeness > 0.8


def test_repeat_gives_the_same_numbers_and_reuses_the_database(first_run, box, ring):
    first, work = first_run
    again = ColmapOracle(SMALL, work_dir=work).evaluate(ring, box, seed=3)
    assert again.extra["database_reused"] and not first.extra["database_reused"]
    assert again.registered_views == first.registered_views and again.n_points == first.n_points
    assert again.error_m == first.error_m and again.completeness == first.completeness


def test_database_fingerprint_changes_with_the_capture_set_and_settings(ring):
    same = database_fingerprint(ring, "ship", SMALL, 3)
    assert database_fingerprint(ring, "ship", SMALL, 3) == same
    fewer = CaptureSet(ring.positions[:-1], ring.yaw[:-1], ring.pitch[:-1], ring.planned_index[:-1], ring.camera)
    moved = CaptureSet(ring.positions + [0.0, 0.0, 0.01], ring.yaw, ring.pitch, ring.planned_index, ring.camera)
    wider = SMALL.model_copy(update={"colmap": SMALL.colmap.model_copy(update={"image_width_px": 640})})
    others = {database_fingerprint(fewer, "ship", SMALL, 3), database_fingerprint(moved, "ship", SMALL, 3),
              database_fingerprint(ring, "other ship", SMALL, 3), database_fingerprint(ring, "ship", wider, 3),
              database_fingerprint(ring, "ship", SMALL, 4)}
    assert same not in others and len(others) == 5
    # the mapper's settings do not touch the features: a changed mapper maps again from the same database
    relaxed = SMALL.model_copy(update={"colmap": SMALL.colmap.model_copy(update={"abs_pose_min_num_inliers": 30})})
    assert database_fingerprint(ring, "ship", relaxed, 3) == same


def test_view_groups_seeing_no_common_surface_fail(box):
    # level views (below the box top, z = 4) square-on to three different faces: 4 of the +x end, 3 of the
    # -x end, 3 of the +y side; no two groups share surface, so at most 4 of 10 views can register together
    pos = np.array([[19.0, y, z] for y in (-2.0, 2.0) for z in (0.5, 2.5)]
                   + [[-19.0, y, 1.5] for y in (-2.5, 0.0, 2.5)] + [[x, 17.0, 1.5] for x in (-3.0, 0.0, 3.0)])
    target = np.array([[4.0, 0.0, 1.0]] * 4 + [[-4.0, 0.0, 1.0]] * 3 + [[0.0, 4.0, 1.0]] * 3)
    yaw, pitch = yaw_pitch_towards(pos, target)
    cs = CaptureSet(pos, yaw, pitch, np.arange(len(pos)), Camera())
    result = ColmapOracle(SMALL).evaluate(cs, box, seed=0)
    assert result.failed and result.registered_views <= 4


def test_position_priors_are_written_per_image(first_run, ring):
    _, work = first_run
    db = pycolmap.Database.open(str(work / "database.db"))
    try:
        priors = db.read_all_pose_priors()
        images = {im.image_id: im.name for im in db.read_all_images()}
    finally:
        db.close()
    assert len(priors) == len(ring)
    for prior in priors:
        view = int(images[prior.corr_data_id.id][4:8])
        np.testing.assert_allclose(prior.position, ring.positions[view])
        np.testing.assert_allclose(prior.position_covariance, np.eye(3))


def test_gnss_priors_hold_the_model_at_the_recorded_positions(first_run, box, ring, tmp_path):
    # the same images (the database is reused: priors are not part of its fingerprint) with priors off by a
    # common 2.9 m navigation bias plus 0.2 m of noise per photo
    _, work = first_run
    for name in ("database.db", "fingerprint.json"):
        shutil.copy(work / name, tmp_path / name)
    bias = np.array([2.0, -1.5, 1.5])
    gnss = ring.positions + bias + np.random.default_rng(0).normal(0.0, 0.2, ring.positions.shape)
    result = ColmapOracle(SMALL, work_dir=tmp_path).evaluate(dataclasses.replace(ring, prior_positions=gnss), box,
                                                             seed=3)
    assert result.extra["database_reused"] and result.registered_views == len(ring)
    db = pycolmap.Database.open(str(tmp_path / "database.db"))
    try:
        images = {im.image_id: im.name for im in db.read_all_images()}
        written = {int(images[p.corr_data_id.id][4:8]): p.position for p in db.read_all_pose_priors()}
    finally:
        db.close()
    np.testing.assert_allclose([written[v] for v in range(len(ring))], gnss)  # the recorded positions
    # prior BA puts the cameras at the recorded positions, i.e. a bias away from the true ones; the
    # georeferencing similarity to the true positions removes it and the points land on the box
    assert result.extra["camera_prior_residual_m"] < 0.5
    assert abs(result.extra["camera_residual_before_m"] - np.linalg.norm(bias)) < 0.5
    assert result.accuracy_m < 0.05 and result.completeness > 0.8


def test_rolled_views_render_turned_and_still_register(box, ring):
    rolled = dataclasses.replace(ring, roll=np.radians(np.where(np.arange(len(ring)) % 2 == 0, 8.0, -8.0)))
    result = ColmapOracle(SMALL).evaluate(rolled, box, seed=3)
    assert not result.failed and result.registered_views == len(ring)
    # the cameras sit at their priors, and turned as the capture rotations say (roll sign included: the
    # wrong sign would leave 16 deg, no roll 8 deg)
    assert result.extra["camera_residual_before_m"] < 0.5
    assert result.extra["camera_rotation_error_deg"] < 1.0
    assert result.accuracy_m < 0.05
