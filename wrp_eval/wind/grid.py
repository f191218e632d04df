"""The gridded mean wind every source produces, and its interpolation (paper Sec. 4.1).

Representation (the same for WRF, MM5 and the synthetic boundary layer):

* horizontal: a regular-or-not rectilinear grid of columns, axes ``x_m`` (nx,) and ``y_m`` (ny,) in a
  *grid frame* whose origin is the ship and whose x axis makes the angle ``grid_yaw_rad`` (CCW) with the
  ship's x axis (bow). WRF/MM5 grids keep their own orientation (west_east, south_north); the synthetic grid
  is built in the ship frame (``grid_yaw_rad = 0``).
* vertical: terrain-following levels given per column, ``heights_m`` (nx, ny, nz), strictly increasing in k,
  metres above the surface (sea level at sea).
* values: ``velocity_mps`` (nx, ny, nz, 3) already rotated into the ship frame (x bow, y port, z up).

Interpolation at a point: rotate it into the grid frame, find the horizontal cell (4 columns) and, in each
column, the two levels that bracket its height: these are the paper's "eight grid points close to the UAV".

* ``idw`` (the paper): inverse-distance weights ``1/d^p`` over those 8 nodes. Distances are measured in
  cell units (each axis divided by the cell size along it), because WRF cells are ~10 km wide and ~30 m tall:
  metric distances would make the weights ignore height. A point on a node returns the node's value.
  IDW is exact at nodes and continuous inside a cell, but - a property of the method, not of this code -
  it jumps slightly across cell faces (the far corners of the two neighbouring cells differ).
* ``trilinear``: linear in height inside each column, then bilinear across the 4 columns: exact at nodes
  and continuous everywhere.

Points outside the grid raise :class:`OutsideWindGridError` unless ``clamp`` is set (then each coordinate
is clipped to the grid's range).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from wrp_eval.errors import InputError

INTERPOLATION_METHODS = ("idw", "trilinear")


class OutsideWindGridError(InputError):
    """A query point lies outside the wind grid and clamping is off."""


@dataclass(frozen=True)
class WindGrid:
    """Mean wind on columns of terrain-following levels (see the module docstring for the frames).

    x_m (nx,), y_m (ny,): strictly increasing grid-frame column coordinates, metres from the ship.
    heights_m (nx, ny, nz): level heights above the surface, strictly increasing along the last axis.
    velocity_mps (nx, ny, nz, 3): wind in the ship frame, m/s.
    grid_yaw_rad: angle of the grid-frame x axis, CCW from the ship's x axis (bow).
    source: where the field came from (for messages and metadata).
    """

    x_m: np.ndarray
    y_m: np.ndarray
    heights_m: np.ndarray
    velocity_mps: np.ndarray
    grid_yaw_rad: float = 0.0
    source: str = "wind grid"

    @cached_property
    def common_levels(self) -> np.ndarray | None:
        """(nz,) the level heights when every column has the same ones (a flat sea: the synthetic field), else
        None. Interpolation then finds a point's level once instead of once per column (same numbers)."""
        first = self.heights_m[0, 0]
        return first if np.all(self.heights_m == first) else None

    def __post_init__(self) -> None:
        x, y = np.asarray(self.x_m, float), np.asarray(self.y_m, float)
        h, v = np.asarray(self.heights_m, float), np.asarray(self.velocity_mps, float)
        object.__setattr__(self, "x_m", x)
        object.__setattr__(self, "y_m", y)
        object.__setattr__(self, "heights_m", h)
        object.__setattr__(self, "velocity_mps", v)
        if x.ndim != 1 or y.ndim != 1 or x.size < 2 or y.size < 2:
            raise InputError(self.source, "the wind grid needs at least 2 columns along x and along y")
        if np.any(np.diff(x) <= 0) or np.any(np.diff(y) <= 0):
            raise InputError(self.source, "wind grid x/y axes must be strictly increasing")
        if h.ndim != 3 or h.shape[:2] != (x.size, y.size) or h.shape[2] < 2:
            raise InputError(self.source, f"heights have shape {h.shape}, expected ({x.size}, {y.size}, nz>=2)")
        if v.shape != h.shape + (3,):
            raise InputError(self.source, f"velocities have shape {v.shape}, expected {h.shape + (3,)}")
        if not (np.all(np.isfinite(h)) and np.all(np.isfinite(v))):
            raise InputError(self.source, "wind grid contains NaN or Inf")
        if np.any(np.diff(h, axis=2) <= 0):
            raise InputError(self.source, "level heights are not strictly increasing in some column")

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.heights_m.shape

    def to_grid_frame(self, points: np.ndarray) -> np.ndarray:
        """Ship-frame points (n, 3) -> grid-frame (n, 3) (rotation about z by -grid_yaw_rad)."""
        c, s = np.cos(self.grid_yaw_rad), np.sin(self.grid_yaw_rad)
        out = np.array(points, dtype=float, copy=True)
        out[:, 0] = c * points[:, 0] + s * points[:, 1]
        out[:, 1] = -s * points[:, 0] + c * points[:, 1]
        return out

    def node_positions(self) -> np.ndarray:
        """Ship-frame positions of every node, (nx, ny, nz, 3)."""
        c, s = np.cos(self.grid_yaw_rad), np.sin(self.grid_yaw_rad)
        gx, gy = np.meshgrid(self.x_m, self.y_m, indexing="ij")
        xs, ys = c * gx - s * gy, s * gx + c * gy
        nz = self.shape[2]
        return np.stack([np.repeat(xs[..., None], nz, 2), np.repeat(ys[..., None], nz, 2), self.heights_m], -1)


