"""``logs/<run>/report.md``: the run's tables and figures, the paper's figures beside ours as anchors.

The paper's values (Tables 3, 4, 7 and Sec. 4.1) are comparison points measured on another system (Unity
scene, ContextCapture, a Xeon + RTX 3090): they are printed beside what we measured, never substituted.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from wrp_eval.atomic import atomic_path, write_text_atomic
from wrp_eval.envelope.jobs import boundary_text
from wrp_eval.envelope.result import Envelope
from wrp_eval.experiment import ExperimentContext, evaluated_wrp_dir
from wrp_eval.run_summary import CampaignRun, RunSummary, SurrogateFit
from wrp_eval.surrogate.data import TrialData
from wrp_eval.wind.field import sample_mean_field
from wrp_eval.wind.outputs import quiver_png
from wrp_eval.wrp.evaluation import EvaluationResult
from wrp_eval.wrp.optimize import Table3Row
from wrp_eval.wrp.risk import ViewRisk

# Paper anchors (wind-resistance-aerial-path-planning, Sec. 4.1 and Tables 3, 4, 7; stylized ship).
PAPER: dict[str, Any] = {
    "views": 49, "length_m": 684.566, "flight_time_s": 159.764,
    "min_s": 2.708, "max_s": 0.236, "tsp_s": 25.537,
    "surrogate_r2": 0.98, "surrogate_rmse": 0.16,
    "iswrp_t030": {"offset_rate_pct": 28.57, "position_offset_m": 56.96717, "rotation_offset_deg": 269.9075,
                   "time_s": 79.282, "error": 3.01412},
    "swrp_t030": {"offset_rate_pct": 100.0, "position_offset_m": 207.8728, "rotation_offset_deg": 788.8271,
                  "time_s": 297.169, "error": 3.27652},
    "table4_no_wrp_mean_error": float(np.mean([3.70727, 3.54705, 3.68358, 3.77493, 3.48076])),
}


def _savefig(fig, file: Path) -> Path:
    """``fig`` as a PNG at 90 dpi, written atomically; returns ``file``."""
    with atomic_path(file) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    return file


def ship_path_figure(mesh, path, file: Path, risk_m: np.ndarray | None = None) -> Path:
    """The ship mesh (shaded), the tour and the viewpoints (surface blue, transition orange; with ``risk_m``
    (n,) each viewpoint coloured by its risk, mm, :mod:`wrp_eval.wrp.risk`)."""

    fig = Figure(figsize=(11, 6))
    ax = fig.add_subplot(projection="3d")
    above = mesh.triangles_center[:, 2] > 0
    light = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    shade = 0.35 + 0.65 * np.clip(mesh.face_normals[above] @ light, 0, 1)
    ax.add_collection3d(Poly3DCollection(mesh.triangles[above], facecolors=matplotlib.colormaps["gray"](shade),
                                         linewidths=0))
    p = path.positions
    ax.plot(p[:, 0], p[:, 1], p[:, 2], "-", color="0.4", lw=0.8)
    transition = path.kind == 1
    if risk_m is not None:
        dots = ax.scatter(*p.T, s=24, c=1e3 * np.nan_to_num(risk_m), cmap="inferno_r", depthshade=False,
                          label="viewpoints (colour: risk)")
        fig.colorbar(dots, ax=ax, shrink=0.6, label="risk: error std the view adds when missed (mm)")
    else:
        ax.scatter(*p[~transition].T, s=12, c="tab:blue", label="surface views", depthshade=False)
        if transition.any():
            ax.scatter(*p[transition].T, s=18, c="tab:orange", label="transition views", depthshade=False)
    lo, hi = p.min(0), p.max(0)
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    top = 1.15 * float(hi[2])
    ax.set_zlim(0, top)
    ax.set_box_aspect((1, 1, max(top / (2 * half), 0.15)))   # true proportions, not a cube
    ax.set_xlabel("x (m, bow +)")
    ax.set_ylabel("y (m, port +)")
    ax.set_zlabel("z (m)")
    ax.view_init(25, -60)
    ax.legend(loc="upper left")
    ax.set_title(f"{len(path)} viewpoints, {path.length_m:.0f} m")
    fig.tight_layout()
    out = _savefig(fig, file)
    return out


def offsets_figure(offsets: np.ndarray, file: Path) -> Path:
    """Histograms of the flown offsets (all trials x viewpoints): dx, dy, dz (m) and dyaw (deg)."""

    flat = offsets.reshape(-1, 4)
    flat = flat[np.all(np.isfinite(flat), axis=1)]
    fig = Figure(figsize=(14, 3.2))
    axes = fig.subplots(1, 4)
    for ax, k, name in zip(axes, range(4), ("dx (m)", "dy (m)", "dz (m)", "dyaw (deg)"), strict=True):
        values = np.degrees(flat[:, k]) if k == 3 else flat[:, k]
        ax.hist(values, bins=60, color="tab:blue")
        ax.set_xlabel(name)
    axes[0].set_ylabel("captures")
    fig.suptitle("flown offsets from the planned viewpoints (commanded box + wind)")
    fig.tight_layout()
    out = _savefig(fig, file)
    return out


def fmt(value, digits: int = 3) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    return f"{float(value):.{digits}g}" if abs(float(value)) < 1e4 else f"{float(value):.0f}"


def _ci(ci) -> str:
    return f"[{fmt(ci[0])}, {fmt(ci[1])}]" if ci else "n/a"


def _design_text(design: str) -> str:
    """What a campaign's perturbation design means, for the report."""
    if design == "physical":
        return ("the path flown as planned (`physical` design: every capture error from the flight: navigation, "
                "gimbal, capture mode, battery swaps and the autopilot's return rules, air wake, ship motion)")
    return f"commanded offsets from the campaign's `{design}` perturbation design"


