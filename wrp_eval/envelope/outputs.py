"""What an envelope writes: envelope.json (every cell and its provenance), envelope.csv (a row per cell),
envelope.png (the polar plot) and envelope.rrd (entities ``envelope/*``), each atomically."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import cast

import numpy as np
import rerun as rr
from matplotlib import colormaps
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.projections.polar import PolarAxes

from wrp_eval.atomic import atomic_path, write_text_atomic
from wrp_eval.envelope.result import Envelope
from wrp_eval.recording import recording

CSV_COLUMNS = ("direction", "relative_deg", "compass_from_deg", "speed_m_s", "flights", "decision", "meets",
               "p_meets_spec", "repeated_ci_low", "repeated_ci_high", "nominal_ci_low", "nominal_ci_high",
               "p_completed", "completeness_mean", "error_mean_m", "error_p95_m", "expected_sorties",
               "mission_time_s", "views_lost", "limit", "endings", "forecast", "folder")
COLOUR_MAP = "RdYlGn"


def write_envelope(envelope: Envelope, out: str | Path, ship_length_m: float, ship_breadth_m: float,
                   recording_id: str | None = None) -> dict:
    """Every output into ``out``; returns name -> file. ``recording_id``: of the recording the .rrd joins."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = {"json": write_text_atomic(out / "envelope.json", json.dumps(envelope.to_json_dict(), indent=1)),
             "csv": write_text_atomic(out / "envelope.csv", cells_csv(envelope)),
             "png": polar_plot(envelope, out / "envelope.png", ship_length_m, ship_breadth_m),
             "rrd": save_envelope_recording(envelope, out / "envelope.rrd", recording_id)}
    return {k: str(v) for k, v in files.items()}


def cells_csv(envelope: Envelope) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(CSV_COLUMNS)
    for c in envelope.cells:
        writer.writerow([c.direction, c.relative_deg, c.compass_from_deg, c.speed_m_s, c.flights, c.decision,
                         c.meets, c.p_meets_spec, *c.repeated_ci, *c.p_meets_spec_ci, c.p_completed,
                         c.completeness_mean, c.error_mean_m, c.error_p95_m, c.expected_sorties,
                         c.mission_time_s, c.views_lost, c.limit,
                         json.dumps(c.endings, sort_keys=True), c.forecast, c.folder])
    return buffer.getvalue()


