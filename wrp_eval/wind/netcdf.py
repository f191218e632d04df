"""Mesoscale mean wind from WRF output, or MM5 output converted to netCDF, as a :class:`WindGrid`.

What the reader does (the WRF-ARW conventions: Skamarock et al. 2019, "A Description of the Advanced Research
WRF Model Version 4", NCAR/TN-556+STR, Sec. 3 (staggered Arakawa-C grid, geopotential PH + PHB)):

1. checks that every variable it needs is there, with the expected dimensions (a staggered dimension is one
   longer than its mass-grid twin) and finite values;
2. picks the time: nearest output, or linear between the two outputs that bracket the requested time;
3. destaggers: U along west_east_stag, V along south_north_stag, W/PH/PHB along bottom_top_stag (any
   dimension named ``*_stag`` is averaged onto mass points, so MM5's B-grid dot points work too);
4. heights: z = (PH + PHB) / 9.81 on w-levels, averaged to mass levels, minus HGT (height above the ground,
   i.e. above the sea at sea); MM5 gives heights directly (see :data:`MM5_LAYOUT`);
5. rotates grid-relative (U, V) to earth east/north (COSALPHA/SINALPHA when the file has them, else the local
   grid rotation from XLAT/XLONG), then to the ship frame for the ship's heading;
6. places the ship: the grid is expressed in metres from the ship in its own (west_east, south_north)
   orientation, with a local tangent-plane spacing measured from XLAT/XLONG at the ship; the grid's yaw
   relative to the bow is stored on the :class:`WindGrid`;
7. fills below the lowest model level (~30 m in WRF) with a log law matched to U10/V10 (Charnock z0), on
   fixed fill heights (0 m = calm surface, 2, 5, 10, 20 m by default, those below the lowest level).

The time of the field is fixed for the whole simulation (a flight lasts minutes, WRF outputs are hours
apart): ``velocity(points, t)`` ignores ``t``.

MM5: only MM5 output already converted to netCDF is read, with the names of :data:`MM5_LAYOUT`.
The MM5 v3 binary output format (MMOUT_DOMAINx) is NOT read; convert it first.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import cast

import numpy as np
import xarray as xr
from numpy.typing import NDArray

from wrp_eval.errors import InputError
from wrp_eval.frames import (
    ShipPose,
    enu_to_ship,
    geographic_to_enu_equirectangular,
    wrap_180,
)
from wrp_eval.wind.boundary_layer import (
    GRAVITY_MPS2,
    charnock_roughness,
    log_law_factor,
)
from wrp_eval.wind.grid import WindGrid

DEFAULT_FILL_HEIGHTS_M = (0.0, 2.0, 5.0, 10.0, 20.0)
TIME_FORMATS = ("%Y-%m-%d_%H:%M:%S", "%Y-%m-%dT%H:%M:%S", "%Y-%m-%d %H:%M:%S", "%Y-%m-%dT%H:%M", "%Y-%m-%d")


@dataclass(frozen=True)
class NetcdfLayout:
    """Names of the variables and dimensions the reader expects.

    Either ``geopotential`` (perturbation, base) in m^2/s^2 on w-levels (WRF) or ``height`` in metres above
    sea level (on mass or w-levels) gives the level heights; ``terrain`` (m) is subtracted from them.
    """

    name: str
    u: str
    v: str
    w: str
    terrain: str
    u10: str
    v10: str
    lat: str
    lon: str
    times: str
    time_dim: str = "Time"
    level_dim: str = "bottom_top"
    south_north_dim: str = "south_north"
    west_east_dim: str = "west_east"
    geopotential: tuple[str, str] | None = None
    height: str | None = None
    cos_alpha: str | None = "COSALPHA"
    sin_alpha: str | None = "SINALPHA"

    def required(self) -> list[str]:
        names = [self.u, self.v, self.w, self.terrain, self.u10, self.v10, self.lat, self.lon, self.times]
        if self.geopotential:
            names += list(self.geopotential)
        elif self.height is not None:
            names.append(self.height)
        return names


WRF_LAYOUT = NetcdfLayout(name="WRF", u="U", v="V", w="W", terrain="HGT", u10="U10", v10="V10",
                          lat="XLAT", lon="XLONG", times="Times", geopotential=("PH", "PHB"))

# MM5 output converted to netCDF (e.g. with a MM5-to-netCDF converter, renaming as needed): cross-point
# (mass) dims south_north / west_east, dot-point (B-grid corner) dims south_north_stag / west_east_stag,
# half-sigma levels bottom_top, full-sigma levels bottom_top_stag. Level order may be top-down as in MM5
# (k = 1 at the top): the reader sorts levels by height.
MM5_LAYOUT = NetcdfLayout(
    name="MM5",
    u="U",            # (Time, bottom_top, south_north_stag, west_east_stag)  m/s, grid-relative, dot points
    v="V",            # (Time, bottom_top, south_north_stag, west_east_stag)  m/s, grid-relative, dot points
    w="W",            # (Time, bottom_top_stag, south_north, west_east)       m/s, full sigma levels
    height="Z",       # (Time, bottom_top, south_north, west_east)            m above sea level, half sigma
    terrain="TERRAIN",  # (Time, south_north, west_east) or (south_north, west_east)  m
    u10="U10", v10="V10",  # (Time, south_north, west_east)  m/s grid-relative, cross points
    lat="LATITCRS", lon="LONGICRS",  # cross-point latitude / longitude, degrees
    times="Times",    # (Time,) strings "YYYY-MM-DD_HH:MM:SS"
)


def _open(path: Path) -> xr.Dataset:
    if not path.is_file():
        raise InputError(path, "no such file")
    try:
        return xr.open_dataset(path, decode_times=False, mask_and_scale=True)
    except Exception as err:  # xarray raises many types for unreadable files
        raise InputError(path, f"cannot read as netCDF: {type(err).__name__}: {err}") from None


def _parse_time(text: str, source: str) -> datetime:
    text = text.strip().rstrip("Z")
    for fmt in TIME_FORMATS:
        try:
            return datetime.strptime(text, fmt)
        except ValueError:
            continue
    raise InputError(source, f"cannot parse time {text!r} (use e.g. 2005-08-28T15:00:00)")


def _file_times(ds: xr.Dataset, layout: NetcdfLayout, path: Path) -> list[datetime]:
    raw = np.asarray(ds[layout.times].values)
    if raw.ndim == 2:  # a char array (Time, DateStrLen)
        raw = np.array([b"".join(row) for row in raw.astype("S1")])
    texts = [r.decode() if isinstance(r, bytes) else str(r) for r in raw.reshape(-1)]
    return [_parse_time(t, f"{path}: variable {layout.times}") for t in texts]


def select_times(file_times: list[datetime], time: str | None, mode: str,
                 source: str) -> list[tuple[int, float]]:
    """(index, weight) pairs for the requested time: one pair (nearest) or two (linear)."""
    if mode not in ("nearest", "linear"):
        raise InputError("wind.time_interpolation", f"unknown mode {mode!r}; choose nearest or linear")
    if time is None:
        return [(0, 1.0)]
    wanted = _parse_time(time, "wind.time")
    secs = np.array([(t - file_times[0]).total_seconds() for t in file_times])
    w = (wanted - file_times[0]).total_seconds()
    if mode == "nearest":
        return [(int(np.argmin(np.abs(secs - w))), 1.0)]
    if w < secs.min() or w > secs.max():
        raise InputError(source, f"time {time} is outside the file's times "
                                 f"{file_times[0].isoformat()} .. {file_times[-1].isoformat()}")
    hi = int(np.clip(np.searchsorted(secs, w, side="left"), 0, len(secs) - 1))
    if secs[hi] == w or hi == 0:
        return [(hi, 1.0)]
    lo = hi - 1
    frac = (w - secs[lo]) / (secs[hi] - secs[lo])
    return [(lo, 1.0 - frac), (hi, frac)]


def _checked(ds: xr.Dataset, name: str, dims: tuple[str, ...], sizes: dict[str, int], path: Path,
             optional_time: bool = False) -> NDArray[np.float64]:
    """The variable's values with dims validated, NaN/Inf refused, any *_stag dim destaggered."""
    if name not in ds.variables:
        raise InputError(path, f"missing variable {name!r}")
    var = ds[name]
    got = tuple(var.dims)
    if optional_time and got == dims[1:]:
        var = var.expand_dims({dims[0]: 1})
        got = dims
    if len(got) != len(dims):
        raise InputError(path, f"variable {name} has dims {got}, expected {dims} (or their _stag twins)")
    values = np.asarray(var.values, dtype=float)
    for axis, (g, want) in enumerate(zip(got, dims, strict=True)):
        if g == want:
            if want in sizes and values.shape[axis] != sizes[want]:
                raise InputError(path, f"variable {name}: dimension {g} has size {values.shape[axis]}, "
                                       f"expected {sizes[want]}")
            continue
        if g != want + "_stag" or want == dims[0]:
            raise InputError(path, f"variable {name} has dims {got}, expected {dims} (or their _stag twins)")
        if want in sizes and values.shape[axis] != sizes[want] + 1:
            raise InputError(path, f"variable {name}: staggered dimension {g} has size {values.shape[axis]}, "
                                   f"expected {sizes[want] + 1}")
    if not np.all(np.isfinite(values)):
        raise InputError(path, f"variable {name} contains NaN or Inf")
    for axis, (g, want) in enumerate(zip(got, dims, strict=True)):
        if g != want:  # destagger: average neighbouring staggered points onto mass points
            lo = np.take(values, np.arange(values.shape[axis] - 1), axis=axis)
            hi = np.take(values, np.arange(1, values.shape[axis]), axis=axis)
            values = 0.5 * (lo + hi)
    return values