def operator_section(ev: EvaluationResult) -> list[str]:
    """The first thing an operator reads: go / no-go for the forecast wind, P(meets spec) with its CI, views not
    taken and sorties, where the per-view risk is."""
    fc = ev.forecast
    if fc is None:
        return []
    row = fc.row
    return [
        f"## Go / no-go: **{'GO' if fc.go else 'NO-GO'}** (path `{row.path}`)",
        "",
        f"In the forecast wind ({fc.wind_speed_10m_m_s:g} m/s at 10 m from {fc.wind_direction_deg:g} deg, "
        f"turbulence as the campaign draws it), {row.trials} simulated flights of the path to fly:",
        "",
        "| P(meets spec) | CI | views not taken (mean) | P(completed) | P(one sortie) | expected sorties | CI | "
        "mission time (s) |",
        "|---|---|---|---|---|---|---|---|",
        f"| {fmt(row.p_meets_spec, 3)} | {_ci(row.p_meets_spec_ci)} | {fmt(row.mean_views_not_taken, 2)} | "
        f"{fmt(row.p_completed, 3)} | {fmt(row.p_one_sortie, 3)} | {fmt(row.expected_sorties, 3)} | "
        f"{_ci(row.expected_sorties_ci)} | {fmt(row.mean_mission_time_s, 4)} |",
        "",
        "Sorties: after a return home on energy the operator swaps the battery and resumes at the breakpoint "
        "(`sim.mission`: up to max_sorties, swap_time_s on deck). P(completed): the mission flown to its end; "
        "P(one sortie): completed on one battery; sorties and mission time (swaps included) are those of the "
        "completed missions.",
        "",
        *fc.stress_notes,
        f"Spec: error <= {fmt(row.spec_error_m, 4)} m and completeness >= {fmt(row.spec_completeness, 2)}. "
        f"GO needs the lower {ev.confidence:.0%} bound of P(meets spec) >= {fc.go_probability:g}. Where the "
        "error's spread comes from: the per-view risk map below (and `risk/viewpoints` in run.rrd).",
        "",
    ]


# A mission file holds earth-fixed waypoints (WGS84): the ship moves under them (DESIGN.md, ship motion).
EARTH_FRAME_WARNING = (
    "**Earth frame**: the exported missions are waypoints fixed to the earth, computed for the ship's position "
    "and heading in the `ship:` section; the simulation holds the ship there (heave, roll and pitch only). "
    "For a ship under way, or one swinging at anchor, the waypoints do not follow it: re-plan from a fresh AIS "
    "position and heading just before take-off, or fly a ship-relative (follow-me) mission.")


