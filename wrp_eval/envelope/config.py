"""The ``envelope:`` section of an experiment config: the wind grid the mission's envelope is flown on.

The spec the flights must meet, the probability threshold (``go_probability``, 0.8) and the confidence are the
``wrp.evaluate`` section's: the envelope and the forecast's go / no-go read the same rule.
"""

from __future__ import annotations

from itertools import pairwise

from pydantic import Field, field_validator, model_validator

from wrp_eval.schema import StrictModel


class EnvelopeGrid(StrictModel):
    """Where the envelope looks: ``speeds_m_s`` the U10 grid (m/s at 10 m, strictly increasing) searched in each
    of ``directions`` wind directions evenly spaced around the ship (relative to its heading, the first from
    dead ahead); ``look_flights`` flights are added to a cell at each look of the sequential test, up to
    ``max_flights``; the boundary speed is bisected until its bracket is at most ``resolution_m_s`` wide."""

    speeds_m_s: tuple[float, ...] = Field((0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0), min_length=1)
    directions: int = Field(8, ge=1, le=72)
    max_flights: int = Field(32, ge=1, le=100_000)
    look_flights: int = Field(8, ge=1, le=100_000)
    resolution_m_s: float = Field(0.5, ge=0.05, description="bisect the boundary to this (m/s); cell keys keep "
                                  "6 decimals, so finer would not be resolved")

    @field_validator("speeds_m_s")
    @classmethod
    def _increasing(cls, speeds: tuple[float, ...]) -> tuple[float, ...]:
        if any(s < 0 or s > 60 for s in speeds):
            raise ValueError("speeds must lie in [0, 60] m/s")
        if any(b <= a for a, b in pairwise(speeds)):
            raise ValueError("speeds must be strictly increasing")
        return speeds

    @model_validator(mode="after")
    def _looks_fit(self) -> "EnvelopeGrid":
        if self.look_flights > self.max_flights:
            raise ValueError(f"look_flights {self.look_flights} exceeds max_flights {self.max_flights}")
        return self


# The coarser grid of `wrp-eval run` (issue 29 item 5: the operator's first page, with `make run` within 5
# minutes on the 2-core machine): bow, starboard beam, stern, port beam at 4 m/s steps, no bisection (the
# boundary bracketed to the 4 m/s grid step); `wrp-eval envelope` refines it.
RUN_GRID = EnvelopeGrid(speeds_m_s=(0.0, 4.0, 8.0, 12.0, 16.0), directions=4, max_flights=32, look_flights=8,
                        resolution_m_s=4.0)


class EnvelopeSection(StrictModel):
    """``wrp-eval envelope`` flies ``grid``; ``wrp-eval run`` flies ``run_grid`` (none: the run writes no
    envelope). out_dir: none = logs/<run.name>/envelope."""

    grid: EnvelopeGrid = EnvelopeGrid()
    run_grid: EnvelopeGrid | None = RUN_GRID
    out_dir: str | None = None
