"""The envelope job of an experiment: its grid, path, forecast and folder taken from the context; returns data
(the CLI and the run print)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from wrp_eval.campaign.evaluators import DEFAULT_EVALUATOR
from wrp_eval.campaign.rerun_log import campaign_recording_id
from wrp_eval.envelope.config import EnvelopeGrid
from wrp_eval.envelope.forecast import forecast_from_file, forecast_of
from wrp_eval.envelope.outputs import write_envelope
from wrp_eval.envelope.result import Envelope, ForecastWind
from wrp_eval.envelope.runner import run_envelope
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath


@dataclass(frozen=True)
class EnvelopeJob:
    """The envelope and the files written (name -> path)."""

    envelope: Envelope
    files: dict[str, str]


def job_forecast(ctx: ExperimentContext, file: str | Path | None = None, time: str | None = None) -> ForecastWind:
    """The forecast of ``file`` at ``time`` when given, else the ``wind:`` section's mean wind at the ship."""
    if file is not None:
        return forecast_from_file(ctx.config.wind, ctx.particulars, file, time)
    return forecast_of(ctx.config.wind, ctx.particulars, ctx.config_dir, f"wind: section of {ctx.source}")


def envelope_job(ctx: ExperimentContext, grid: EnvelopeGrid, *, out_dir: str | Path | None = None,
                 path: FlightPath | None = None, forecast: ForecastWind | None = None, backend: str | None = None,
                 workers: int | None = None, evaluator: str = DEFAULT_EVALUATOR,
                 evaluator_options: dict | None = None) -> EnvelopeJob:
    """Fly (or resume) the envelope of ``path`` (default the campaign's) on ``grid`` into ``out_dir`` (default
    the run's envelope folder) and write its outputs; ``forecast`` None: the ``wind:`` section's."""
    out = Path(out_dir) if out_dir is not None else ctx.folders.envelope
    path = path if path is not None else ctx.campaign_path
    envelope = run_envelope(ctx, out, grid, path=path, forecast=forecast or job_forecast(ctx), backend=backend,
                            workers=workers, evaluator=evaluator, evaluator_options=evaluator_options)
    proxy = ctx.ship.proxy
    files = write_envelope(envelope, out, proxy.length_m, proxy.breadth_m, campaign_recording_id(path))
    return EnvelopeJob(envelope, files)


def envelope_lines(envelope: Envelope) -> list[str]:
    """The envelope in a few lines of text: the verdict at the forecast and the boundary per direction."""
    lines = []
    cell = envelope.forecast_cell
    if envelope.forecast is not None and cell is not None:
        f = envelope.forecast
        lines.append(f"forecast {f.speed_m_s:.1f} m/s from {f.compass_from_deg:.0f} deg ({cell.direction}): "
                     f"P(meets spec) {cell.p_meets_spec:.2f} [{cell.p_meets_spec_ci[0]:.2f}, "
                     f"{cell.p_meets_spec_ci[1]:.2f}] over {cell.flights} flights -> "
                     f"{'GO' if envelope.go else 'NO-GO'}")
    for b in envelope.boundaries:
        lines.append(f"{b.direction:>17}: {boundary_text(b)}" + (f"; beyond it: {b.limit}" if b.limit else ""))
    lines.append(f"{envelope.flights_flown} flights flown now ({envelope.flights_total} counted) in "
                 f"{envelope.wall_s:.0f} s")
    return lines


def boundary_text(b) -> str:
    if b.boundary_m_s is None:
        return f"below {b.bracket_m_s[1]:g} m/s (not even the lowest speed meets the spec)"
    if b.above_grid:
        return f">= {b.boundary_m_s:g} m/s (the grid's top)"
    return f"{b.boundary_m_s:g} m/s (fails at {b.bracket_m_s[1]:g})"