def envelope_section(env: Envelope, path_name: str, figure: str, risk_figure: str | None) -> list[str]:
    """The operator's first page: go / no-go at the forecast read off the envelope, the boundary speed per
    direction and what limits the mission beyond it, sorties and mission time at the forecast, the per-view risk
    map, the earth-frame warning. figure / risk_figure: the envelope's and the risk map's images, relative to the
    report."""
    cell, f, rule = env.forecast_cell, env.forecast, env.rule
    verdict = "no forecast" if env.go is None else ("GO" if env.go else "NO-GO")
    lines = [f"## Go / no-go: **{verdict}** at the forecast (path `{path_name}`)", ""]
    if cell is not None and f is not None:
        lines += [
            f"Forecast {f.speed_m_s:.1f} m/s at 10 m from {f.compass_from_deg:.0f} deg ({cell.direction}, "
            f"{f.relative_deg:.0f} deg off the bow; {f.source}): P(meets spec) **{cell.p_meets_spec:.2f}** "
            f"{_ci(cell.repeated_ci)} over {cell.flights} simulated flights (the sequential test's interval, valid "
            f"for its early stop; nominal fixed-n {_ci(cell.p_meets_spec_ci)}); the test says *{cell.decision}*: "
            f"GO needs its lower bound >= {rule['threshold']:g}, which with at most {rule['max_flights']} flights "
            "takes flights without a miss.", "",
            "| at the forecast | P(completed) | expected sorties | mission time (s) | views lost (mean) | "
            "mean error (mm) | p95 error (mm) |", "|---|---|---|---|---|---|---|",
            f"| {cell.direction} {cell.speed_m_s:g} m/s | {fmt(cell.p_completed, 3)} | "
            f"{fmt(cell.expected_sorties, 3)} | "
            f"{fmt(cell.mission_time_s, 4)} | {fmt(cell.views_lost, 2)} | {fmt(1e3 * cell.error_mean_m, 4)} | "
            f"{fmt(1e3 * cell.error_p95_m, 4)} |", ""]
    lines += ["### Wind envelope", "", f"![envelope]({figure})", "",
              f"Boundary: the highest U10 whose flights meet the spec (error <= {fmt(1e3 * rule['spec_error_m'], 4)} "
              f"mm, completeness >= {fmt(rule['spec_completeness'], 2)}) with P >= {rule['threshold']:g}, per wind "
              "direction relative to the bow, cells the test left undecided counted by their estimate (no error "
              "control); proved: the highest U10 the test decided (the GO rule); beyond the boundary, what ended "
              "the flights that missed the spec.", "",
              "| wind from | boundary U10 | proved up to | beyond it |", "|---|---|---|---|"]
    lines += [f"| {b.direction} | {boundary_text(b)} | "
              f"{'-' if b.proved_m_s is None else f'{b.proved_m_s:g} m/s'} | {b.limit or '-'} |"
              for b in env.boundaries]
    lines += ["", f"{len(env.cells)} cells, {env.flights_total} flights ({rule['test']}; looks of "
                  f"{rule['look_flights']} up to {rule['max_flights']} flights); `envelope/envelope.json`, "
                  "`envelope.csv`, entities `envelope/*` in run.rrd.", ""]
    if risk_figure:
        lines += [f"Where the error's spread comes from: ![per-view risk]({risk_figure}) (section Per-view risk).", ""]
    return lines + [EARTH_FRAME_WARNING, ""]


def write_report(ctx: ExperimentContext, path, summary: RunSummary, trials: TrialData, risk: ViewRisk | None = None,
                 envelope: Envelope | None = None, error_sources: dict | None = None) -> Path:
    """Figures under ``<run>/figures`` and ``<run>/report.md``; returns the report's path. path: the planned
    FlightPath; summary: the run summary so far; trials: the campaign's trials (as the surrogate was trained on);
    risk: the per-view risk map (:mod:`wrp_eval.wrp.risk`), None: no risk section; envelope: the run's wind
    envelope (the first page), None: the forecast flights of the evaluation open the report instead;
    error_sources: :func:`wrp_eval.wrp.robust.campaign_error_sources`, None: no such section."""
    config, out = ctx.config, ctx.folders.root
    _figures(ctx, path, trials, risk)
    ev = summary.evaluate
    if envelope is not None:
        if summary.envelope is None:
            raise ValueError("an envelope to report but none in the run summary")
        first_page = envelope_section(envelope, summary.envelope.path,
                                      os.path.relpath(ctx.folders.envelope / "envelope.png", out),
                                      "figures/view_risk.png" if risk is not None else None)
    else:
        first_page = operator_section(ev)
    lines = [*header_section(config.run.name, summary.config, config.run.seed, ctx.ship), *first_page,
             *ship_section(ctx.ship.complexity, path, summary.plan), *WIND_SECTION,
             *campaign_section(summary.campaign, config.campaign.perturbation.design, summary.surrogate),
             *surrogate_section(summary.surrogate), *wrp_section(ev.wrp or {}), *robustness_section(ev),
             *(error_sources_section(error_sources) if error_sources and error_sources["sources"] else []),
             *levers_lines(ctx),
             *(risk_section(risk) if risk is not None else []),
             *missions_section(summary.missions, out), *timings_section(summary.timings_s, out)]
    return write_text_atomic(out / "report.md", "\n".join(lines))


