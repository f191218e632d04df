"""``wrp-eval bench --only envelope``: the default envelope of the quickstart path, timed.

envelope.wall_s: the default grid (U10 0-16 m/s in 2 m/s steps x 8 directions, looks of 8 flights up to 32,
boundary to 0.5 m/s) and the forecast cell, flown from scratch with 2 workers and the synthetic oracle; anchor:
the issue's target of 5 minutes on the 2-core machine. envelope.flights: the flights it took (the fixed grid
would be 72 cells x 32). envelope.cells. envelope.boundary_m_s.<direction>: the boundary speed per direction
(NaN: not even the lowest grid speed meets the spec). envelope.flights_per_min: the flights' rate.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from wrp_eval.bench_record import BenchRecord
from wrp_eval.campaign.capture_bench import quickstart_context
from wrp_eval.config import ExperimentConfig
from wrp_eval.envelope.jobs import envelope_job

TARGET_S = 300.0


def run_bench(out_dir: Path | None = None) -> list[BenchRecord]:
    ctx = quickstart_context()
    doc = ctx.config.model_dump(mode="json")
    doc["campaign"]["backend"].update({"kind": "local", "workers": 2})
    ctx = ctx.with_config(ExperimentConfig.model_validate(doc))
    grid = ctx.config.envelope.grid
    with tempfile.TemporaryDirectory() as tmp:
        job = envelope_job(ctx, grid, out_dir=Path(out_dir or tmp) / "envelope")
    env = job.envelope
    note = (f"{grid.directions} directions x U10 {grid.speeds_m_s[0]:g}-{grid.speeds_m_s[-1]:g} m/s, looks of "
            f"{grid.look_flights} up to {grid.max_flights}, boundary to {grid.resolution_m_s:g} m/s, 2 workers")
    records = [
        BenchRecord("envelope.wall_s", env.wall_s, "s", "issue 29 target (2-core machine)", TARGET_S, note),
        BenchRecord("envelope.flights", env.flights_flown, "flights", "the fixed grid at max_flights",
                    grid.directions * len(grid.speeds_m_s) * grid.max_flights, note),
        BenchRecord("envelope.cells", len(env.cells), "cells", "the fixed grid",
                    grid.directions * len(grid.speeds_m_s)),
        BenchRecord("envelope.flights_per_min", 60.0 * env.flights_flown / env.wall_s, "flights/min", note=note),
    ]
    for b in env.boundaries:
        records.append(BenchRecord(f"envelope.boundary_m_s.{b.direction.replace(' ', '_')}",
                                   float("nan") if b.boundary_m_s is None else b.boundary_m_s, "m/s",
                                   note=f"fails at {b.bracket_m_s[1]}; beyond it: {b.limit}"))
    return records
