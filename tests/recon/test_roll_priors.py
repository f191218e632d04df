"""Camera roll and recorded (navigation) positions reach every oracle; known by construction.

* roll None / 0 leaves every oracle bit for bit as the level camera; 180 deg of roll shows the same
  surface (a pinhole image is centrally symmetric), 90 deg turns a landscape image portrait;
* the renderer turns its image with the camera;
* COLMAP's position priors are the recorded positions when given (a stand-in pycolmap records what is
  written), the true ones otherwise; roll, not the priors, changes the database fingerprint;
* capture files carry roll and priors, and files without those columns still load.
"""

from __future__ import annotations

import dataclasses
import sys
import types
import typing

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from wrp_eval.camera import Camera
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon import colmap as colmap_module
from wrp_eval.recon.capture_io import captures_from_parquet, captures_from_path
from wrp_eval.recon.colmap import database_fingerprint, write_position_priors
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.render import SolidTexture, render_views
from wrp_eval.recon.synthetic import SyntheticOracle, observe
from wrp_eval.recon.validate import _perturbed, _subset
from wrp_eval.sim.captures import PRIOR_COLUMNS, ROLL_COLUMN, CaptureSet, pose_columns

from .conftest import make_box, ring_views


def _rolled(cs: CaptureSet, roll_rad: float) -> CaptureSet:
    return dataclasses.replace(cs, roll=np.full(len(cs), roll_rad))


@pytest.fixture
def tower():
    """A 2 x 2 m tower from z = -2 to 28 m, seen level from 40 m: taller than a landscape image, shorter than
    a portrait one (half fields of view 15.0 and 21.9 deg: 2 x 39 tan 15 = 20.9 m < 28 m < 31.3 m)."""
    return make_box((2.0, 2.0, 30.0), (0.0, 0.0, 13.0))


@pytest.fixture
def tower_ring():
    return ring_views((0, 0, 0), 40.0, (13.0,), 16, target=(0, 0, 13.0))


def test_capture_set_keeps_the_positional_form_and_carries_new_fields():
    pos = np.arange(12.0).reshape(4, 3)
    cs = CaptureSet(pos, np.zeros(4), np.zeros(4), np.arange(4), Camera())
    assert cs.roll is None and cs.prior_positions is None
    np.testing.assert_array_equal(cs.position_priors(), pos)  # None: the true positions
    full = dataclasses.replace(cs, roll=np.arange(4) * 0.1, prior_positions=pos + 2.0)
    np.testing.assert_array_equal(full.position_priors(), pos + 2.0)
    sub = full.subset(np.array([True, False, True, False]))
    np.testing.assert_array_equal(sub.roll, [0.0, 0.2])
    np.testing.assert_array_equal(sub.prior_positions, pos[[0, 2]] + 2.0)
    assert _subset(full, np.array([1, 3])).roll.tolist() == [0.1, 0.30000000000000004]


def test_perturbed_validation_set_keeps_roll_and_the_navigation_error():
    cs = ring_views((0, 0, 0), 20.0, (5.0,), 8)
    cs = dataclasses.replace(cs, roll=np.full(8, 0.05), prior_positions=cs.positions + [1.0, -2.0, 0.5])
    moved = _perturbed(cs, np.random.default_rng(0), 3.0, 5.0)
    np.testing.assert_array_equal(moved.roll, cs.roll)
    np.testing.assert_allclose(moved.prior_positions - moved.positions, [[1.0, -2.0, 0.5]] * 8)


def test_oracle_rejects_malformed_roll_and_priors(box_on_water, fast_section):
    cs = ring_views((0, 0, 0), 22.0, (3.0,), 8)
    oracle = SyntheticOracle(fast_section)
    with pytest.raises(InputError, match="roll has shape"):
        oracle.evaluate(dataclasses.replace(cs, roll=np.zeros(3)), box_on_water)
    bad = cs.positions.copy()
    bad[2, 0] = np.nan
    with pytest.raises(InputError, match="prior_positions is not all finite"):
        oracle.evaluate(dataclasses.replace(cs, prior_positions=bad), box_on_water)


def test_level_roll_is_bit_identical_and_half_turn_sees_the_same_surface(box_on_water, fast_section):
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 16, target=(0, 0, 1.5))
    oracle = SyntheticOracle(fast_section)
    level = oracle.evaluate(cs, box_on_water, seed=0)
    zero = oracle.evaluate(_rolled(cs, 0.0), box_on_water, seed=0)
    assert (zero.error_m, zero.completeness, zero.n_points, zero.scale) == (level.error_m, level.completeness,
                                                                           level.n_points, level.scale)
    # 180 deg: the ray grid is symmetric about the principal point, the same points are seen and rebuilt
    half = oracle.evaluate(_rolled(cs, np.pi), box_on_water, seed=0)
    assert half.n_points == level.n_points and half.registered_views == level.registered_views
    # 10 deg of residual roll: the image rectangle turns, other points fall inside it
    tilted = oracle.evaluate(_rolled(cs, np.radians(10.0)), box_on_water, seed=0)
    assert tilted.extra["hits"] != level.extra["hits"]