def levers_lines(ctx: ExperimentContext) -> list[str]:
    """The levers section of the evaluation's robust levers.json; none when the evaluation flew no robust path."""
    file = evaluated_wrp_dir(ctx.folders.evaluate, "robust") / "levers.json"
    if not (ctx.config.wrp.evaluate.robust and file.is_file()):
        return []
    return levers_section(json.loads(file.read_text()))


def _figures(ctx: ExperimentContext, path, trials: TrialData, risk: ViewRisk | None) -> None:
    """The report's own figures under ``<run>/figures``: ship and path, the risk map, the wind, the offsets."""
    figures, ship = ctx.folders.root / "figures", ctx.ship
    ship_path_figure(ship.mesh, path, figures / "ship_path.png")
    if risk is not None:
        ship_path_figure(ship.mesh, path, figures / "view_risk.png", risk.risk_m)
    x, y, z, velocity = sample_mean_field(ctx.config.wind, ship.particulars, ctx.config_dir)
    figures.mkdir(parents=True, exist_ok=True)
    quiver_png(figures / "wind_field.png", x, y, z, velocity, ctx.config.wind.source)
    offsets_figure(trials.offsets[trials.complete()], figures / "offsets.png")


def header_section(run_name: str, config_source: str, seed: int, ship) -> list[str]:
    """The title and what was run: config, seed, the ship's proxy."""
    proxy = ship.proxy
    return [f"# wrp-eval run `{run_name}`", "",
            f"Config `{config_source}`, seed {seed}; ship: {ship.particulars.ship_type.value} "
            f"({proxy.length_m:.0f} x {proxy.breadth_m:.0f} x {proxy.height_m:.1f} m proxy above the "
            f"waterline, no-fly margin {proxy.no_fly_margin_m:g} m). The paper's figures are anchors from "
            "another system (Unity scene, ContextCapture, Xeon + RTX 3090), not targets.", ""]


def ship_section(complexity, path, plan_metrics: dict) -> list[str]:
    """Per-face surface complexity and the path's figures beside the paper's Table 7."""
    t = plan_metrics["timings"]
    return [
        "## Ship and path (paper Sec. 3)", "", "![ship and path](figures/ship_path.png)", "",
        "| per face | " + " | ".join(complexity.face_names) + " |",
        "|---|" + "---|" * len(complexity.face_names),
        "| surface complexity (tri/m^2) | " + " | ".join(fmt(c) for c in complexity.complexity) + " |", "",
        "| figure | ours | paper (Table 7, stylized ship) |", "|---|---|---|",
        f"| viewpoints | {len(path)} ({plan_metrics.get('n_transition_views', 0)} transition) | {PAPER['views']} |",
        f"| length (m) | {path.length_m:.1f} | {PAPER['length_m']} |",
        f"| flight time (s) | {path.flight_time_s:.1f} | {PAPER['flight_time_s']} |",
        f"| Min (s) | {fmt(t.get('min_s'))} | {PAPER['min_s']} |",
        f"| Max (s) | {fmt(t.get('max_s'))} | {PAPER['max_s']} |",
        f"| tour (s) | {fmt(t.get('tsp_s'))} | {PAPER['tsp_s']} (GA) |",
        f"| planning total (s) | {fmt(t.get('total_s'))} | |", ""]


WIND_SECTION = ["## Wind (mean field; Dryden turbulence on top in every flight)", "",
                "![wind field](figures/wind_field.png)", ""]


