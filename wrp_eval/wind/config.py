"""The ``wind:`` section of an experiment config (embedded default: a synthetic marine boundary layer).

Conventions: ``direction_deg`` is meteorological - the compass bearing the wind blows FROM, degrees clockwise
from true north (270 = a westerly, blowing toward the east). The ship's position and heading are not here:
they come from the ship (AIS) and are passed to :func:`wrp_eval.wind.field.build_wind_field`.
A relative ``file`` is resolved against the folder given to the builder (the config file's folder in the
CLI), else the working directory.
"""

from __future__ import annotations

from itertools import pairwise
from typing import Any, Literal

from pydantic import Field, model_validator

from wrp_eval.schema import StrictModel, renamed_keys


class WindGridSection(StrictModel):
    """Ship-frame grid of the synthetic field, and of the samples ``wrp-eval wind field`` writes."""

    x_range_m: tuple[float, float] = Field((-300.0, 300.0), description="along the ship (bow +x), m")
    y_range_m: tuple[float, float] = Field((-300.0, 300.0), description="across the ship (port +y), m")
    spacing_m: float = Field(10.0, gt=0, description="horizontal node spacing, m")
    z_levels_m: tuple[float, ...] = Field((0.0, 2.0, 5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 80.0, 100.0, 130.0,
                                           160.0, 200.0), min_length=2,
                                          description="level heights above the sea, m, increasing")

    @model_validator(mode="after")
    def _check(self) -> "WindGridSection":
        for name, (lo, hi) in (("x_range_m", self.x_range_m), ("y_range_m", self.y_range_m)):
            if not hi - lo >= self.spacing_m:
                raise ValueError(f"wind.grid.{name}: the range must be at least one spacing wide")
        z = self.z_levels_m
        if any(b <= a for a, b in pairwise(z)) or z[0] < 0:
            raise ValueError("wind.grid.z_levels_m must be >= 0 and strictly increasing")
        return self


class TurbulenceSection(StrictModel):
    """Dryden turbulence (MIL-F-8785C low altitude)."""

    severity: Literal["none", "from_mean", "light", "moderate", "severe"] = Field(
        "from_mean", description="W20 from the mean field at 20 ft, or a MIL-F-8785C preset "
                                 "(light/moderate/severe: W20 = 15/30/45 kt), or none")
    sigma_w_m_s: float | None = Field(None, ge=0, description="intensity override: sigma_w (W20 = 10 sigma_w)")
    airspeed_floor_m_s: float = Field(2.0, gt=0, description="floor of the frozen-field speed V (hover)")

    @model_validator(mode="before")
    @classmethod
    def _old_keys(cls, data: Any) -> Any:
        return renamed_keys(data, {"sigma_w_mps": "sigma_w_m_s", "airspeed_floor_mps": "airspeed_floor_m_s"},
                            "wind.turbulence")


class GustSection(StrictModel):
    """Discrete 1-cosine gusts (off by default)."""

    enabled: bool = False
    rate_per_min: float = Field(1.0, ge=0, description="mean number of gust onsets per minute")
    amplitude_m_s: float = Field(3.0, ge=0)
    duration_s: float = Field(4.0, gt=0)
    direction_spread_deg: float = Field(30.0, ge=0, le=180, description="+- spread about the mean wind azimuth")
    horizon_s: float = Field(1800.0, gt=0, description="gusts are drawn over [0, horizon_s]")

    @model_validator(mode="before")
    @classmethod
    def _old_keys(cls, data: Any) -> Any:
        return renamed_keys(data, {"amplitude_mps": "amplitude_m_s"}, "wind.gusts")


class AirWakeSection(StrictModel):
    """The ship's air wake (:mod:`wrp_eval.wind.air_wake`): the mean wind is reduced and the turbulence raised
    in the lee of the hull box. The box comes from the ship's particulars: with only a pose (lat, lon, heading)
    there is no hull and the wake is skipped, whatever ``enabled`` says.

    Defaults from the PRIME building-wake model (Schulman, Strimaitis & Scire 2000, J. Air & Waste Manage.
    Assoc. 50:378-390; EPA AERMOD ``prime.f``): near-wake speed deficit dU/U = 0.7 and wake factor 1.7 on
    sigma_v, sigma_w (Weil 1996); wake influence limited to 15 scale lengths R."""

    enabled: bool = Field(True, description="model the wake when the hull (ShipParticulars) is known")
    lee_deficit: float = Field(0.7, ge=0, le=1.3, description="fraction of the mean wind removed in the "
                               "recirculation cavity (PRIME dU/U = 0.7; > 1 reverses the mean flow, up to the "
                               "0.3 U return flow Drivas & Shair 1974 measured)")
    turbulence_ratio: float = Field(1.7, ge=1, le=5, description="turbulence sigma in the cavity / free-stream "
                                    "sigma at the same height (Weil 1996 wake factor 1.7); 5: sanity bound")
    extent_scale_lengths: float = Field(15.0, gt=0, le=50, description="wake length past the cavity end, in "
                                        "Wilson scale lengths R (PRIME limits wake effects to 15 R)")


class WindSection(StrictModel):
    """Mean field (synthetic, WRF or MM5-as-netCDF) + turbulence + gusts + the ship's air wake, and how it is
    interpolated."""

    source: Literal["synthetic", "wrf", "mm5"] = "synthetic"
    file: str | None = Field(None, description="netCDF file for source wrf / mm5")
    time: str | None = Field(None, description="ISO time in the file (default: the first output)")
    time_interpolation: Literal["nearest", "linear"] = "nearest"
    speed_10m_m_s: float = Field(6.0, ge=0, le=60, description="synthetic: mean speed at 10 m")
    direction_deg: float = Field(270.0, ge=0, lt=360, description="synthetic: direction the wind blows FROM")
    charnock_alpha: float = Field(0.011, gt=0, le=0.1, description="Charnock constant (0.011 open sea)")
    veer_deg_per_100m: float = Field(0.0, ge=-90, le=90, description="synthetic: clockwise turn per 100 m")
    gradient_per_km: float = Field(0.0, ge=-0.5, le=0.5, description="synthetic: fractional speed change per "
                                                                      "km downwind")
    fill_heights_m: tuple[float, ...] = Field((0.0, 2.0, 5.0, 10.0, 20.0), description="wrf/mm5: log-law levels "
                                              "added below the lowest model level")
    interpolation: Literal["idw", "trilinear"] = Field("idw", description="idw = the paper's 8-point "
                                                                           "inverse-distance weighting")
    idw_power: float = Field(2.0, gt=0)
    clamp: bool = Field(False, description="clip points outside the grid instead of failing")
    grid: WindGridSection = WindGridSection()
    turbulence: TurbulenceSection = TurbulenceSection()
    gusts: GustSection = GustSection()
    air_wake: AirWakeSection = AirWakeSection()

    @model_validator(mode="before")
    @classmethod
    def _old_keys(cls, data: Any) -> Any:
        return renamed_keys(data, {"speed_10m_mps": "speed_10m_m_s"}, "wind")

    @model_validator(mode="after")
    def _check(self) -> "WindSection":
        if self.source in ("wrf", "mm5") and not self.file:
            raise ValueError(f"wind.file is required when wind.source is {self.source}")
        return self
