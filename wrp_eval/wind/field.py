"""The wind the simulator flies through: mean field + Dryden turbulence + optional gusts, batch-first, in the
ship's air wake when the hull is known.

``build_wind_field(sections, ship, flight_rngs, dt_s, base_dir)`` turns one ``wind:`` section per flight into
ONE :class:`WindField` for the whole batch (a single flight is a batch of one); ``WindField.velocity(points,
t)`` is the one call the simulator makes at every step (row i of ``points`` = flight i). Flight i's wind
depends only on its own section and its own generator, never on the batch it is in: row i is bit-identical to
the field built for flight i alone (tests/wind/test_field.py), which is what lets a campaign fly trials of
different drawn winds together.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar, cast

import numpy as np
from numpy.typing import NDArray

from wrp_eval.errors import InputError
from wrp_eval.frames import ShipLike, ship_pose
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import build_proxy
from wrp_eval.streams import FlightRngs, children, flight_generators
from wrp_eval.wind.air_wake import ShipAirWake
from wrp_eval.wind.base import WindModel
from wrp_eval.wind.boundary_layer import synthetic_marine_grid
from wrp_eval.wind.config import WindGridSection, WindSection
from wrp_eval.wind.dryden import (
    FT_M,
    DrydenTurbulence,
    severity_w20_mps,
)
from wrp_eval.wind.grid import GriddedMeanWind, WindGrid
from wrp_eval.wind.gusts import OneMinusCosineGusts
from wrp_eval.wind.netcdf import MM5_LAYOUT, WRF_LAYOUT, read_mean_wind

TWENTY_FT_M = 20.0 * FT_M

T = TypeVar("T")


@dataclass
class WindField:
    """``velocity(points, t) -> (n, 3)`` m/s, world (ship) frame = mean + turbulence + gusts, or in the ship's
    air wake ``mean (1 - deficit) + gain turbulence + (1 - deficit) gusts``.

    With turbulence, gusts or flights in different mean fields, ``points`` must have one row per flight
    (n_flights, 3) and t must not decrease between calls; a mean field shared by every flight takes any (n, 3).
    The wake (:class:`wrp_eval.wind.air_wake.ShipAirWake`) is oriented row by row by the free-stream mean wind
    at the point. The Dryden filters keep seeing the free-stream mean (their axes and frozen-field speed), so
    the turbulence stays continuous across the wake edge and the wake only scales it. Gusts are sheltered
    like the mean wind (quasi-steady: the wake's speed scales with the approach speed, gusts included).
    """

    mean: WindModel
    turbulence: DrydenTurbulence | None = None
    gusts: OneMinusCosineGusts | None = None
    wake: ShipAirWake | None = None

    def speed_10m_at_ship(self, n_flights: int) -> NDArray[np.float64]:
        """(n_flights,) m/s: each flight's mean horizontal wind 10 m above the sea at the ship (the origin), from
        its own mean field (synthetic or mesoscale): what raises the sea it flies over."""
        mean = self.mean.velocity(np.tile([0.0, 0.0, 10.0], (n_flights, 1)), 0.0)
        speed: NDArray[np.float64] = np.hypot(mean[:, 0], mean[:, 1])
        return speed

    def inside(self, points: NDArray[np.float64]) -> NDArray[np.bool_]:
        """(n,) bool: the rows of ``points`` (n, 3) m inside the mean field's domain (a mean model without an
        ``inside`` covers everywhere). The simulator ends a flight blown outside as lost, instead of raising."""
        inside = getattr(self.mean, "inside", None)
        return np.ones(len(points), dtype=bool) if inside is None else inside(points)

    def velocity(self, points: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        points = np.asarray(points, dtype=float)
        wind = self.mean.velocity(points, t)
        if self.wake is not None:
            return self._in_wake(self.wake, points, t, wind)
        if self.turbulence is not None:
            wind = wind + self.turbulence.velocity(points, t, mean_wind=wind)
        if self.gusts is not None:
            wind = wind + self.gusts.velocity(points, t)
        return wind

    def _in_wake(self, wake: ShipAirWake, points: NDArray[np.float64], t: float,
                 mean: NDArray[np.float64]) -> NDArray[np.float64]:
        """The wind at points (n, 3) whose free-stream mean wind is ``mean`` (n, 3), in the air wake ``wake``."""
        deficit, gain = wake.factors(points, mean)
        kept = (1.0 - deficit)[:, None]
        wind = mean * kept
        if self.turbulence is not None:
            wind = wind + gain[:, None] * self.turbulence.velocity(points, t, mean_wind=mean)
        if self.gusts is not None:
            wind = wind + kept * self.gusts.velocity(points, t)
        return wind


def grid_axes(grid: WindGridSection) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Node coordinates (x, y, z) of a ``wind.grid`` section (ranges include both ends)."""
    def axis(lo: float, hi: float) -> NDArray[np.float64]:
        n = int(np.floor((hi - lo) / grid.spacing_m + 1e-9)) + 1
        return cast(NDArray[np.float64], lo + grid.spacing_m * np.arange(n))
    return axis(*grid.x_range_m), axis(*grid.y_range_m), np.asarray(grid.z_levels_m, dtype=float)