def _cell(axis: np.ndarray, coord: np.ndarray, clamp: bool, name: str, source: str):
    """Lower cell index (n,) and fraction in [0, 1] (n,) of ``coord`` along a rectilinear axis."""
    lo, hi = axis[0], axis[-1]
    outside = (coord < lo) | (coord > hi) | ~np.isfinite(coord)
    if np.any(outside):
        if not clamp:
            bad = coord[outside][0]
            raise OutsideWindGridError(source, f"query {name} = {bad:.3f} m is outside the wind grid "
                                               f"[{lo:.3f}, {hi:.3f}] m (enlarge the grid or set wind.clamp)")
        coord = np.clip(np.nan_to_num(coord, nan=lo), lo, hi)
    idx = np.clip(np.searchsorted(axis, coord, side="right") - 1, 0, axis.size - 2)
    frac = (coord - axis[idx]) / (axis[idx + 1] - axis[idx])
    return idx, frac


def _outside_levels(z: np.ndarray, bottom: np.ndarray, top: np.ndarray, clamp: bool, source: str) -> None:
    """Refuse (unless ``clamp``) heights z (n,) below ``bottom`` or above ``top`` (n,) of their cell."""
    outside = (z < bottom) | (z > top) | ~np.isfinite(z)
    if np.any(outside) and not clamp:
        row = np.nonzero(outside)[0][0]
        raise OutsideWindGridError(
            source, f"query height z = {z[row]:.3f} m is outside the wind grid's levels "
                    f"[{bottom[row]:.3f}, {top[row]:.3f}] m here (enlarge the grid or set wind.clamp)")


def _column_levels(heights: np.ndarray, z: np.ndarray, clamp: bool, source: str):
    """(lower level k (n, 4) int, fraction fz (n, 4)) of heights z (n, 1) in the cell's 4 columns' levels
    ``heights`` (n, 4, nz). Outside = below every column's lowest level or above every column's top; between,
    a column a little shorter than its neighbours holds its end value (per-column clipping)."""
    _outside_levels(z[:, 0], heights[..., 0].min(axis=1), heights[..., -1].max(axis=1), clamp, source)
    zc = np.clip(np.nan_to_num(np.broadcast_to(z, heights.shape[:2]), nan=0.0),
                 heights[..., 0], heights[..., -1])        # (n, 4), clipped per column
    nz = heights.shape[2]
    k = np.clip((heights <= zc[..., None]).sum(axis=2) - 1, 0, nz - 2)   # (n, 4) lower level per column
    h_lo = np.take_along_axis(heights, k[..., None], 2)[..., 0]
    h_hi = np.take_along_axis(heights, k[..., None] + 1, 2)[..., 0]
    return k, (zc - h_lo) / (h_hi - h_lo)