def test_roll_turns_the_footprint_on_a_wall():
    # one camera at z = 20 m, 15 m square-on to the +x face (x = 5) of a wall wider and taller than its view;
    # looking along -x, its right is +y: wall coordinates right = y, up = z - 20
    cam = Camera()
    cs = CaptureSet(np.array([[20.0, 0.0, 20.0]]), np.array([np.pi]), np.zeros(1), np.arange(1), cam)
    gt = SyntheticOracle().ground_truth(make_box((10.0, 40.0, 40.0), (0.0, 0.0, 20.0)))
    roll = np.radians(25.0)
    level = observe(cs, gt, 61, 41, 1e4, np.radians(89))
    rolled = observe(_rolled(cs, roll), gt, 61, 41, 1e4, np.radians(89))
    half_w, half_h = 15.0 * np.tan(cam.half_fov_x), 15.0 * np.tan(cam.half_fov_y)
    right, up = rolled.points[:, 1], rolled.points[:, 2] - 20.0
    # the rolled camera's right axis is (cos, -sin) and its up axis (sin, cos) in wall (right, up)
    # coordinates (right side down): in those axes every hit lies in the level footprint
    own_r = np.cos(roll) * right - np.sin(roll) * up
    own_u = np.sin(roll) * right + np.cos(roll) * up
    assert np.all(np.abs(own_r) <= half_w + 1e-3) and np.all(np.abs(own_u) <= half_h + 1e-3)
    assert own_r.max() > 0.9 * half_w and own_u.max() > 0.9 * half_h  # and fills it
    # the level footprint is the axis-aligned rectangle; the turned one reaches past its top and bottom
    assert np.abs(level.points[:, 2] - 20.0).max() <= half_h + 1e-3
    assert up.max() > half_h + 1.0 and up.min() < -half_h - 1.0
    # right side down: the hits on the camera's right (right > 0) reach lower than those on its left
    assert up[right > 0.5 * half_w].min() < up[right < -0.5 * half_w].min() - 1.0


def test_portrait_roll_sees_the_whole_tower(tower, tower_ring, fast_section):
    oracle = SyntheticOracle(fast_section)
    gt = oracle.ground_truth(tower)
    top_level = observe(tower_ring, gt, 40, 27, 1e4, np.radians(80)).points[:, 2].max()
    top_rolled = observe(_rolled(tower_ring, np.pi / 2), gt, 40, 27, 1e4, np.radians(80)).points[:, 2].max()
    assert top_level < 13.0 + 39.0 * np.tan(Camera().half_fov_y) < 28.0 - 3.0  # the top 4 m is out of frame
    assert top_rolled > 27.0  # portrait: 39 tan 21.9 deg = 15.7 m above the axis, past the top at 28 m
    level = oracle.evaluate(tower_ring, tower, seed=0)
    portrait = oracle.evaluate(_rolled(tower_ring, np.pi / 2), tower, seed=0)
    assert level.completeness < 0.9 and portrait.completeness > 0.98


def test_render_turns_with_the_camera(box_on_water):
    cs = ring_views((0, 0, 0), 22.0, (6.0,), 3, target=(0, 0, 1.5))
    gt = SyntheticOracle().ground_truth(box_on_water)
    texture = SolidTexture(seed=0)
    level, _ = render_views(cs, gt, 90, texture)
    half, _ = render_views(_rolled(cs, np.pi), gt, 90, texture)
    # pixel centres are symmetric about the principal point: a half turn is the image turned by 180 deg
    # (up to float rounding of the rays on silhouette edges)
    assert np.mean(np.all(half == level[:, ::-1, ::-1], axis=-1)) > 0.99
    tilted, _ = render_views(_rolled(cs, np.radians(10.0)), gt, 90, texture)
    assert np.mean(np.all(tilted == level, axis=-1)) < 0.9


class _FakeDatabase:
    """What write_position_priors needs of pycolmap.Database, recording the priors written."""

    written: typing.ClassVar[list] = []

    def __init__(self, names):
        self.images = [types.SimpleNamespace(name=n, data_id=i) for i, n in enumerate(names)]

    def clear_pose_priors(self):
        _FakeDatabase.written = []

    def read_all_images(self):
        return self.images

    def write_pose_prior(self, prior):
        _FakeDatabase.written.append(prior)

    def num_pose_priors(self):
        return len(_FakeDatabase.written)

    def close(self):
        pass


@pytest.fixture
def fake_pycolmap(monkeypatch):
    names = [f"view{i:04d}.png" for i in range(6)]
    fake = types.SimpleNamespace(
        Database=types.SimpleNamespace(open=lambda path: _FakeDatabase(names)),
        PosePrior=types.SimpleNamespace,
        PosePriorCoordinateSystem=types.SimpleNamespace(CARTESIAN="cartesian"))
    monkeypatch.setitem(sys.modules, "pycolmap", fake)
    return names