def campaign_section(campaign: CampaignRun, design: str, surrogate: SurrogateFit) -> list[str]:
    """The campaign's trials, its design, the flown offsets and the share of their variance the flights made."""
    share = surrogate.physical_variance_share
    return ["## Monte Carlo campaign", "",
            f"{campaign.trials} trials ({campaign.failed} failed) in `{campaign.dir}`; "
            f"{_design_text(design)}, flown through sampled winds in MuJoCo, scored by the synthetic reconstruction "
            "oracle.", "", "![flown offsets](figures/offsets.png)", "",
            *([f"Share of the flown offsets' variance that the flights made (not commanded): position "
               f"{fmt(share['position'], 3)}, yaw {fmt(share['yaw'], 3)} (issue 18 target >= 0.9).", ""]
              if share else [])]


def surrogate_section(sur: SurrogateFit) -> list[str]:
    """The surrogate's held-out figures beside the paper's Sec. 4.1."""
    return ["## Surrogate (paper Sec. 4.1)", "", "| held-out test trials | ours | paper |", "|---|---|---|",
            f"| R^2 | {fmt(sur.r2, 3)} | {PAPER['surrogate_r2']} |",
            f"| RMSE (m) | {fmt(sur.rmse, 3)} | {PAPER['surrogate_rmse']} (on errors of ~3 m) |",
            f"| MAE (m) | {fmt(sur.mae, 3)} | |", f"| trials | {sur.n} | 300 experiments in all |", "",
            "![parity](surrogate/parity.png)", ""]


def wrp_section(wrp: dict[str, Table3Row]) -> list[str]:
    """The ISWRP and SWRP rows of the paper's Table 3 (ours, the paper's at threshold 0.30 beside); none when the
    evaluation optimised neither (``wrp.evaluate.kinds: []``)."""
    if not wrp:
        return []
    lines = ["## ISWRP and SWRP (paper Table 3 columns; paper at threshold 0.30)", "",
             "| path | threshold (m) | offset rate (%) | position offset (m) | rotation offset (deg) | time (s) | "
             "oracle error, wind-free (m) | paper: rate / pos / rot / time / error |",
             "|---|---|---|---|---|---|---|---|"]
    for kind in (k for k in ("iswrp", "swrp") if k in wrp):      # wrp.evaluate.kinds may leave one out
        row, p = wrp[kind], PAPER[f"{kind}_t030"]
        lines.append(f"| {kind.upper()} | {fmt(row.threshold_m)} | {fmt(row.offset_rate_pct)} | "
                     f"{fmt(row.position_offset_m)} | {fmt(row.rotation_offset_deg)} | "
                     f"{fmt(row.time_s)} | {fmt(row.oracle_error_m)} | {p['offset_rate_pct']} / "
                     f"{p['position_offset_m']} / {p['rotation_offset_deg']} / {p['time_s']} / {p['error']} |")
    return lines


def robustness_section(ev: EvaluationResult) -> list[str]:
    """The three paths under the same winds (paper Tables 4/5 analogue), the paired differences and, with a
    placebo control, every WRP's verdict and the path to fly."""
    lines = ["", "## Robustness: the three paths under the same winds (paper Tables 4/5 analogue)", "",
             f"Common random numbers: {ev.common_random_numbers or ''}. Bootstrap {ev.confidence:.0%} "
             "intervals.", "", "| path | trials | mean error (m) | CI | std | 95th pct | failure rate |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {row.path} | {row.trials} | {fmt(row.mean_error_m, 4)} | "
              f"{_ci(row.mean_error_m_ci)} | {fmt(row.std_error_m)} | {fmt(row.p95_error_m, 4)} | "
              f"{100 * row.failure_rate:.1f} % |" for row in ev.paths]
    lines += ["", "| paired vs initial | mean error difference (m) | CI | p95 error difference (m) | CI | "
                  "P(meets spec) difference | CI | pairs | failure-rate difference |",
              "|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {pair.path} | {pair.mean_error_diff_m:+.4f} | {_ci(pair.mean_error_diff_ci)} | "
              f"{fmt(pair.p95_error_diff_m, 4)} | {_ci(pair.p95_error_diff_ci)} | {fmt(pair.p_meets_spec_diff, 3)} | "
              f"{_ci(pair.p_meets_spec_diff_ci)} | {pair.both_succeeded} | {100 * pair.failure_rate_diff:+.1f} points |"
              for pair in ev.paired]
    if ev.robustness is not None:
        lines += _verdict_lines(ev)
    return lines + [
        "", f"Paper anchor: mean error of the no-WRP path under random offsets "
        f"{PAPER['table4_no_wrp_mean_error']:.3f} vs ISWRP {PAPER['iswrp_t030']['error']} / SWRP "
        f"{PAPER['swrp_t030']['error']} (Table 4; ContextCapture errors, another scale than our oracle's).", "",
        "![error distributions](evaluate/boxplot.png)", ""]


