"""The wind the simulator flies through: mean field + Dryden turbulence + optional gusts.

``build_wind_field(section, ship, n_flights, rng, dt_s)`` turns the ``wind:`` config section into a
:class:`WindField` for a batch of flights; ``WindField.velocity(points, t)`` is the one call the
simulator makes at every step (row i of ``points`` = flight i).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wrp_eval.errors import InputError
from wrp_eval.wind.base import WindModel
from wrp_eval.wind.boundary_layer import synthetic_marine_grid
from wrp_eval.wind.config import WindGridSection, WindSection
from wrp_eval.wind.dryden import FT_M, DrydenTurbulence, severity_w20_mps
from wrp_eval.wind.grid import GriddedMeanWind, WindGrid
from wrp_eval.wind.gusts import OneMinusCosineGusts
from wrp_eval.wind.netcdf import MM5_LAYOUT, WRF_LAYOUT, read_mean_wind

TWENTY_FT_M = 20.0 * FT_M


@dataclass
class WindField:
    """``velocity(points, t) -> (n, 3)`` m/s, world (ship) frame = mean + turbulence + gusts.

    With turbulence or gusts, ``points`` must have one row per flight (n_flights, 3) and t must not
    decrease between calls; the mean field alone takes any (n, 3).
    """

    mean: WindModel
    turbulence: DrydenTurbulence | None = None
    gusts: OneMinusCosineGusts | None = None

    def velocity(self, points: np.ndarray, t: float) -> np.ndarray:
        points = np.asarray(points, dtype=float)
        wind = self.mean.velocity(points, t)
        if self.turbulence is not None:
            wind = wind + self.turbulence.velocity(points, t, mean_wind=wind)
        if self.gusts is not None:
            wind = wind + self.gusts.velocity(points, t)
        return wind


def grid_axes(grid: WindGridSection) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node coordinates (x, y, z) of a ``wind.grid`` section (ranges include both ends)."""
    def axis(lo, hi):
        n = int(np.floor((hi - lo) / grid.spacing_m + 1e-9)) + 1
        return lo + grid.spacing_m * np.arange(n)
    return axis(*grid.x_range_m), axis(*grid.y_range_m), np.asarray(grid.z_levels_m, dtype=float)


def _ship_pose(ship) -> tuple[float, float, float]:
    if hasattr(ship, "lat_deg"):
        return float(ship.lat_deg), float(ship.lon_deg), float(ship.heading_deg)
    try:
        lat, lon, heading = (float(v) for v in ship)
    except (TypeError, ValueError):
        raise InputError("ship", "expected ShipParticulars or (lat_deg, lon_deg, heading_deg)") from None
    return lat, lon, heading


def build_mean_grid(section: WindSection, ship, base_dir: str | Path | None = None) -> WindGrid:
    """The configured mean field as a :class:`WindGrid` around the ship."""
    lat, lon, heading = _ship_pose(ship)
    if section.source == "synthetic":
        x, y, z = grid_axes(section.grid)
        return synthetic_marine_grid(section.speed_10m_mps, section.direction_deg, heading, x, y, z,
                                     section.charnock_alpha, section.veer_deg_per_100m, section.gradient_per_km)
    path = Path(section.file)
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    layout = WRF_LAYOUT if section.source == "wrf" else MM5_LAYOUT
    return read_mean_wind(path, lat, lon, heading, section.time, section.time_interpolation, layout,
                          section.fill_heights_m, section.charnock_alpha)


def build_wind_field(section: WindSection, ship, n_flights: int = 1, rng=0, dt_s: float = 0.01,
                     base_dir: str | Path | None = None) -> WindField:
    """A :class:`WindField` for ``n_flights`` flights stepping by ``dt_s`` seconds.

    ship: ShipParticulars (lat_deg, lon_deg, heading_deg are used) or a (lat, lon, heading) tuple.
    rng: Generator, SeedSequence or int; flight i's turbulence and gusts use the i-th spawned child
    (each split in two), so adding flights never changes the earlier flights' wind.
    """
    mean = GriddedMeanWind(build_mean_grid(section, ship, base_dir), section.interpolation,
                           section.idw_power, section.clamp)
    parent = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    flight_rngs = parent.spawn(n_flights)
    streams = [g.spawn(2) for g in flight_rngs]
    at_20ft = mean.velocity(np.array([[0.0, 0.0, TWENTY_FT_M]]), 0.0)[0]
    turb_cfg = section.turbulence
    turbulence = None
    if turb_cfg.severity != "none" or turb_cfg.sigma_w_mps is not None:
        if turb_cfg.severity in ("light", "moderate", "severe"):
            w20 = severity_w20_mps(turb_cfg.severity)
        else:  # from_mean (W20 at the ship, from the mean field), or none + an explicit intensity
            w20 = float(np.hypot(at_20ft[0], at_20ft[1]))
        turbulence = DrydenTurbulence(n_flights, dt_s, [s[0] for s in streams], w20, turb_cfg.sigma_w_mps,
                                      turb_cfg.airspeed_floor_mps)
    gusts = None
    if section.gusts.enabled:
        g = section.gusts
        azimuth = float(np.arctan2(at_20ft[1], at_20ft[0]))
        gusts = OneMinusCosineGusts(n_flights, [s[1] for s in streams], g.horizon_s, g.rate_per_min,
                                    g.amplitude_mps, g.duration_s, azimuth, g.direction_spread_deg)
    return WindField(mean, turbulence, gusts)