def _common_level(levels: np.ndarray, z: np.ndarray, clamp: bool, source: str):
    """:func:`_column_levels` where every column has the levels ``levels`` (nz,): the same arithmetic, once per
    point instead of once per column; k, fz broadcast to (n, 4)."""
    n = z.shape[0]
    _outside_levels(z, np.full(n, levels[0]), np.full(n, levels[-1]), clamp, source)
    zc = np.clip(np.nan_to_num(z, nan=0.0), levels[0], levels[-1])
    k = np.clip((levels <= zc[:, None]).sum(axis=1) - 1, 0, levels.size - 2)
    fz = (zc - levels[k]) / (levels[k + 1] - levels[k])
    return np.broadcast_to(k[:, None], (n, 4)), np.broadcast_to(fz[:, None], (n, 4))


def interpolate(grid: WindGrid, points: np.ndarray, method: str = "idw", idw_power: float = 2.0,
                clamp: bool = False, values: np.ndarray | None = None,
                value_index: np.ndarray | None = None) -> np.ndarray:
    """Mean wind (n, 3) m/s, ship frame, at ship-frame ``points`` (n, 3) m.

    values: optional node velocities of k fields (k, nx, ny, nz, 3) on ``grid``'s geometry, and value_index
    (n,) int: row i of ``points`` is interpolated in ``values[value_index[i]]`` (a batch of flights, each in
    its own mean field; the index lets flights share a field without copying it). Default: the grid's own
    values. Every row is computed independently of the others, so a row's result does not depend on the
    batch it is in."""
    if method not in INTERPOLATION_METHODS:
        raise InputError("wind.interpolation", f"unknown method {method!r}; choose from {INTERPOLATION_METHODS}")
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (n, 3), got {points.shape}")
    g = grid.to_grid_frame(points)
    i, fx = _cell(grid.x_m, g[:, 0], clamp, "x (grid frame)", grid.source)
    j, fy = _cell(grid.y_m, g[:, 1], clamp, "y (grid frame)", grid.source)

    # the 4 columns of the cell, order (i,j), (i+1,j), (i,j+1), (i+1,j+1): shape (n, 4)
    ci = np.stack([i, i + 1, i, i + 1], axis=1)
    cj = np.stack([j, j, j + 1, j + 1], axis=1)
    if grid.common_levels is not None:
        k, fz = _common_level(grid.common_levels, g[:, 2], clamp, grid.source)
    else:
        k, fz = _column_levels(grid.heights_m[ci, cj], g[:, 2:3], clamp, grid.source)
    if values is None:
        v_lo = grid.velocity_mps[ci, cj, k]                # (n, 4, 3)
        v_hi = grid.velocity_mps[ci, cj, k + 1]
    else:
        field = np.asarray(value_index)[:, None]
        v_lo = values[field, ci, cj, k]                    # (n, 4, 3): each row's own field's nodes
        v_hi = values[field, ci, cj, k + 1]

    fxc = np.stack([fx, 1 - fx, fx, 1 - fx], axis=1)       # cell-unit distance to each column along x
    fyc = np.stack([fy, fy, 1 - fy, 1 - fy], axis=1)
    if method == "trilinear":
        column = v_lo + fz[..., None] * (v_hi - v_lo)      # (n, 4, 3)
        wx = np.stack([1 - fx, fx, 1 - fx, fx], axis=1)
        wy = np.stack([1 - fy, 1 - fy, fy, fy], axis=1)
        return np.einsum("nc,ncd->nd", wx * wy, column)

    # Paper Sec. 4.1: inverse-distance weighting over the 8 surrounding grid points.
    d2_lo = fxc**2 + fyc**2 + fz**2                        # (n, 4) squared cell-unit distances
    d2_hi = fxc**2 + fyc**2 + (1 - fz) ** 2
    d2 = np.concatenate([d2_lo, d2_hi], axis=1)            # (n, 8)
    values = np.concatenate([v_lo, v_hi], axis=1)          # (n, 8, 3)
    on_node = d2 < 1e-24
    with np.errstate(divide="ignore"):
        w = np.where(on_node, 0.0, d2 ** (-0.5 * idw_power))
    hit = on_node.any(axis=1)
    w[hit] = on_node[hit].astype(float)                    # a query on a node returns that node's value
    w /= w.sum(axis=1, keepdims=True)
    return np.einsum("nc,ncd->nd", w, values)


