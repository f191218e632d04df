"""``wrp-eval envelope CONFIG``: up to what wind, from which directions, the planned mission meets its spec.

    wrp-eval envelope CONFIG [--path P] [--speeds LIST] [--directions N] [--flights N] [--look N]
                             [--resolution M_S] [--out DIR] [--backend local|ray] [--workers K]
                             [--forecast FILE [--time ISO]]

Per wind direction relative to the bow (N evenly spaced, the first dead ahead) the U10 grid (default 0-16 m/s
in 2 m/s steps) is searched for the boundary speed: the highest U10 whose flights meet the spec
(``wrp.evaluate``) with P >= go_probability (0.8). Each cell flies the path in looks of --look flights (up to
--flights) and stops when its confidence interval decides (a sequential test, envelope/README.md); the boundary
is bisected to --resolution m/s. Flight k of every cell draws the same navigation, ship motion and turbulence.
Writes <out>/envelope.json, envelope.csv, envelope.png (polar plot) and envelope.rrd; a re-run resumes and flies
no stored flight again. --forecast reads the forecast mean wind at the ship from a WRF / MM5 netCDF file (else
the ``wind:`` section's) and flies its cell: GO / NO-GO.
"""

from __future__ import annotations

import argparse

from wrp_eval.envelope.config import EnvelopeGrid
from wrp_eval.envelope.jobs import envelope_job, envelope_lines, job_forecast
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath
from wrp_eval.schema import parse_model


def _speeds(text: str) -> tuple[float, ...]:
    try:
        return tuple(float(s) for s in text.split(",") if s.strip())
    except ValueError:
        raise InputError("--speeds", f"expected comma-separated m/s values, got {text!r}") from None


def grid_of(args: argparse.Namespace, base: EnvelopeGrid) -> EnvelopeGrid:
    """The config's grid with the command line's overrides (validated: one line on a bad grid)."""
    doc = base.model_dump()
    for key, value in (("speeds_m_s", _speeds(args.speeds) if args.speeds else None),
                       ("directions", args.directions), ("max_flights", args.flights),
                       ("look_flights", args.look), ("resolution_m_s", args.resolution)):
        if value is not None:
            doc[key] = value
    if args.flights is not None and args.look is None:
        doc["look_flights"] = min(doc["look_flights"], args.flights)
    return parse_model(EnvelopeGrid, doc, "envelope grid (--speeds/--directions/--flights/--look/--resolution)")


def _run(args: argparse.Namespace) -> int:
    if args.time is not None and args.forecast is None:
        raise InputError("--time", "needs --forecast FILE")
    ctx = ExperimentContext.load(args.config)
    grid = grid_of(args, ctx.config.envelope.grid)
    forecast = job_forecast(ctx, args.forecast, args.time)
    path = FlightPath.load(args.path) if args.path else None
    job = envelope_job(ctx, grid, out_dir=args.out, path=path, forecast=forecast, backend=args.backend,
                       workers=args.workers)
    print("\n".join(envelope_lines(job.envelope)))
    print("wrote " + ", ".join(job.files.values()))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("envelope", help="P(meets spec) against wind speed and direction: the mission's envelope",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config")
    p.add_argument("--path", default=None, help="path.json to fly (default campaign.path or the plan)")
    p.add_argument("--speeds", default=None, help="U10 grid, comma-separated m/s (default envelope.grid)")
    p.add_argument("--directions", type=int, default=None, help="wind directions around the ship")
    p.add_argument("--flights", type=int, default=None, help="most flights per cell")
    p.add_argument("--look", type=int, default=None, help="flights per look of the sequential test")
    p.add_argument("--resolution", type=float, default=None, help="bisect the boundary to this (m/s)")
    p.add_argument("--out", default=None, help="folder (default envelope.out_dir or logs/<run.name>/envelope)")
    p.add_argument("--backend", choices=("local", "ray"), default=None, help="overrides campaign.backend.kind")
    p.add_argument("--workers", type=int, default=None, help="worker processes / Ray CPUs (0: in-process)")
    p.add_argument("--forecast", default=None, help="WRF / MM5 netCDF file: the forecast mean wind at the ship")
    p.add_argument("--time", default=None, help="ISO time in the forecast file (default its first output)")
    p.set_defaults(func=_run)