def test_colmap_position_priors_are_the_recorded_positions(fake_pycolmap, tmp_path):
    names = fake_pycolmap
    cs = ring_views((0, 0, 0), 20.0, (5.0,), 6)
    gnss = cs.positions + np.random.default_rng(0).normal(0.0, 1.5, cs.positions.shape)
    assert write_position_priors(tmp_path / "db", names, dataclasses.replace(cs, prior_positions=gnss), 1.0) == 6
    by_id = {p.corr_data_id: p for p in _FakeDatabase.written}
    np.testing.assert_array_equal([by_id[i].position for i in range(6)], gnss)
    np.testing.assert_allclose(by_id[0].position_covariance, np.eye(3))
    # no recorded positions: the true ones (a perfect fix), with sigma^2 on the diagonal
    write_position_priors(tmp_path / "db", names, cs, 2.0)
    np.testing.assert_array_equal([p.position for p in _FakeDatabase.written], cs.positions)
    np.testing.assert_allclose(_FakeDatabase.written[0].position_covariance, 4.0 * np.eye(3))
    assert colmap_module.write_position_priors is write_position_priors  # the function ColmapOracle calls


def test_colmap_fingerprint_follows_roll_not_priors():
    cs = ring_views((0, 0, 0), 20.0, (5.0,), 6)
    section = OracleSection()
    level = database_fingerprint(cs, "ship", section, 0)
    assert database_fingerprint(_rolled(cs, 0.0), "ship", section, 0) == level  # same images
    assert database_fingerprint(_rolled(cs, 0.1), "ship", section, 0) != level  # other images
    # priors are rewritten before every mapping; they do not change the features
    assert database_fingerprint(dataclasses.replace(cs, prior_positions=cs.positions + 1.0), "ship", section,
                                0) == level


def _line_path(n: int) -> FlightPath:
    """n viewpoints 1 m apart along x at 10 m, looking along +x, 0.3 rad down."""
    zeros = np.zeros(n, int)
    return FlightPath(np.column_stack([np.arange(float(n)), np.zeros(n), np.full(n, 10.0)]), np.zeros(n),
                np.full(n, -0.3), zeros, zeros, zeros)


def _write_table(file, capture_sets, n_views, drop=()):
    cols = pose_columns(capture_sets, n_views)
    taken = np.isfinite(cols["x_m"])
    table = {"trial": np.repeat(np.arange(len(capture_sets)), n_views), "view": np.tile(np.arange(n_views),
                                                                                       len(capture_sets)),
             "taken": taken, **{k: v for k, v in cols.items() if k not in drop}}
    pq.write_table(pa.table(table), file)


def test_capture_file_round_trip_with_roll_and_priors(tmp_path):
    path = _line_path(5)
    rng = np.random.default_rng(4)
    base = captures_from_path(path)
    flown = base.subset(np.array([0, 1, 3, 4]))  # view 2 not taken
    flown = dataclasses.replace(flown, roll=rng.normal(0.0, 0.05, 4),
                                prior_positions=flown.positions + rng.normal(0.0, 1.0, (4, 3)),
                                blur_px=rng.uniform(0.0, 8.0, 4))
    file = tmp_path / "captures.parquet"
    _write_table(file, [base, flown], len(path))
    back = captures_from_parquet(file, 1, path)
    np.testing.assert_array_equal(back.planned_index, [0, 1, 3, 4])
    np.testing.assert_allclose(back.roll, flown.roll, rtol=1e-12)
    np.testing.assert_allclose(back.prior_positions, flown.prior_positions, rtol=1e-12)
    np.testing.assert_allclose(back.blur_px, flown.blur_px, rtol=1e-12)
    np.testing.assert_allclose(back.yaw, flown.yaw, atol=1e-12)
    level = captures_from_parquet(file, 0, path)  # a trial without them: roll 0, priors = true positions
    np.testing.assert_array_equal(level.roll, np.zeros(5))
    np.testing.assert_array_equal(level.prior_positions, level.positions)
    np.testing.assert_array_equal(level.blur_px, np.zeros(5))


def test_capture_file_without_roll_or_prior_columns_still_loads(tmp_path):
    path = _line_path(3)
    old = tmp_path / "old.parquet"
    _write_table(old, [captures_from_path(path)], 3)
    assert ROLL_COLUMN not in pq.read_schema(old).names
    cs = captures_from_parquet(old, 0, path)
    assert cs.roll is None and cs.prior_positions is None and cs.blur_px is None and len(cs) == 3
    np.testing.assert_array_equal(cs.blur(), np.zeros(3))  # a record from before blur was written: sharp
    broken = tmp_path / "broken.parquet"
    flown = dataclasses.replace(captures_from_path(path), prior_positions=np.ones((3, 3)))
    _write_table(broken, [flown], 3, drop=PRIOR_COLUMNS[1:])
    with pytest.raises(InputError, match="prior_x_m but not all"):
        captures_from_parquet(broken, 0, path)