def build_mean_grid(section: WindSection, ship: ShipLike, base_dir: str | Path | None = None) -> WindGrid:
    """The configured mean field as a :class:`WindGrid` around the ship.

    ship: anything :func:`wrp_eval.frames.ship_pose` takes (ShipParticulars, ShipPose, (lat, lon, heading))."""
    pose = ship_pose(ship)
    if section.source == "synthetic":
        x, y, z = grid_axes(section.grid)
        return synthetic_marine_grid(section.speed_10m_m_s, section.direction_deg, pose.heading_deg, x, y, z,
                                     section.charnock_alpha, section.veer_deg_per_100m, section.gradient_per_km)
    if section.file is None:
        raise InputError("wind.file", f"required when wind.source is {section.source}")
    path = Path(section.file)
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    layout = WRF_LAYOUT if section.source == "wrf" else MM5_LAYOUT
    return read_mean_wind(path, pose.lat_deg, pose.lon_deg, pose.heading_deg, section.time,
                          section.time_interpolation, layout, section.fill_heights_m, section.charnock_alpha)


def _shared(sections: Sequence[WindSection], name: str, value: Callable[[WindSection], T]) -> T:
    """``value(section)`` of the first flight, checked to be the same for every flight of the batch (settings
    one batched model holds once)."""
    first = value(sections[0])
    if any(value(s) != first for s in sections[1:]):
        raise ValueError(f"the flights of one wind field must share wind.{name}")
    return first


def build_mean_wind(sections: Sequence[WindSection], ship: ShipLike,
                    base_dir: str | Path | None = None) -> GriddedMeanWind:
    """The mean wind of a batch, one ``wind:`` section per flight: one grid per distinct mean field (flights
    whose sections give the same field share one grid, built once), interpolated as the sections say (which
    the flights must share)."""
    method = _shared(sections, "interpolation", lambda s: s.interpolation)
    power = _shared(sections, "idw_power", lambda s: s.idw_power)
    clamp = _shared(sections, "clamp", lambda s: s.clamp)
    # what the grid depends on (not turbulence, gusts or interpolation)
    dumped: dict[int, str] = {}   # a batch often repeats one section object: dump each object once
    for s in sections:
        if id(s) not in dumped:
            dumped[id(s)] = s.model_dump_json(exclude={"turbulence", "gusts", "air_wake", "interpolation",
                                                          "idw_power", "clamp"})
    keys = [dumped[id(s)] for s in sections]
    first: dict[str, int] = {}                                   # distinct field -> its first flight
    for i, k in enumerate(keys):
        first.setdefault(k, i)
    grids = [build_mean_grid(sections[i], ship, base_dir) for i in first.values()]
    field_of = {k: j for j, k in enumerate(first)}
    flight_field = np.array([field_of[k] for k in keys]) if len(grids) > 1 else None
    return GriddedMeanWind(grids, method, power, clamp, flight_field)


