"""Placebo paths: same number of moved viewpoints, same move magnitudes and yaw offsets, random choice."""

from __future__ import annotations

import numpy as np

from wrp_eval.ship.nofly import flyable
from wrp_eval.wrp.placebo import moved_views, placebo_offsets


def _wrp(n=20):
    off = np.zeros((n, 4))
    off[[2, 5, 11]] = [[1.0, 0.0, 0.0, 0.2], [0.0, -2.0, 0.0, -0.1], [0.0, 0.0, 0.5, 0.0]]
    return off


def test_placebos_move_as_many_views_by_the_same_amounts():
    wrp = _wrp()
    placebos, infeasible = placebo_offsets(wrp, 30, np.random.default_rng(0))
    assert placebos.shape == (30, 20, 4) and infeasible == 0
    for p in placebos:
        moved = moved_views(p)
        assert len(moved) == 3
        np.testing.assert_allclose(np.sort(np.linalg.norm(p[moved, :3], axis=1)), [0.5, 1.0, 2.0])
        np.testing.assert_allclose(np.sort(p[moved, 3]), [-0.1, 0.0, 0.2])
    chosen = {tuple(moved_views(p)) for p in placebos}
    assert len(chosen) > 25                       # the choice of views is random
    dirs = placebos[:, :, :3][np.linalg.norm(placebos[:, :, :3], axis=2) > 0]
    assert np.abs(np.mean(dirs / np.linalg.norm(dirs, axis=1, keepdims=True), axis=0)).max() < 0.3  # no bias


def test_placebos_are_seeded_and_respect_the_safety_predicate():
    wrp = _wrp()
    base = np.column_stack([np.linspace(-50, 50, 20), np.full(20, 30.0), np.full(20, 1.2)])
    box = np.array([[-60.0, -10.0, 0.0], [60.0, 10.0, 25.0]])
    a, _ = placebo_offsets(wrp, 10, np.random.default_rng(3), base, lambda pts: flyable(pts, box, 1.0))
    b, _ = placebo_offsets(wrp, 10, np.random.default_rng(3), base, lambda pts: flyable(pts, box, 1.0))
    np.testing.assert_array_equal(a, b)
    assert np.all(flyable(base[None] + a[:, :, :3], box, 1.0))   # 0.2 m above the floor: no move goes below it


def test_an_unmoved_wrp_has_unmoved_placebos():
    placebos, infeasible = placebo_offsets(np.zeros((8, 4)), 5, np.random.default_rng(0))
    assert not placebos.any() and infeasible == 0
