"""The wind of a batch of trials, each with its own drawn scenario, as ONE batched wind model.

Trial i of a batch flies exactly the wind ``build_wind_field(section_i, ship, n_flights=1, rng=seed_i)`` of the
wind stage would give it (``section_i`` = the ``wind:`` section with the trial's drawn speed, direction,
turbulence and mesoscale time/file), so a trial's wind does not depend on the batch it shares -- but the
batch is evaluated with one vectorised call per time step instead of one call per flight:

* mean field: the trials' grids share their geometry (same axes, levels and grid yaw; always true for the
  synthetic source, and for one netCDF file), so their node values are stacked and every flight is
  interpolated against its own values in one vectorised call (:class:`StackedMeanWind`). Grids of different
  geometry fall back to one interpolation per flight.
* turbulence: one :class:`DrydenTurbulence` with per-flight generators and per-flight W20.
* gusts (optional): one gust model per flight (summed per flight; gusts are off by default).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wrp_eval.campaign.sampling import WindDraw
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.dryden import DrydenTurbulence, severity_w20_mps
from wrp_eval.wind.field import TWENTY_FT_M, WindField, build_mean_grid
from wrp_eval.wind.grid import GriddedMeanWind, WindGrid, interpolate
from wrp_eval.wind.gusts import OneMinusCosineGusts


def trial_wind_section(base: WindSection, draw: WindDraw) -> WindSection:
    """The ``wind:`` section of one trial: the base with the trial's drawn values.

    speed/direction apply to the synthetic source (a netCDF field brings its own); ``severity`` replaces the
    turbulence severity; an explicit ``sigma_w_mps`` replaces the intensity; ``file``/``time`` (None: keep the
    base's) pick the mesoscale output."""
    turbulence = base.turbulence.model_copy(update={"severity": draw.severity, "sigma_w_mps": draw.sigma_w_mps})
    update = {"speed_10m_mps": draw.speed_10m_m_s, "direction_deg": draw.direction_deg % 360.0,
              "turbulence": turbulence}
    if draw.file is not None:
        update["file"] = draw.file
    if draw.time is not None:
        update["time"] = draw.time
    return base.model_copy(update=update)


def _same_geometry(grids: list[WindGrid]) -> bool:
    g0 = grids[0]
    return all(g.grid_yaw_rad == g0.grid_yaw_rad and np.array_equal(g.x_m, g0.x_m) and np.array_equal(g.y_m, g0.y_m)
               and np.array_equal(g.heights_m, g0.heights_m) for g in grids[1:])


@dataclass
class StackedMeanWind:
    """Per-flight mean fields of one geometry: ``velocity(points (n,3), t)``, row i of ``points`` is flight i.

    The wind stage's :func:`wrp_eval.wind.grid.interpolate` evaluated for all flights at once, each against
    its own node values, so each row is bit-identical to the wind stage's interpolation of that flight's grid
    alone (tests/campaign/test_trial_wind.py checks this exactly).
    """

    grids: list[WindGrid]
    method: str = "idw"
    idw_power: float = 2.0
    clamp: bool = False

    def __post_init__(self) -> None:
        self.geometry = self.grids[0]
        self.values = np.stack([g.velocity_mps for g in self.grids])      # (F, nx, ny, nz, 3)

    def velocity(self, points: np.ndarray, t: float = 0.0) -> np.ndarray:
        return interpolate(self.geometry, points, self.method, self.idw_power, self.clamp, values=self.values)


@dataclass
class PerFlightMean:
    """Fallback for grids of different geometry: one interpolation per flight."""

    means: list[GriddedMeanWind]

    def velocity(self, points: np.ndarray, t: float = 0.0) -> np.ndarray:
        return np.concatenate([m.velocity(points[i:i + 1], t) for i, m in enumerate(self.means)])


@dataclass
class PerFlightGusts:
    gusts: list[OneMinusCosineGusts]

    def velocity(self, points: np.ndarray, t: float) -> np.ndarray:
        return np.concatenate([g.velocity(points[i:i + 1], t) for i, g in enumerate(self.gusts)])


def build_trial_wind(base: WindSection, draws: list[WindDraw], ship, dt_s: float,
                     base_dir: str | Path | None = None) -> WindField:
    """One :class:`WindField` for a batch of trials (row i = trial ``draws[i]``); see the module docstring."""
    sections = [trial_wind_section(base, d) for d in draws]
    grids = [build_mean_grid(s, ship, base_dir) for s in sections]
    if _same_geometry(grids):
        mean = StackedMeanWind(grids, base.interpolation, base.idw_power, base.clamp)
    else:
        mean = PerFlightMean([GriddedMeanWind(g, base.interpolation, base.idw_power, base.clamp) for g in grids])
    # the streams build_wind_field(section, ship, 1, seed) gives its single flight
    streams = [np.random.default_rng(d.seed).spawn(1)[0].spawn(2) for d in draws]
    w20 = np.zeros(len(draws))
    any_turbulence = False
    for i, (s, g) in enumerate(zip(sections, grids)):
        t = s.turbulence
        if t.severity == "none" and t.sigma_w_mps is None:
            continue
        any_turbulence = True
        if t.sigma_w_mps is not None:
            w20[i] = 10.0 * t.sigma_w_mps          # the wind stage's intensity override: W20 = 10 sigma_w
        elif t.severity in ("light", "moderate", "severe"):
            w20[i] = severity_w20_mps(t.severity)
        else:  # from_mean: W20 = the mean wind at 20 ft over the ship
            at_20ft = GriddedMeanWind(g, s.interpolation, s.idw_power, s.clamp).velocity(
                np.array([[0.0, 0.0, TWENTY_FT_M]]), 0.0)[0]
            w20[i] = float(np.hypot(at_20ft[0], at_20ft[1]))
    turbulence = None
    if any_turbulence:  # a trial without turbulence gets W20 = 0: zero output from the same filter
        turbulence = DrydenTurbulence(len(draws), dt_s, [st[0] for st in streams], w20, None,
                                      base.turbulence.airspeed_floor_mps)
    gusts = None
    if base.gusts.enabled:
        gs = []
        for s, g, st in zip(sections, grids, streams):
            at_20ft = GriddedMeanWind(g, s.interpolation, s.idw_power, s.clamp).velocity(
                np.array([[0.0, 0.0, TWENTY_FT_M]]), 0.0)[0]
            c = s.gusts
            gs.append(OneMinusCosineGusts(1, [st[1]], c.horizon_s, c.rate_per_min, c.amplitude_mps, c.duration_s,
                                          float(np.arctan2(at_20ft[1], at_20ft[0])), c.direction_spread_deg))
        gusts = PerFlightGusts(gs)
    return WindField(mean, turbulence, gusts)
