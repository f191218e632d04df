"""The envelope as a typed document: what ``envelope.json`` holds and the report and the plots read."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass


@dataclass(frozen=True)
class CellResult:
    """One flown cell. relative_deg: wind FROM, clockwise from the bow; compass_from_deg: the same as a
    meteorological direction; speed_m_s: U10; flights: counted by the test; decision: meets / fails / undecided
    (sequential.py); meets: counts as meeting the threshold (decided, or undecided with P >= threshold);
    p_meets_spec with ``repeated_ci``, the test's Clopper-Pearson interval at the repeated level (valid however
    early the cell stopped: the interval to read), and ``p_meets_spec_ci``, the nominal fixed-n interval at the
    plain confidence (not adjusted for the early stop; kept for comparison with the evaluation's); completeness,
    error mean and p95 (m, flights that did not fail); sorties and mission time (s, completed missions);
    views_lost: mean views no sortie took; endings: counts by ending; limit: what kept flights from meeting
    the spec; folder: the cell's campaign folder; forecast: the cell of the forecast wind."""

    relative_deg: float
    compass_from_deg: float
    speed_m_s: float
    direction: str
    flights: int
    decision: str
    meets: bool
    p_meets_spec: float
    p_meets_spec_ci: tuple[float, float]
    repeated_ci: tuple[float, float]
    p_completed: float
    completeness_mean: float
    error_mean_m: float
    error_p95_m: float
    expected_sorties: float
    mission_time_s: float
    views_lost: float
    endings: dict[str, int]
    limit: str
    folder: str
    forecast: bool = False


@dataclass(frozen=True)
class DirectionBoundary:
    """Per direction: boundary_m_s the highest U10 whose cell counts as meeting the threshold (undecided cells by
    their point estimate: no error control; None: not even the lowest grid speed); proved_m_s the highest U10
    whose cell the sequential test decided "meets" (the GO rule; None: none); bracket_m_s (boundary, lowest
    failing speed above it; None where there is none); above_grid: the highest grid speed meets; limit: what
    limits the mission in the first failing cell above the boundary ("" when there is none)."""

    relative_deg: float
    direction: str
    boundary_m_s: float | None
    proved_m_s: float | None
    bracket_m_s: tuple[float | None, float | None]
    above_grid: bool
    limit: str


@dataclass(frozen=True)
class ForecastWind:
    """The forecast mean wind: U10 (m/s), the direction FROM (deg, compass) and relative to the bow, and where
    it came from (the ``wind:`` section, or a netCDF file and time)."""

    speed_m_s: float
    compass_from_deg: float
    relative_deg: float
    source: str


@dataclass(frozen=True)
class Envelope:
    """The whole envelope: every flown cell, the boundary per direction, the forecast and its cell (None when
    no forecast was flown), the verdict there (GO when the sequential test decided that the forecast cell meets
    the threshold; None without a forecast), the rule (threshold, confidence, spec, looks), the grid, how many
    flights were flown this call and in all, the wall time of this call, and the provenance (config, path
    digest, root seed, versions)."""

    cells: tuple[CellResult, ...]
    boundaries: tuple[DirectionBoundary, ...]
    forecast: ForecastWind | None
    go: bool | None
    rule: dict
    grid: dict
    flights_flown: int
    flights_total: int
    wall_s: float
    provenance: dict

    @property
    def forecast_cell(self) -> CellResult | None:
        return next((c for c in self.cells if c.forecast), None)

    def to_json_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_json_dict(cls, doc: dict) -> "Envelope":
        def tuple_of(value):
            return tuple(value) if isinstance(value, list) else value
        cells = tuple(CellResult(**{k: tuple_of(v) for k, v in c.items()}) for c in doc["cells"])
        bounds = tuple(DirectionBoundary(**{k: tuple_of(v) for k, v in b.items()}) for b in doc["boundaries"])
        forecast = ForecastWind(**doc["forecast"]) if doc.get("forecast") else None
        return cls(cells, bounds, forecast, **{k: doc[k] for k in ("go", "rule", "grid", "flights_flown",
                                                                     "flights_total", "wall_s", "provenance")})