def _boundary_line(envelope: Envelope, top_m_s: float, proved: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(theta rad, radius m/s) of the closed boundary line (a direction without a meeting cell sits at 0, one
    meeting at the top of the grid at the top); ``proved``: the line of the cells the test decided "meets"."""
    theta, radius = [], []
    for b in sorted(envelope.boundaries, key=lambda b: b.relative_deg):
        theta.append(np.radians(b.relative_deg))
        if proved:
            radius.append(b.proved_m_s or 0.0)
        else:
            radius.append(top_m_s if b.above_grid else (b.boundary_m_s or 0.0))
    return np.array(theta + theta[:1]), np.array(radius + radius[:1])


def _ship_outline(length: float, breadth: float, scale: float) -> np.ndarray:
    """(k, 2) polar (theta, r) of a top view of the hull, bow up, its length ``scale`` m/s on the plot."""
    half_l, half_b = 0.5, 0.5 * breadth / length
    xy = np.array([[0, half_l], [half_b, 0.25], [half_b, -half_l], [-half_b, -half_l], [-half_b, 0.25],
                   [0, half_l]]) * scale
    return np.stack([np.arctan2(xy[:, 0], xy[:, 1]), np.hypot(xy[:, 0], xy[:, 1])], axis=1)


def polar_plot(envelope: Envelope, file: Path, ship_length_m: float, ship_breadth_m: float) -> Path:
    """Direction (relative to the bow, clockwise, bow up) as the angle, U10 as the radius, each flown cell
    coloured by P(meets spec) (hollow: undecided), the boundary line, the forecast as a star, the ship's
    outline in the centre."""
    top = float(envelope.grid["speeds_m_s"][-1])
    fig = Figure(figsize=(6.4, 6.4))
    ax = cast(PolarAxes, fig.add_subplot(projection="polar"))
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    cells = envelope.cells
    theta = np.radians([c.relative_deg for c in cells])
    radius = np.array([c.speed_m_s for c in cells])
    p = np.array([c.p_meets_spec for c in cells])
    norm = Normalize(0.0, 1.0)
    decided = np.array([c.decision != "undecided" for c in cells], bool)
    art = ax.scatter(theta[decided], radius[decided], c=p[decided], cmap=COLOUR_MAP, norm=norm, s=60,
                     edgecolors="k", linewidths=0.5, zorder=3)
    ax.scatter(theta[~decided], radius[~decided], facecolors="none",
               edgecolors=colormaps[COLOUR_MAP](norm(p[~decided])), s=60, linewidths=1.5, zorder=3)
    line_theta, line_r = _boundary_line(envelope, top)
    ax.plot(line_theta, line_r, "k-", lw=1.5,
            label=f"boundary: P(meets spec) >= {envelope.rule['threshold']:g} (undecided cells by their estimate)")
    proved_theta, proved_r = _boundary_line(envelope, top, proved=True)
    ax.plot(proved_theta, proved_r, "k--", lw=1.0, label="proved by the test (the GO rule)")
    outline = _ship_outline(ship_length_m, ship_breadth_m, 0.3 * top)
    ax.fill(outline[:, 0], outline[:, 1], color="0.6", zorder=2)
    if envelope.forecast is not None:
        f = envelope.forecast
        ax.plot(np.radians(f.relative_deg), f.speed_m_s, marker="*", ms=16, color="tab:blue", mec="k", ls="none",
                zorder=4, label=f"forecast {f.speed_m_s:.1f} m/s" + (
                    "" if envelope.go is None else (": GO" if envelope.go else ": NO-GO")))
    ax.scatter([], [], facecolors="none", edgecolors="0.3", s=60, label="undecided after the last look")
    ax.set_rlim(0, top * 1.05)
    ax.set_rlabel_position(22.5)
    ax.set_xticks(np.radians(np.arange(0, 360, 45)))
    ax.set_xticklabels(["bow", "stbd bow", "stbd beam", "stbd qtr", "stern", "port qtr", "port beam", "port bow"])
    ax.set_title("Mission envelope: U10 (m/s) by wind direction relative to the bow", fontsize=10)
    fig.colorbar(art, ax=ax, shrink=0.7, pad=0.1, label="P(meets spec)")
    ax.legend(loc="lower left", bbox_to_anchor=(-0.12, -0.12), fontsize=8, frameon=False)
    with atomic_path(file) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    return file


def _plane_points(relative_deg, speed_m_s) -> np.ndarray:
    """(n, 3): a cell at angle theta (clockwise from the bow) and radius U as (U sin theta, U cos theta, 0), bow
    along +y as on the polar plot."""
    t = np.radians(np.asarray(relative_deg, float))
    r = np.asarray(speed_m_s, float)
    return np.stack([r * np.sin(t), r * np.cos(t), np.zeros_like(r)], axis=-1)


def save_envelope_recording(envelope: Envelope, file: Path, recording_id: str | None = None) -> Path:
    """Entities ``envelope/cells`` (coloured by P(meets spec), labelled), ``envelope/boundary`` and
    ``envelope/forecast`` on the polar plane (x: starboard, y: bow, metres = m/s of U10); static."""
    cells = envelope.cells
    p = np.array([c.p_meets_spec for c in cells])
    colours = (255 * colormaps[COLOUR_MAP](np.nan_to_num(p))[:, :3]).astype(np.uint8)
    labels = [f"{c.direction} {c.speed_m_s:g} m/s: P {c.p_meets_spec:.2f} [{c.repeated_ci[0]:.2f}, "
              f"{c.repeated_ci[1]:.2f}] over {c.flights} flights, {c.decision}; {c.limit}" for c in cells]
    theta, radius = _boundary_line(envelope, float(envelope.grid["speeds_m_s"][-1]))
    with recording(file, recording_id=recording_id) as rec:
        rec.log("envelope", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.log("envelope/cells", rr.Points3D(_plane_points([c.relative_deg for c in cells],
                                                            [c.speed_m_s for c in cells]),
                                              colors=colours, radii=0.25, labels=labels), static=True)
        rec.log("envelope/boundary", rr.LineStrips3D([_plane_points(np.degrees(theta), radius)]), static=True)
        if envelope.forecast is not None:
            f = envelope.forecast
            rec.log("envelope/forecast", rr.Points3D(_plane_points([f.relative_deg], [f.speed_m_s]), radii=0.4,
                                                     labels=[f"forecast {f.speed_m_s:.1f} m/s from "
                                                             f"{f.compass_from_deg:.0f} deg"]), static=True)
    return file