def _same_geometry(a: WindGrid, b: WindGrid) -> bool:
    """True when two grids share axes, level heights and orientation (their values may differ)."""
    return (a.grid_yaw_rad == b.grid_yaw_rad and np.array_equal(a.x_m, b.x_m) and np.array_equal(a.y_m, b.y_m)
            and np.array_equal(a.heights_m, b.heights_m))


class GriddedMeanWind:
    """The mean wind of a batch of flights over :class:`WindGrid` s, a :class:`~wrp_eval.wind.base.WindModel`
    (steady: ``t`` is ignored).

    grids: one WindGrid (every flight in the same field: ``velocity`` then takes any (n, 3) points) or a
    sequence of the distinct fields; flight_field (F,) int: the index into ``grids`` of flight i's field
    (needed with more than one field: ``velocity`` then takes (F, 3) points, row i = flight i).
    Fields of one geometry (always the synthetic source's; one netCDF file at one time) are interpolated in
    one vectorised call against their stacked node values; fields of different geometries (other files or
    times) in one call per geometry. Each row equals :func:`interpolate` of that flight's field alone, bit for
    bit (tests/wind/test_field.py).
    """

    def __init__(self, grids: WindGrid | Sequence[WindGrid], method: str = "idw", idw_power: float = 2.0,
                 clamp: bool = False, flight_field: np.ndarray | None = None):
        if method not in INTERPOLATION_METHODS:
            raise InputError("wind.interpolation", f"unknown method {method!r}; choose from {INTERPOLATION_METHODS}")
        self.grids = (grids,) if isinstance(grids, WindGrid) else tuple(grids)
        self.method, self.idw_power, self.clamp = method, float(idw_power), bool(clamp)
        if not self.grids:
            raise ValueError("GriddedMeanWind needs at least one grid")
        if len(self.grids) > 1 and flight_field is None:
            raise ValueError("flight_field is required with more than one field")
        self.flight_field = None if flight_field is None else np.asarray(flight_field, dtype=int)
        if self.flight_field is not None and (self.flight_field.ndim != 1 or self.flight_field.size == 0
                                              or self.flight_field.min() < 0
                                              or self.flight_field.max() >= len(self.grids)):
            raise ValueError(f"flight_field must be (F,) indices into the {len(self.grids)} grids")
        # fields grouped by geometry -> per group: geometry, stacked values (k, nx, ny, nz, 3), the flights
        # (rows) in it and each row's index into the stack; built once, used at every step
        self._groups: list[tuple[WindGrid, np.ndarray, np.ndarray, np.ndarray]] = []
        if len(self.grids) > 1:
            geometries: list[list[int]] = []
            for f, g in enumerate(self.grids):
                same = [m for m in geometries if _same_geometry(self.grids[m[0]], g)]
                if same:
                    same[0].append(f)
                else:
                    geometries.append([f])
            for fields in geometries:
                stack_index = np.full(len(self.grids), -1)
                stack_index[fields] = np.arange(len(fields))
                rows = np.flatnonzero(np.isin(self.flight_field, fields))
                values = np.stack([self.grids[f].velocity_mps for f in fields])
                self._groups.append((self.grids[fields[0]], values, rows, stack_index[self.flight_field[rows]]))

    def velocity(self, points: np.ndarray, t: float = 0.0) -> np.ndarray:
        """Mean wind (n, 3) m/s at ship-frame points (n, 3) m (row i = flight i with several fields)."""
        if not self._groups:
            return interpolate(self.grids[0], points, self.method, self.idw_power, self.clamp)
        points = np.asarray(points, dtype=float)
        if points.shape != (self.flight_field.size, 3):
            raise ValueError(f"points must have shape ({self.flight_field.size}, 3), one row per flight, "
                             f"got {points.shape}")
        if len(self._groups) == 1:
            geometry, values, _, index = self._groups[0]
            return interpolate(geometry, points, self.method, self.idw_power, self.clamp, values, index)
        out = np.empty_like(points)
        for geometry, values, rows, index in self._groups:   # one call per geometry (a few at most)
            if rows.size:
                out[rows] = interpolate(geometry, points[rows], self.method, self.idw_power, self.clamp,
                                        values, index)
        return out