def flight_w20_mps(sections: Sequence[WindSection], at_20ft: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """Dryden W20 (F,) m/s per flight, or None when no flight has turbulence. at_20ft (F, 3): each flight's
    mean wind 20 ft over the ship (``severity: from_mean``). ``sigma_w_m_s`` overrides the severity
    (W20 = 10 sigma_w); a flight without turbulence in a batch with some gets W20 = 0, for which the shared
    Dryden filter outputs exactly zero."""
    turbulent = [s.turbulence.severity != "none" or s.turbulence.sigma_w_m_s is not None for s in sections]
    if not any(turbulent):
        return None
    w20 = np.zeros(len(sections))
    for i, (s, on) in enumerate(zip(sections, turbulent, strict=True)):   # per flight, once at construction
        t = s.turbulence
        if not on:
            continue
        if t.sigma_w_m_s is not None:
            w20[i] = 10.0 * t.sigma_w_m_s
        elif t.severity in ("light", "moderate", "severe"):
            w20[i] = severity_w20_mps(t.severity)
        else:  # from_mean, or none with an explicit intensity (overridden above)
            w20[i] = float(np.hypot(at_20ft[i, 0], at_20ft[i, 1]))
    return w20


def build_air_wake(sections: Sequence[WindSection], ship: ShipLike) -> ShipAirWake | None:
    """The batch's air wake (the flights share ``wind.air_wake``), or None when it is disabled or ``ship`` has
    no hull: a :class:`ShipPose` or (lat, lon, heading) has no box, so the wake is skipped (documented in the
    wind README; the ship-less benchmarks and grid samples build fields that way). The box is the proxy of the
    true ship (no ``height_error``): the wind blows around the real hull."""
    settings = _shared(sections, "air_wake", lambda s: s.air_wake)
    if not settings.enabled or not isinstance(ship, ShipParticulars):
        return None
    return ShipAirWake.from_section(build_proxy(ship).bounds, settings)


def build_wind_field(sections: Sequence[WindSection], ship: ShipLike, flight_rngs: FlightRngs, dt_s: float = 0.01,
                     base_dir: str | Path | None = None) -> WindField:
    """ONE :class:`WindField` for a batch of F = len(sections) flights stepping by ``dt_s`` seconds.

    sections: flight i's ``wind:`` section (e.g. the config's for every flight, or each campaign trial's
    drawn one); flights must share the interpolation, the airspeed floor, the gust and the air-wake settings.
    ship: ShipParticulars, ShipPose or (lat, lon, heading) (:func:`wrp_eval.frames.ship_pose`); with
    ShipParticulars and ``air_wake.enabled`` the field carries the ship's air wake (:func:`build_air_wake`).
    flight_rngs: one Generator per flight, or a seed / SeedSequence / Generator the F are spawned from
    (:func:`wrp_eval.streams.flight_generators`). Flight i's generator is split in two, turbulence then
    gusts, so flight i's wind depends only on its section and its generator.
    base_dir: the folder relative netCDF files are resolved against.
    """
    sections = list(sections)
    n = len(sections)
    if n < 1:
        raise ValueError("a wind field needs at least one flight")
    streams = [children(g, 2) for g in flight_generators(flight_rngs, n)]
    mean = build_mean_wind(sections, ship, base_dir)
    at_20ft = mean.velocity(np.tile([0.0, 0.0, TWENTY_FT_M], (n, 1)), 0.0)          # (F, 3) over the ship
    w20 = flight_w20_mps(sections, at_20ft)
    turbulence = None
    if w20 is not None:
        floor = _shared(sections, "turbulence.airspeed_floor_m_s", lambda s: s.turbulence.airspeed_floor_m_s)
        turbulence = DrydenTurbulence(n, dt_s, [s[0] for s in streams], w20, None, floor)
    gusts = None
    g = _shared(sections, "gusts", lambda s: s.gusts)
    if g.enabled:
        azimuth = np.arctan2(at_20ft[:, 1], at_20ft[:, 0])                         # (F,) mean-wind azimuth
        gusts = OneMinusCosineGusts(n, [s[1] for s in streams], g.horizon_s, g.rate_per_min, g.amplitude_m_s,
                                    g.duration_s, azimuth, g.direction_spread_deg)
    return WindField(mean, turbulence, gusts, build_air_wake(sections, ship))


def sample_mean_field(section: WindSection, ship: ShipLike, base_dir: str | Path | None = None
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The configured mean field on its grid nodes above the sea: x (nx,), y (ny,), z (nz,) m and velocity
    (nx, ny, nz, 3) m/s in the ship frame (z: the ``wind.grid`` levels above 0, or all when none is).
    ship: anything :func:`wrp_eval.frames.ship_pose` takes."""
    mean = build_mean_wind([section], ship, base_dir)
    x, y, z = grid_axes(section.grid)
    z = z[z > 0] if np.any(z > 0) else z
    gx, gy, gz = np.meshgrid(x, y, z, indexing="ij")
    points = np.stack([gx, gy, gz], -1).reshape(-1, 3)
    return x, y, z, mean.velocity(points, 0.0).reshape(gx.shape + (3,))