def _verdict_lines(ev: EvaluationResult) -> list[str]:
    lines = ["", "| path | wind-free error (m) | P(meets spec) | CI | views not taken (mean) | expected sorties | "
                 "mission time (s) |", "|---|---|---|---|---|---|---|"]
    windfree = ev.windfree_error_m or {}
    lines += [f"| {row.path} | {fmt(windfree.get(row.path), 4)} | "
              f"{fmt(row.p_meets_spec, 3)} | {_ci(row.p_meets_spec_ci)} | "
              f"{fmt(row.mean_views_not_taken, 2)} | {fmt(row.expected_sorties, 3)} "
              f"{_ci(row.expected_sorties_ci)} | {fmt(row.mean_mission_time_s, 4)} |"
              for row in ev.paths]
    spec = ev.paths[0]
    lines += ["", f"Spec: error <= {fmt(spec.spec_error_m, 4)} m and completeness >= "
                  f"{fmt(spec.spec_completeness, 2)}.", "",
              "| WRP | robustness gain (mm) | CI | placebo 95th pct (mm) | placebos | verdict |",
              "|---|---|---|---|---|---|"]
    for kind, v in (ev.robustness or {}).items():
        ci = v.gain_ci_m
        lines.append(f"| {kind} | {1e3 * v.gain_m:+.2f} | "
                     + (f"[{1e3 * ci[0]:+.2f}, {1e3 * ci[1]:+.2f}]" if ci else "-")
                     + f" | {1e3 * v.placebo_gain_p95_m:+.2f} | {len(v.placebo_gains_m)} | "
                     + ("**recommended**" if v.recommended else f"not recommended: {v.reason}") + " |")
    return lines + ["", f"**Path to fly: {ev.recommended_path}.** Robustness gain = [E_wind - E_windfree](initial) "
                        "- [E_wind - E_windfree](WRP) per paired trial; a WRP is recommended only when its gain's CI "
                        "excludes 0 and exceeds the 95th percentile of its placebo paths' gains (as many viewpoints "
                        "moved by the same magnitudes, chosen at random, flown under the same winds)."]