def read_mean_wind(path: str | Path, lat_deg: float, lon_deg: float, heading_deg: float,
                   time: str | None = None, time_interpolation: str = "nearest",
                   layout: NetcdfLayout = WRF_LAYOUT, fill_heights_m: Sequence[float] = DEFAULT_FILL_HEIGHTS_M,
                   charnock_alpha: float = 0.011) -> WindGrid:
    """Read a WRF (or converted MM5) file into a :class:`WindGrid` around a ship.

    lat_deg/lon_deg: ship position (degrees); heading_deg: compass bearing of the bow.
    time: ISO time (None = the first output); time_interpolation: "nearest" or "linear".
    """
    path = Path(path)
    f = _read_fields(path, layout, time, time_interpolation)
    # (t, k, j, i) -> (t, i, j, k): x = west_east, y = south_north
    u, v, w, z_asl = (np.transpose(a, (0, 3, 2, 1)) for a in (f.u, f.v, f.w, f.z_asl))
    terrain, u10, v10 = (np.transpose(a, (0, 2, 1)) for a in (f.terrain, f.u10, f.v10))
    lat, lon = f.lat.T, f.lon.T                                               # (nx, ny)
    if terrain.shape[0] not in (1, u.shape[0]):
        raise InputError(path, f"variable {layout.terrain} has {terrain.shape[0]} times, {layout.u} has {u.shape[0]}")
    heights, u, v, w = _bottom_up(z_asl - terrain[..., None], u, v, w, path)  # height above the ground
    x_axis, y_axis, grid_yaw = _ship_placement(lat, lon, lat_deg, lon_deg, heading_deg, path)
    # grid-relative -> earth: per-column rotation of the grid x axis from east
    if f.cos_alpha is not None and f.sin_alpha is not None:
        cos_a, sin_a = f.cos_alpha.T, f.sin_alpha.T
    else:
        dlat = np.gradient(lat, axis=0)
        dlon = wrap_180(np.gradient(lon, axis=0)) * np.cos(np.deg2rad(lat))
        alpha = np.arctan2(dlat, dlon)
        cos_a, sin_a = np.cos(alpha), np.sin(alpha)
    heading = np.deg2rad(heading_deg)

    def to_ship(gu: NDArray[np.float64], gv: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        e = gu * cos_a[..., None] - gv * sin_a[..., None] if gu.ndim == 4 else gu * cos_a - gv * sin_a
        n = gu * sin_a[..., None] + gv * cos_a[..., None] if gu.ndim == 4 else gu * sin_a + gv * cos_a
        return enu_to_ship(e, n, heading)

    hgt_list, vel_list, weights = [], [], []
    fill = np.asarray([h for h in fill_heights_m if h < heights[..., 0].min() - 1.0], dtype=float)
    for index, weight in f.picks:
        vx, vy = to_ship(u[index][None], v[index][None])
        vel = np.stack([vx[0], vy[0], w[index]], axis=-1)                   # (nx, ny, nz, 3)
        hgt = heights[index]
        if fill.size:
            # neutral log law matched to the 10 m wind (Charnock 1955 roughness): U(z) = U10 ln(z/z0)/ln(10/z0),
            # Charnock z0
            sx, sy = to_ship(u10[index], v10[index])
            z0, _ = charnock_roughness(np.hypot(sx, sy), charnock_alpha)
            factor = log_law_factor(fill[None, None, :], z0[..., None])      # (nx, ny, nf)
            fvel = np.stack([sx[..., None] * factor, sy[..., None] * factor, np.zeros_like(factor)], -1)
            vel = np.concatenate([fvel, vel], axis=2)
            hgt = np.concatenate([np.broadcast_to(fill, hgt.shape[:2] + fill.shape), hgt], axis=2)
        hgt_list.append(hgt)
        vel_list.append(vel)
        weights.append(weight)
    # one or two picks, so each sum is an array
    heights_out = cast(NDArray[np.float64], sum(wt * h for wt, h in zip(weights, hgt_list, strict=True)))
    velocity_out = cast(NDArray[np.float64], sum(wt * v for wt, v in zip(weights, vel_list, strict=True)))
    return WindGrid(x_axis, y_axis, heights_out, velocity_out, float(grid_yaw),
                    source=f"{path} ({layout.name})")


@dataclass(frozen=True)
class _Fields:
    """A file's raw fields in its own dimension order: u, v, w, z_asl (t, k, j, i) m/s and m above sea level;
    terrain, u10, v10 (t or 1, j, i); lat, lon (j, i) deg; cos_alpha, sin_alpha (j, i) or None; the time picks
    (index, weight) of :func:`select_times`."""

    u: NDArray[np.float64]
    v: NDArray[np.float64]
    w: NDArray[np.float64]
    z_asl: NDArray[np.float64]
    terrain: NDArray[np.float64]
    u10: NDArray[np.float64]
    v10: NDArray[np.float64]
    lat: NDArray[np.float64]
    lon: NDArray[np.float64]
    cos_alpha: NDArray[np.float64] | None
    sin_alpha: NDArray[np.float64] | None
    picks: list[tuple[int, float]]


def _read_fields(path: Path, layout: NetcdfLayout, time: str | None, time_interpolation: str) -> _Fields:
    """The fields of ``layout`` from the file at ``path``, every variable, dimension and time count checked."""
    ds = _open(path)
    try:
        missing = [n for n in layout.required() if n not in ds.variables]
        if missing:
            raise InputError(path, f"missing variable(s) {missing} needed to read a {layout.name} file")
        t_dim, k_dim = layout.time_dim, layout.level_dim
        j_dim, i_dim = layout.south_north_dim, layout.west_east_dim
        for d in (t_dim, k_dim, j_dim, i_dim):
            if d not in ds.sizes:
                raise InputError(path, f"missing dimension {d!r} of a {layout.name} file")
        sizes = {d: int(ds.sizes[d]) for d in (k_dim, j_dim, i_dim)}
        if min(sizes[j_dim], sizes[i_dim]) < 2 or sizes[k_dim] < 2:
            raise InputError(path, f"grid {sizes} is too small (need >= 2 points along each axis)")
        d3, d2 = (t_dim, k_dim, j_dim, i_dim), (t_dim, j_dim, i_dim)
        times = _file_times(ds, layout, path)
        picks = select_times(times, time, time_interpolation, str(path))
        u, v, w = (_checked(ds, name, d3, sizes, path) for name in (layout.u, layout.v, layout.w))
        if layout.geopotential:
            ph = _checked(ds, layout.geopotential[0], d3, sizes, path)
            phb = _checked(ds, layout.geopotential[1], d3, sizes, path)
            z_asl = (ph + phb) / GRAVITY_MPS2   # destaggered above = mean of the two w-levels
        elif layout.height is not None:
            z_asl = _checked(ds, layout.height, d3, sizes, path)
        else:
            raise InputError(path, f"the {layout.name} layout names no level heights (geopotential or height)")
        terrain = _checked(ds, layout.terrain, d2, sizes, path, optional_time=True)
        u10, v10 = (_checked(ds, name, d2, sizes, path) for name in (layout.u10, layout.v10))
        lat, lon = (_checked(ds, name, d2, sizes, path, optional_time=True)[0] for name in (layout.lat, layout.lon))
        cos_a = sin_a = None
        if layout.cos_alpha and layout.sin_alpha and layout.cos_alpha in ds.variables \
                and layout.sin_alpha in ds.variables:
            cos_a = _checked(ds, layout.cos_alpha, d2, sizes, path, optional_time=True)[0]
            sin_a = _checked(ds, layout.sin_alpha, d2, sizes, path, optional_time=True)[0]
    finally:
        ds.close()
    n_times = u.shape[0]
    for name, arr in ((layout.u10, u10), (layout.v10, v10)):
        if arr.shape[0] != n_times:
            raise InputError(path, f"variable {name} has {arr.shape[0]} times, {layout.u} has {n_times}")
    if len(times) != n_times:
        raise InputError(path, f"variable {layout.times} has {len(times)} times, {layout.u} has {n_times}")
    return _Fields(u, v, w, z_asl, terrain, u10, v10, lat, lon, cos_a, sin_a, picks)


def _bottom_up(heights: NDArray[np.float64], u: NDArray[np.float64], v: NDArray[np.float64], w: NDArray[np.float64],
               path: Path) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The level heights above the ground (t, i, j, k) m and the winds, ordered bottom-up (MM5's sigma order is
    top-down); a column that is not strictly monotonic, or whose lowest level is not above the ground, is an
    :class:`InputError`."""
    if np.any(np.diff(heights, axis=3) == 0):
        raise InputError(path, "level heights are not strictly monotonic")
    if np.all(np.diff(heights, axis=3) < 0):
        heights, u, v, w = (a[..., ::-1] for a in (heights, u, v, w))
    if np.any(np.diff(heights, axis=3) <= 0):
        raise InputError(path, "level heights are not monotonic in some column")
    if np.any(heights[..., 0] <= 0):
        raise InputError(path, "the lowest model level is at or below the ground in some column")
    return heights, u, v, w


def _ship_placement(lat: NDArray[np.float64], lon: NDArray[np.float64], lat_deg: float, lon_deg: float,
                    heading_deg: float, path: Path) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """(x axis (nx,) m, y axis (ny,) m, the grid x axis' angle CCW from the bow rad) of the grid of columns at
    ``lat``, ``lon`` (nx, ny) deg around the ship: its fractional index by Newton steps in a local plane
    (equirectangular about the ship: fine over a few cells; see frames)."""
    east, north = geographic_to_enu_equirectangular(lat, lon, ShipPose(lat_deg, lon_deg, heading_deg))
    de_di, de_dj = np.gradient(east, axis=0), np.gradient(east, axis=1)
    dn_di, dn_dj = np.gradient(north, axis=0), np.gradient(north, axis=1)
    nx, ny = east.shape
    ci, cj = map(int, np.unravel_index(np.argmin(east**2 + north**2), east.shape))
    for _ in range(3):  # Newton steps on the fractional index of the ship
        jac = np.array([[de_di[ci, cj], de_dj[ci, cj]], [dn_di[ci, cj], dn_dj[ci, cj]]])
        step = np.linalg.solve(jac, -np.array([east[ci, cj], north[ci, cj]]))
        fi, fj = ci + step[0], cj + step[1]
        ci, cj = int(np.clip(round(fi), 0, nx - 1)), int(np.clip(round(fj), 0, ny - 1))
    if not (0.0 <= fi <= nx - 1 and 0.0 <= fj <= ny - 1):
        raise InputError(path, f"the ship at lat {lat_deg:.4f}, lon {lon_deg:.4f} is outside the grid "
                               f"(lat {lat.min():.3f}..{lat.max():.3f}, lon {lon.min():.3f}..{lon.max():.3f})")
    dx = float(np.hypot(de_di[ci, cj], dn_di[ci, cj]))
    dy = float(np.hypot(de_dj[ci, cj], dn_dj[ci, cj]))
    grid_alpha = float(np.arctan2(dn_di[ci, cj], de_di[ci, cj]))   # grid x axis, CCW from east
    return (np.arange(nx) - fi) * dx, (np.arange(ny) - fj) * dy, grid_alpha + np.deg2rad(heading_deg) - np.pi / 2
