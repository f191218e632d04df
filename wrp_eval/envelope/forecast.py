"""The forecast mean wind the operator flies in: U10 and its direction at the ship, from the ``wind:`` section
or from a WRF / MM5 netCDF file through the wind stage's reader (:func:`wrp_eval.wind.field.build_mean_grid`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wrp_eval.envelope.result import ForecastWind
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.field import build_mean_grid
from wrp_eval.wind.grid import interpolate

U10_POINT_M = (0.0, 0.0, 10.0)      # the ship's position, 10 m above the sea


def relative_from_deg(velocity_ship: np.ndarray) -> float:
    """The direction the ship-frame wind ``velocity_ship`` (3,) m/s (x bow, y port) blows FROM, clockwise from
    the bow (deg, [0, 360)): a seaman's relative bearing (90: on the starboard beam)."""
    towards_port, ahead = float(velocity_ship[1]), float(velocity_ship[0])
    return float(np.degrees(np.arctan2(towards_port, -ahead)) % 360.0)


def forecast_of(wind: WindSection, ship, base_dir: str | Path | None, source: str) -> ForecastWind:
    """The mean wind 10 m above the sea at the ship of the ``wind`` section (synthetic or netCDF). ship: the
    ship's particulars (position and heading)."""
    heading = float(ship.heading_deg)
    if wind.source == "synthetic":
        relative = (wind.direction_deg - heading) % 360.0
        return ForecastWind(float(wind.speed_10m_m_s), float(wind.direction_deg), float(relative), source)
    grid = build_mean_grid(wind, ship, base_dir)
    velocity = interpolate(grid, np.array([U10_POINT_M]), wind.interpolation, wind.idw_power, clamp=True)[0]
    relative = relative_from_deg(velocity)
    return ForecastWind(float(np.hypot(velocity[0], velocity[1])), (heading + relative) % 360.0, relative, source)


def forecast_from_file(wind: WindSection, ship, file: str | Path, time: str | None) -> ForecastWind:
    """The forecast of a WRF netCDF ``file`` (an MM5 file when the ``wind:`` section says mm5) at ISO ``time``
    (None: the file's first output), interpolated linearly in time between outputs, so that a time outside the
    file's span is refused (the wind stage's ``nearest`` mode would answer with the closest output, however far).
    A bad file or time is an :class:`~wrp_eval.errors.InputError` naming it."""
    source = wind.source if wind.source in ("wrf", "mm5") else "wrf"
    section = wind.model_copy(update={"source": source, "file": str(file), "time": time,
                                      "time_interpolation": "linear"})
    return forecast_of(section, ship, None, f"{source} {file}" + (f" at {time}" if time else " (first output)"))
