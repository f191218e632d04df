"""The WRF reader against the real Katrina sample, the MM5 mapping, and broken files."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from wrp_eval.errors import InputError
from wrp_eval.wind.boundary_layer import charnock_roughness, log_law_factor
from wrp_eval.wind.grid import interpolate
from wrp_eval.wind.netcdf import DEFAULT_FILL_HEIGHTS_M, MM5_LAYOUT, read_mean_wind

SHIP_LAT, SHIP_LON = 23.7, -89.5          # inside the sample domain, at sea


def destaggered(ds, t):
    u = ds.U.values[t]
    v = ds.V.values[t]
    w = ds.W.values[t]
    z = (ds.PH.values[t] + ds.PHB.values[t]) / 9.81
    return (0.5 * (u[..., :-1] + u[..., 1:]), 0.5 * (v[:, :-1] + v[:, 1:]), 0.5 * (w[:-1] + w[1:]),
            0.5 * (z[:-1] + z[1:]) - ds.HGT.values[t])


@pytest.fixture(scope="module")
def east_grid(wrf_path):
    # heading 90 (bow east): ship x = east, y = north, and the Mercator grid is not rotated
    return read_mean_wind(wrf_path, SHIP_LAT, SHIP_LON, 90.0)


def test_node_values_equal_the_files_destaggered_values(east_grid, wrf_dataset):
    u, v, w, z = destaggered(wrf_dataset, 0)
    nfill = len(DEFAULT_FILL_HEIGHTS_M)
    g = east_grid
    assert g.shape == (48, 48, 14 + nfill)
    assert abs(g.grid_yaw_rad) < 1e-6
    np.testing.assert_allclose(g.velocity_mps[:, :, nfill:, 0], u.transpose(2, 1, 0), atol=1e-4)
    np.testing.assert_allclose(g.velocity_mps[:, :, nfill:, 1], v.transpose(2, 1, 0), atol=1e-4)
    np.testing.assert_allclose(g.velocity_mps[:, :, nfill:, 2], w.transpose(2, 1, 0), atol=1e-6)
    np.testing.assert_allclose(g.heights_m[:, :, nfill:], z.transpose(2, 1, 0), rtol=1e-6)
    # horizontal spacing = DX / map factor (Mercator): ~9.15 km here
    assert np.diff(g.x_m).mean() == pytest.approx(10_000 / wrf_dataset.MAPFAC_M.values[0, 20, 20], rel=0.01)


def test_heights_monotonic_and_fill_matches_u10(east_grid, wrf_dataset):
    assert np.all(np.diff(east_grid.heights_m, axis=2) > 0)
    k10 = DEFAULT_FILL_HEIGHTS_M.index(10.0)
    u10 = wrf_dataset.U10.values[0].T
    v10 = wrf_dataset.V10.values[0].T
    np.testing.assert_allclose(east_grid.velocity_mps[:, :, k10, 0], u10, atol=1e-5)
    np.testing.assert_allclose(east_grid.velocity_mps[:, :, k10, 1], v10, atol=1e-5)
    z0, _ = charnock_roughness(np.hypot(u10, v10))
    np.testing.assert_allclose(east_grid.velocity_mps[:, :, 1, 0], u10 * log_law_factor(2.0, z0), atol=1e-5)
    np.testing.assert_allclose(east_grid.velocity_mps[:, :, 0], 0.0)


@pytest.mark.parametrize("method", ["idw", "trilinear"])
def test_interpolation_exact_at_nodes_of_the_file(wrf_path, method):
    grid = read_mean_wind(wrf_path, SHIP_LAT, SHIP_LON, 37.0)      # a rotated grid
    nodes = grid.node_positions()[20:23, 18:21].reshape(-1, 3)
    np.testing.assert_allclose(interpolate(grid, nodes, method), grid.velocity_mps[20:23, 18:21].reshape(-1, 3),
                               atol=1e-6)


def test_trilinear_continuous_along_a_flight_line(east_grid):
    t = np.linspace(0, 1, 4001)[:, None]
    pts = np.array([-15_000.0, -8_000.0, 3.0]) + t * np.array([30_000.0, 17_000.0, 400.0])
    vals = interpolate(east_grid, pts, "trilinear")
    assert np.abs(np.diff(vals, axis=0)).max() < 0.1      # 7 m horizontal / 0.1 m vertical per sample


def test_heading_rotates_vectors_not_speeds(wrf_path):
    a = read_mean_wind(wrf_path, SHIP_LAT, SHIP_LON, 90.0)
    b = read_mean_wind(wrf_path, SHIP_LAT, SHIP_LON, 0.0)
    np.testing.assert_allclose(np.linalg.norm(a.velocity_mps, axis=-1), np.linalg.norm(b.velocity_mps, axis=-1),
                               atol=1e-4)
    # bow north: ship x = north = a's y, ship y (port) = west = -a's x
    np.testing.assert_allclose(b.velocity_mps[..., 0], a.velocity_mps[..., 1], atol=1e-4)
    np.testing.assert_allclose(b.velocity_mps[..., 1], -a.velocity_mps[..., 0], atol=1e-4)
    p = np.array([[0.0, 0.0, 50.0]])
    va, vb = interpolate(a, p, "trilinear")[0], interpolate(b, p, "trilinear")[0]
    np.testing.assert_allclose([vb[0], vb[1]], [va[1], -va[0]], atol=1e-4)


def test_time_selection(wrf_path, wrf_dataset):
    nfill = len(DEFAULT_FILL_HEIGHTS_M)
    near = read_mean_wind(wrf_path, SHIP_LAT, SHIP_LON, 90.0, "2005-08-28T16:00:00", "nearest")
    np.testing.assert_allclose(near.velocity_mps[:, :, nfill:, 0], destaggered(wrf_dataset, 1)[0].transpose(2, 1, 0),
                               atol=1e-4)
    lin = read_mean_wind(wrf_path, SHIP_LAT, SHIP_LON, 90.0, "2005-08-28T16:00:00", "linear")
    expect = (2 / 3) * destaggered(wrf_dataset, 1)[0] + (1 / 3) * destaggered(wrf_dataset, 2)[0]
    np.testing.assert_allclose(lin.velocity_mps[:, :, nfill:, 0], expect.transpose(2, 1, 0), atol=1e-4)
    with pytest.raises(InputError, match="outside the file's times"):
        read_mean_wind(wrf_path, SHIP_LAT, SHIP_LON, 90.0, "2005-08-29T12:00:00", "linear")


def test_ship_outside_the_domain(wrf_path):
    with pytest.raises(InputError, match="outside the grid"):
        read_mean_wind(wrf_path, 40.0, -60.0, 0.0)


def _variables(wrf_dataset, names=("U", "V", "W", "PH", "PHB", "HGT", "U10", "V10", "XLAT", "XLONG", "Times")):
    return wrf_dataset[list(names)].isel(Time=slice(0, 2))


@pytest.mark.parametrize("case, message", [
    ("missing", "missing variable"),
    ("nan", "NaN or Inf"),
    ("inf", "NaN or Inf"),
    ("dims", "has dims"),
    ("stag", "staggered dimension"),
    ("garbage", "cannot read as netCDF"),
])
def test_bad_files_fail_with_a_clear_message(tmp_path, wrf_dataset, case, message):
    path = tmp_path / f"{case}.nc"
    ds = _variables(wrf_dataset).copy(deep=True)
    if case == "missing":
        ds = ds.drop_vars("PHB")
    elif case == "nan":
        ds["U"].values[0, 3, 4, 5] = np.nan
    elif case == "inf":
        ds["V10"].values[1, 2, 2] = np.inf
    elif case == "dims":
        ds["U10"] = ds["U10"].isel(south_north=0)
    elif case == "stag":
        ds = ds.isel(west_east_stag=slice(0, 40))
    if case == "garbage":
        path.write_bytes(b"this is not a netCDF file")
    else:
        ds.to_netcdf(path)
    with pytest.raises(InputError, match=message) as err:
        read_mean_wind(path, SHIP_LAT, SHIP_LON, 0.0)
    assert str(path) in str(err.value) and "\n" not in str(err.value)


def test_mm5_layout_reads_dot_points_and_top_down_levels(tmp_path):
    """An MM5-style file built by hand from a known field: B-grid dot-point winds, levels top-down."""
    nx, ny, nz = 6, 5, 4
    lat = 10.0 + 0.09 * np.arange(ny)
    lon = 20.0 + 0.09 * np.arange(nx)
    heights_up = np.array([40.0, 120.0, 300.0, 700.0])
    # dot-point u: varies linearly with the dot index so that the 4-point average is known
    dot_i = np.arange(nx + 1)[None, None, :]
    dot_j = np.arange(ny + 1)[None, :, None]
    level = np.arange(nz)[:, None, None]
    u_dot = (1.0 + 0.5 * dot_i + 0.25 * dot_j + level).astype(float)
    v_dot = np.full((nz, ny + 1, nx + 1), -2.0)
    z = np.broadcast_to(heights_up[::-1, None, None], (nz, ny, nx)) + 0.0   # top-down, as in MM5
    u_dot = u_dot[::-1]                                                       # top-down too
    ds = xr.Dataset({
        "U": (("Time", "bottom_top", "south_north_stag", "west_east_stag"), u_dot[None]),
        "V": (("Time", "bottom_top", "south_north_stag", "west_east_stag"), v_dot[None]),
        "W": (("Time", "bottom_top_stag", "south_north", "west_east"), np.zeros((1, nz + 1, ny, nx))),
        "Z": (("Time", "bottom_top", "south_north", "west_east"), z[None]),
        "TERRAIN": (("south_north", "west_east"), np.zeros((ny, nx))),
        "U10": (("Time", "south_north", "west_east"), np.full((1, ny, nx), 3.0)),
        "V10": (("Time", "south_north", "west_east"), np.zeros((1, ny, nx))),
        "LATITCRS": (("south_north", "west_east"), np.broadcast_to(lat[:, None], (ny, nx)) + 0.0),
        "LONGICRS": (("south_north", "west_east"), np.broadcast_to(lon[None, :], (ny, nx)) + 0.0),
        "Times": (("Time",), np.array([b"2001-01-01_00:00:00"])),
    })
    path = tmp_path / "mm5.nc"
    ds.to_netcdf(path)
    grid = read_mean_wind(path, 10.2, 20.2, 90.0, layout=MM5_LAYOUT)
    nfill = sum(h < 39.0 for h in DEFAULT_FILL_HEIGHTS_M)
    np.testing.assert_allclose(grid.heights_m[2, 2, nfill:], heights_up)
    # cross point (i, j) = mean of dot points (i..i+1, j..j+1): 1 + 0.5 (i + 0.5) + 0.25 (j + 0.5) + level
    i, j = 3, 2
    expect = 1 + 0.5 * (i + 0.5) + 0.25 * (j + 0.5) + np.arange(nz)
    np.testing.assert_allclose(grid.velocity_mps[i, j, nfill:, 0], expect, atol=1e-6)
    np.testing.assert_allclose(grid.velocity_mps[i, j, nfill:, 1], -2.0, atol=1e-6)
    k10 = list(DEFAULT_FILL_HEIGHTS_M).index(10.0)
    np.testing.assert_allclose(grid.velocity_mps[:, :, k10, 0], 3.0, atol=1e-9)
