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

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.compiled import as_rows, kernel
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

    x_m: NDArray[np.float64]
    y_m: NDArray[np.float64]
    heights_m: NDArray[np.float64]
    velocity_mps: NDArray[np.float64]
    grid_yaw_rad: float = 0.0
    source: str = "wind grid"

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

    def to_grid_frame(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """Ship-frame points (n, 3) -> grid-frame (n, 3) (rotation about z by -grid_yaw_rad)."""
        c, s = np.cos(self.grid_yaw_rad), np.sin(self.grid_yaw_rad)
        out = np.array(points, dtype=float, copy=True)
        out[:, 0] = c * points[:, 0] + s * points[:, 1]
        out[:, 1] = -s * points[:, 0] + c * points[:, 1]
        return out

    def node_positions(self) -> NDArray[np.float64]:
        """Ship-frame positions of every node, (nx, ny, nz, 3)."""
        c, s = np.cos(self.grid_yaw_rad), np.sin(self.grid_yaw_rad)
        gx, gy = np.meshgrid(self.x_m, self.y_m, indexing="ij")
        xs, ys = c * gx - s * gy, s * gx + c * gy
        nz = self.shape[2]
        return np.stack([np.repeat(xs[..., None], nz, 2), np.repeat(ys[..., None], nz, 2), self.heights_m], -1)


# what _interpolate_rows reports about the first query outside the grid (clamp off): which coordinate
_INSIDE, _OUTSIDE_X, _OUTSIDE_Y, _OUTSIDE_Z = 0, 1, 2, 3


@kernel
def _lower_index(axis: NDArray[np.float64], coord: float) -> int:
    """Index of the interval of the increasing ``axis`` (m,) holding ``coord`` (within its range): the last
    node <= coord, at most m - 2 (a coordinate on the top node is in the last interval)."""
    k = 0
    while k < axis.size - 2 and axis[k + 1] <= coord:
        k += 1
    return k


@kernel
def _clamped(coord: float, lo: float, hi: float, nan_value: float) -> float:
    if coord != coord:                          # NaN
        coord = nan_value
    clamped: float = np.minimum(np.maximum(coord, lo), hi)
    return clamped


@kernel
def _first_outside(coords: NDArray[np.float64], lo: NDArray[np.float64], hi: NDArray[np.float64]) -> int:
    """Row of the first coordinate outside [lo, hi] (n,) or not finite, -1 if none."""
    for row in range(coords.size):
        c = coords[row]
        if not (c >= lo[row] and c <= hi[row]):     # also true for NaN
            return row
    return -1


@kernel
def _interpolate_rows(points: NDArray[np.float64], grid_yaw: float, x_axis: NDArray[np.float64],
                      y_axis: NDArray[np.float64], heights: NDArray[np.float64], values: NDArray[np.float64],
                      field: NDArray[np.int64], idw: bool, idw_power: float,
                      clamp: bool) -> tuple[NDArray[np.float64], int, int]:
    """Mean wind (n, 3) at ship-frame ``points`` (n, 3) (the grid frame is turned by ``grid_yaw`` rad), in
    ``values[field[i]]`` ((k, nx, ny, nz, 3), ``field`` (n,) int); ``idw``: inverse-distance weights (else
    trilinear). Returns (wind, code, row): code _INSIDE, or (clamp off) the first coordinate found outside (x
    over every row, then y, then z) and its row; the wind is then not computed."""
    n = points.shape[0]
    c, s = np.cos(grid_yaw), np.sin(grid_yaw)                  # WindGrid.to_grid_frame
    gx = c * points[:, 0] + s * points[:, 1]
    gy = -s * points[:, 0] + c * points[:, 1]
    gz = np.ascontiguousarray(points[:, 2])     # one layout for _first_outside (compiled once)
    out = np.zeros((n, 3))
    if not clamp:
        row = _first_outside(gx, np.full(n, x_axis[0]), np.full(n, x_axis[-1]))
        if row >= 0:
            return out, _OUTSIDE_X, row
        row = _first_outside(gy, np.full(n, y_axis[0]), np.full(n, y_axis[-1]))
        if row >= 0:
            return out, _OUTSIDE_Y, row
    ci, cj = np.empty(4, np.int64), np.empty(4, np.int64)
    fxc, fyc, kc, fzc = np.empty(4), np.empty(4), np.empty(4, np.int64), np.empty(4)
    wxc, wyc = np.empty(4), np.empty(4)
    nz = heights.shape[2]
    bottom, top = np.empty(n), np.empty(n)
    cells = np.empty((n, 4), np.int64)
    fractions = np.empty((n, 2))
    for row in range(n):
        x = _clamped(gx[row], x_axis[0], x_axis[-1], x_axis[0])
        y = _clamped(gy[row], y_axis[0], y_axis[-1], y_axis[0])
        i, j = _lower_index(x_axis, x), _lower_index(y_axis, y)
        cells[row, 0], cells[row, 1] = i, j
        fractions[row, 0] = (x - x_axis[i]) / (x_axis[i + 1] - x_axis[i])
        fractions[row, 1] = (y - y_axis[j]) / (y_axis[j + 1] - y_axis[j])
        if clamp:
            continue
        # outside in height = below every column's lowest level or above every column's top
        bottom[row] = np.minimum(np.minimum(heights[i, j, 0], heights[i + 1, j, 0]),
                                 np.minimum(heights[i, j + 1, 0], heights[i + 1, j + 1, 0]))
        top[row] = np.maximum(np.maximum(heights[i, j, nz - 1], heights[i + 1, j, nz - 1]),
                              np.maximum(heights[i, j + 1, nz - 1], heights[i + 1, j + 1, nz - 1]))
    if not clamp:
        row = _first_outside(gz, bottom, top)
        if row >= 0:
            return out, _OUTSIDE_Z, row
    for row in range(n):
        i, j = cells[row, 0], cells[row, 1]
        fx, fy = fractions[row, 0], fractions[row, 1]
        # the 4 columns of the cell, order (i,j), (i+1,j), (i,j+1), (i+1,j+1); cell-unit distances to each
        ci[0], ci[1], ci[2], ci[3] = i, i + 1, i, i + 1
        cj[0], cj[1], cj[2], cj[3] = j, j, j + 1, j + 1
        fxc[0], fxc[1], fxc[2], fxc[3] = fx, 1 - fx, fx, 1 - fx
        fyc[0], fyc[1], fyc[2], fyc[3] = fy, fy, 1 - fy, 1 - fy
        wxc[0], wxc[1], wxc[2], wxc[3] = 1 - fx, fx, 1 - fx, fx     # trilinear: the columns' bilinear weights
        wyc[0], wyc[1], wyc[2], wyc[3] = 1 - fy, 1 - fy, fy, fy
        z = gz[row]
        if z != z:
            z = 0.0
        for c in range(4):
            column = heights[ci[c], cj[c]]
            zc = np.minimum(np.maximum(z, column[0]), column[nz - 1])    # a column a little shorter holds its end value
            k = _lower_index(column, zc)
            kc[c], fzc[c] = k, (zc - column[k]) / (column[k + 1] - column[k])
        f = field[row]
        if idw:
            # Paper Sec. 4.1: inverse-distance weighting over the 8 surrounding grid points
            weights = np.empty(8)
            on_node = -1
            for c in range(4):
                d2_lo = fxc[c] ** 2 + fyc[c] ** 2 + fzc[c] ** 2
                d2_hi = fxc[c] ** 2 + fyc[c] ** 2 + (1 - fzc[c]) ** 2
                if d2_lo < 1e-24 and on_node < 0:
                    on_node = c
                if d2_hi < 1e-24 and on_node < 0:
                    on_node = 4 + c
                weights[c] = d2_lo ** (-0.5 * idw_power) if d2_lo >= 1e-24 else 0.0
                weights[4 + c] = d2_hi ** (-0.5 * idw_power) if d2_hi >= 1e-24 else 0.0
            if on_node >= 0:                     # a query on a node returns that node's value
                weights[:] = 0.0
                weights[on_node] = 1.0
            total = weights.sum()
            for c in range(8):
                level = kc[c % 4] + (c // 4)
                w = weights[c] / total
                for d in range(3):
                    out[row, d] += w * values[f, ci[c % 4], cj[c % 4], level, d]
        else:
            for c in range(4):
                w = wxc[c] * wyc[c]
                for d in range(3):
                    lo = values[f, ci[c], cj[c], kc[c], d]
                    hi = values[f, ci[c], cj[c], kc[c] + 1, d]
                    out[row, d] += w * (lo + fzc[c] * (hi - lo))
    return out, _INSIDE, -1


@kernel
def _inside_rows(points: NDArray[np.float64], grid_yaw: float, x_axis: NDArray[np.float64], y_axis: NDArray[np.float64],
                 heights: NDArray[np.float64]) -> NDArray[np.bool_]:
    """(n,) bool: ship-frame ``points`` (n, 3) that :func:`_interpolate_rows` (clamp off) accepts: within the
    axes' ranges, and in height within [the lowest bottom, the highest top] of the cell's four columns."""
    n = points.shape[0]
    c, s = np.cos(grid_yaw), np.sin(grid_yaw)
    nz = heights.shape[2]
    out = np.zeros(n, np.bool_)
    for row in range(n):
        x = c * points[row, 0] + s * points[row, 1]
        y = -s * points[row, 0] + c * points[row, 1]
        z = points[row, 2]
        if not (x >= x_axis[0] and x <= x_axis[-1] and y >= y_axis[0] and y <= y_axis[-1]):
            continue
        i, j = _lower_index(x_axis, x), _lower_index(y_axis, y)
        bottom = np.minimum(np.minimum(heights[i, j, 0], heights[i + 1, j, 0]),
                            np.minimum(heights[i, j + 1, 0], heights[i + 1, j + 1, 0]))
        top = np.maximum(np.maximum(heights[i, j, nz - 1], heights[i + 1, j, nz - 1]),
                         np.maximum(heights[i, j + 1, nz - 1], heights[i + 1, j + 1, nz - 1]))
        out[row] = z >= bottom and z <= top
    return out


def inside(grid: WindGrid, points: NDArray[np.float64]) -> NDArray[np.bool_]:
    """(n,) bool: ship-frame ``points`` (n, 3) m where :func:`interpolate` (clamp off) answers instead of raising
    :class:`OutsideWindGridError` (NaN coordinates are outside)."""
    points = as_rows("points", points, (len(points), 3))
    return _inside_rows(points, float(grid.grid_yaw_rad), grid.x_m, grid.y_m, grid.heights_m)


def interpolate(grid: WindGrid, points: ArrayLike, method: str = "idw", idw_power: float = 2.0,
                clamp: bool = False, values: ArrayLike | None = None,
                value_index: ArrayLike | None = None) -> NDArray[np.float64]:
    """Mean wind (n, 3) m/s, ship frame, at ship-frame ``points`` (n, 3) m.

    values: optional node velocities of k fields (k, nx, ny, nz, 3) on ``grid``'s geometry, and value_index
    (n,) int: row i of ``points`` is interpolated in ``values[value_index[i]]`` (a batch of flights, each in
    its own mean field; the index lets flights share a field without copying it). Default: the grid's own
    values. Every row is computed independently of the others (one compiled loop over the rows,
    :mod:`wrp_eval.compiled`), so a row's result does not depend on the batch it is in."""
    if method not in INTERPOLATION_METHODS:
        raise InputError("wind.interpolation", f"unknown method {method!r}; choose from {INTERPOLATION_METHODS}")
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (n, 3), got {points.shape}")
    if values is None:
        values, value_index = grid.velocity_mps[None], np.zeros(len(points), dtype=np.int64)
    else:       # the kernel does not check its indices
        if value_index is None:
            raise TypeError("interpolate() needs value_index with values")
        values = np.asarray(values, dtype=float)
        value_index = as_rows("value_index", value_index, (len(points),), np.int64)
        if values.shape[1:] != grid.velocity_mps.shape:
            raise ValueError(f"values must have shape (k,) + {grid.velocity_mps.shape}, got {values.shape}")
        if value_index.size and not 0 <= value_index.min() <= value_index.max() < len(values):
            raise ValueError(f"value_index must index the {len(values)} fields of values")
    wind, code, row = _interpolate_rows(points, float(grid.grid_yaw_rad), grid.x_m, grid.y_m, grid.heights_m, values,
                                        value_index, method == "idw", float(idw_power),
                                        bool(clamp))
    if code != _INSIDE:
        _refuse_outside(grid, grid.to_grid_frame(points[row:row + 1])[0], code)
    return wind


def _refuse_outside(grid: WindGrid, point: NDArray[np.float64], code: int) -> None:
    """Raise OutsideWindGridError for grid-frame ``point`` (3,) outside the grid along coordinate ``code``."""
    if code == _OUTSIDE_Z:
        i = min(int(np.searchsorted(grid.x_m, point[0], side="right")) - 1, grid.x_m.size - 2)
        j = min(int(np.searchsorted(grid.y_m, point[1], side="right")) - 1, grid.y_m.size - 2)
        columns = grid.heights_m[i:i + 2, j:j + 2]
        raise OutsideWindGridError(grid.source, f"query height z = {point[2]:.3f} m is outside the wind grid's "
                                                f"levels [{columns[..., 0].min():.3f}, {columns[..., -1].max():.3f}] m "
                                                "here (enlarge the grid or set wind.clamp)")
    axis, name, value = (grid.x_m, "x", point[0]) if code == _OUTSIDE_X else (grid.y_m, "y", point[1])
    raise OutsideWindGridError(grid.source, f"query {name} (grid frame) = {value:.3f} m is outside the wind grid "
                                            f"[{axis[0]:.3f}, {axis[-1]:.3f}] m (enlarge the grid or set wind.clamp)")


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
                 clamp: bool = False, flight_field: ArrayLike | None = None) -> None:
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
        self._groups: list[tuple[WindGrid, NDArray[np.float64], NDArray[np.intp], NDArray[np.int_]]] = []
        if len(self.grids) > 1 and self.flight_field is not None:
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

    def inside(self, points: ArrayLike) -> NDArray[np.bool_]:
        """(n,) bool: the rows of ship-frame ``points`` (n, 3) m :meth:`velocity` answers for (everywhere with
        ``clamp``); with several fields row i is tested in flight i's."""
        points = np.asarray(points, dtype=float)
        if self.clamp:
            return np.ones(len(points), dtype=bool)
        if not self._groups:
            return inside(self.grids[0], points)
        out = np.zeros(len(points), dtype=bool)
        for geometry, _, rows, _ in self._groups:
            if rows.size:
                out[rows] = inside(geometry, points[rows])
        return out

    def velocity(self, points: NDArray[np.float64], t: float = 0.0) -> NDArray[np.float64]:
        """Mean wind (n, 3) m/s at ship-frame points (n, 3) m (row i = flight i with several fields)."""
        if not self._groups or self.flight_field is None:
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
