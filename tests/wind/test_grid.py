"""Interpolation on the gridded representation: exactness, continuity, linear reproduction, bounds."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.wind.base import WindModel
from wrp_eval.wind.grid import GriddedMeanWind, OutsideWindGridError, WindGrid, interpolate


@pytest.mark.parametrize("method", ["idw", "trilinear"])
def test_exact_at_every_node(random_grid, method):
    nodes = random_grid.node_positions().reshape(-1, 3)
    got = interpolate(random_grid, nodes, method)
    np.testing.assert_allclose(got, random_grid.velocity_mps.reshape(-1, 3), atol=1e-9)


def test_trilinear_reproduces_a_linear_field():
    x, y, z = np.linspace(-50, 50, 6), np.linspace(-30, 30, 4), np.array([0.0, 5.0, 15.0, 40.0])
    heights = np.broadcast_to(z, (6, 4, 4)).copy()
    gx, gy, gz = np.meshgrid(x, y, z, indexing="ij")
    def lin(X, Y, Z):
        return np.stack([1 + 0.1 * X - 0.2 * Y + 0.05 * Z, 2 * np.ones_like(X), 0.01 * Z], -1)
    grid = WindGrid(x, y, heights, lin(gx, gy, gz))
    pts = np.random.default_rng(0).uniform([-50, -30, 0], [50, 30, 40], (200, 3))
    np.testing.assert_allclose(interpolate(grid, pts, "trilinear"), lin(*pts.T), atol=1e-12)


def test_trilinear_is_continuous_across_cells(random_grid):
    # a straight line through many cells and levels, sampled finely: no jumps
    t = np.linspace(0, 1, 20001)[:, None]
    a, b = np.array([-8.0, -3.0, 0.5]), np.array([10.0, 6.0, 38.0])
    line = random_grid.to_grid_frame(np.zeros((1, 3)))  # (sanity: origin stays at origin)
    assert np.allclose(line, 0)
    c, s = np.cos(0.3), np.sin(0.3)   # build the line in the grid frame, then rotate to the ship frame
    g = a + t * (b - a)
    pts = np.c_[c * g[:, 0] - s * g[:, 1], s * g[:, 0] + c * g[:, 1], g[:, 2]]
    vals = interpolate(random_grid, pts, "trilinear")
    assert np.abs(np.diff(vals, axis=0)).max() < 0.05


def test_idw_is_continuous_inside_a_cell_and_bounded(random_grid):
    # inside one cell the paper's IDW is smooth; it is a convex combination of the 8 corner values
    c, s = np.cos(0.3), np.sin(0.3)
    t = np.linspace(0.01, 0.99, 5001)[:, None]
    g = np.array([-4.0, 1.0, 3.5]) + t * np.array([3.5, 6.0, 4.0])   # within x [-5,0], y [0,8], z [3,9]
    pts = np.c_[c * g[:, 0] - s * g[:, 1], s * g[:, 0] + c * g[:, 1], g[:, 2]]
    vals = interpolate(random_grid, pts, "idw")
    assert np.abs(np.diff(vals, axis=0)).max() < 0.02
    corners = random_grid.velocity_mps[1:3, 1:3, 1:3].reshape(-1, 3)
    assert np.all(vals >= corners.min(0) - 1e-9) and np.all(vals <= corners.max(0) + 1e-9)


def test_idw_weights_nearer_nodes_more():
    x, y, z = np.array([0.0, 1.0]), np.array([0.0, 1.0]), np.array([0.0, 1.0])
    v = np.zeros((2, 2, 2, 3))
    v[0, 0, 0] = [1.0, 0, 0]
    grid = WindGrid(x, y, np.broadcast_to(z, (2, 2, 2)).copy(), v)
    near, far = interpolate(grid, np.array([[0.1, 0.1, 0.1], [0.9, 0.9, 0.9]]), "idw")[:, 0]
    # hand computation at the cell centre: all 8 equidistant -> 1/8
    centre = interpolate(grid, np.array([[0.5, 0.5, 0.5]]), "idw")[0, 0]
    assert centre == pytest.approx(1 / 8)
    assert near > centre > far > 0


def test_outside_points_fail_unless_clamped(random_grid):
    model = GriddedMeanWind(random_grid, "trilinear")
    with pytest.raises(OutsideWindGridError, match="outside the wind grid"):
        model.velocity(np.array([[0.0, 0.0, 1000.0]]), 0.0)
    with pytest.raises(OutsideWindGridError, match="x"):
        model.velocity(np.array([[500.0, 0.0, 5.0]]), 0.0)
    clamped = GriddedMeanWind(random_grid, "trilinear", clamp=True)
    inside = clamped.velocity(np.array([[0.0, 0.0, random_grid.heights_m[2, 1, -1]]]), 0.0)
    assert np.all(np.isfinite(clamped.velocity(np.array([[0.0, 0.0, 1000.0], [500.0, 0.0, 5.0]]), 0.0)))
    assert np.all(np.isfinite(inside))
    assert isinstance(model, WindModel)


def test_bad_grids_are_refused():
    x = np.array([0.0, 1.0])
    with pytest.raises(InputError, match="strictly increasing"):
        WindGrid(x, x, np.array([[[0.0, 0.0]] * 2] * 2), np.zeros((2, 2, 2, 3)))
    with pytest.raises(InputError, match="NaN"):
        WindGrid(x, x, np.broadcast_to([0.0, 1.0], (2, 2, 2)).copy(), np.full((2, 2, 2, 3), np.nan))
    with pytest.raises(InputError, match="unknown method"):
        GriddedMeanWind(WindGrid(x, x, np.broadcast_to([0.0, 1.0], (2, 2, 2)).copy(), np.zeros((2, 2, 2, 3))),
                        "cubic")


def test_inside_tells_exactly_which_points_velocity_answers_for(random_grid):
    # random points around the (rotated, terrain-following) grid: a point is inside iff interpolating it alone
    # does not raise; NaN is outside; with clamp everything is inside
    model = GriddedMeanWind(random_grid, "idw")
    nodes = random_grid.node_positions().reshape(-1, 3)
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    points = np.random.default_rng(4).uniform(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo), (400, 3))
    points = np.vstack([points, nodes[:50], [[np.nan, 0.0, 1.0]]])
    inside = model.inside(points)
    raises = []
    for p in points:
        try:
            model.velocity(p[None, :], 0.0)
            raises.append(False)
        except OutsideWindGridError:
            raises.append(True)
    assert inside.tolist() == [not r for r in raises]
    assert 50 < inside.sum() < len(points) - 50 and inside[400:450].all() and not inside[-1]
    assert GriddedMeanWind(random_grid, "idw", clamp=True).inside(points).all()