def levers_section(levers: dict) -> list[str]:
    """The robust kind's levers (levers.json, :mod:`wrp_eval.wrp.robust`): each lever's screened gains against its
    placebo band, its verdict, and what the robust path applied."""
    lines = ["", "## Levers beyond moving a viewpoint (the robust kind, screened on stored flights)", "",
             f"Redundant and standoff at the {len(levers['views'])} viewpoints of highest registration risk "
             f"({levers['risk_source']}), a face's standoff at its surface viewpoints; each lever screened on "
             f"{len(levers['screen_flights'])} other flights against placebos (the same lever at as many random "
             "viewpoints).", "",
             "| lever | viewpoints | robustness gain (mm) | CI | placebo 95th pct (mm) | error gain (mm) | "
             "p95 gain (mm) | wind-free gain (mm) | placebo p95 gains (mm, min / max) | verdict |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, screen in levers["levers"].items():
        v, ci, p95s = screen["verdict"], screen["verdict"]["gain_ci_m"], screen["placebo_p95_gains_m"]
        lines.append(f"| {name} | {len(screen['views'])} | {1e3 * v['gain_m']:+.3f} | "
                     + (f"[{1e3 * ci[0]:+.3f}, {1e3 * ci[1]:+.3f}]" if ci else "-")
                     + f" | {1e3 * v['placebo_gain_p95_m']:+.3f} | {1e3 * screen['error_gain_m']:+.3f} | "
                     f"{1e3 * screen['p95_gain_m']:+.3f} | {1e3 * screen['windfree_gain_m']:+.3f} | "
                     f"{1e3 * min(p95s):+.3f} / {1e3 * max(p95s):+.3f} | "
                     + ("**recommended**" if v["recommended"] else f"not recommended: {v['reason']}") + " |")
    lines += _error_source_lines(levers.get("error_sources"))
    applied = ", ".join(levers["applied"]) or "none (the robust path is the initial path)"
    return lines + ["", f"Applied ({levers.get('apply', 'recommended')}): {applied}. Placing the levers took "
                        f"{levers['robust_s']:.1f} s, screening them {levers['screen_s']:.1f} s.", ""]


def error_sources_section(error_sources: dict) -> list[str]:
    """Why a WRP has (or has not) something to work on: what each capture error costs the campaign's flights."""
    sources = error_sources["sources"]
    flown, worst = sources["flown"], max((k for k in sources if k not in ("flown", "all")),
                                         key=lambda k: sources[k]["p95_gain_m"])
    return ["", "## Where the error's spread comes from", "",
            f"{len(error_sources['flights'])} of the campaign's flights re-scored by the oracle with one capture error "
            f"removed. With every capture error removed the error's std goes {1e3 * flown['std_m']:.2f} -> "
            f"{1e3 * sources['all']['std_m']:.2f} mm and its p95 {1e3 * flown['p95_m']:.2f} -> "
            f"{1e3 * sources['all']['p95_m']:.2f} mm: about the most a wind-resistant path could win. The largest "
            f"share is the {worst} error's (p95 {1e3 * sources[worst]['p95_gain_m']:+.2f} mm); a lever on another "
            "error (blur: capture mode, speed per leg) can gain no more than its row.",
            *_error_source_lines(sources), ""]


def _error_source_lines(sources: dict | None) -> list[str]:
    """What each capture error costs the screened flights (the bound on any lever acting on it)."""
    if not sources:
        return []
    flown = sources["flown"]
    lines = ["", f"What each capture error costs these flights (re-scored without it; flown: mean "
                 f"{1e3 * flown['mean_m']:.2f} mm, std {1e3 * flown['std_m']:.2f}, p95 {1e3 * flown['p95_m']:.2f}):",
             "", "| removed | mean (mm) | std (mm) | p95 (mm) | mean gain (mm) | p95 gain (mm) |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {name} | {1e3 * row['mean_m']:.3f} | {1e3 * row['std_m']:.3f} | {1e3 * row['p95_m']:.3f} | "
              f"{1e3 * row['mean_gain_m']:+.3f} | {1e3 * row['p95_gain_m']:+.3f} |"
              for name, row in sources.items() if name != "flown"]
    return lines


def risk_section(risk: ViewRisk, top_views: int = 5) -> list[str]:
    """The per-view risk map and the ``top_views`` riskiest viewpoints."""
    top = np.argsort(-np.nan_to_num(risk.risk_m))[:top_views]
    return ["## Per-view risk (what spreads the error)", "",
            "Each viewpoint's risk: what missing it costs the wind-free error (the oracle, the path without "
            "it) x sqrt(p (1 - p)), p the share of the campaign's flights that did not take it (returns "
            "home on the wind limit or the battery). A first-order map: missed views come in runs.", "",
            "![per-view risk](figures/view_risk.png)", "",
            "| view | risk (mm) | missed in | cost when missed (mm) |", "|---|---|---|---|",
            *[f"| {i} | {1e3 * risk.risk_m[i]:.2f} | {100 * risk.p_missed[i]:.0f} % | {1e3 * risk.loss_m[i]:+.2f} |"
              for i in top],
            "", "In the recording: entity `risk/viewpoints`.", ""]


def missions_section(missions: dict[str, list[str]], out: Path) -> list[str]:
    return ["## Missions", "", *[f"- {name}: " + ", ".join(f"`{Path(f).relative_to(out)}`" for f in files)
                                 for name, files in missions.items()]]


def timings_section(timings_s: dict[str, float], out: Path) -> list[str]:
    return ["", "## Timings (s)", "", "| step | wall (s) |", "|---|---|",
            *[f"| {k} | {v:.1f} |" for k, v in timings_s.items()], "", f"Recording: `rerun {out / 'run.rrd'}`", ""]
