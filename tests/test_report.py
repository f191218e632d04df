"""report.md's sections, each from a small hand-made input (no flights): what the operator reads first, the
verdict table, the risk map's order, the run's header, the ship and path table, the campaign, the surrogate,
the missions and the timings."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import trimesh

from wrp_eval.envelope.result import CellResult, DirectionBoundary, Envelope, ForecastWind
from wrp_eval.planning.path import KIND_SURFACE, KIND_TRANSITION, FlightPath
from wrp_eval.report import (
    EARTH_FRAME_WARNING,
    campaign_section,
    envelope_section,
    header_section,
    missions_section,
    operator_section,
    risk_section,
    robustness_section,
    ship_section,
    surrogate_section,
    timings_section,
    wrp_section,
)
from wrp_eval.run_summary import CampaignRun, SurrogateFit
from wrp_eval.ship.complexity import mesh_surface_complexity
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import build_proxy
from wrp_eval.ship.resolve import ResolvedShip
from wrp_eval.wrp.evaluation import EvaluationResult
from wrp_eval.wrp.optimize import Table3Row
from wrp_eval.wrp.risk import ViewRisk


def _cell(relative, speed, p, decision, forecast=False) -> CellResult:
    return CellResult(relative_deg=relative, compass_from_deg=(30 + relative) % 360, speed_m_s=speed,
                      direction={0.0: "bow", 180.0: "stern"}[relative], flights=24, decision=decision,
                      meets=decision == "meets", p_meets_spec=p, p_meets_spec_ci=(p - 0.1, min(1.0, p + 0.1)),
                      repeated_ci=(p - 0.15, min(1.0, p + 0.15)), p_completed=1.0, completeness_mean=0.97,
                      error_mean_m=0.0251, error_p95_m=0.0262, expected_sorties=1.0, mission_time_s=362.8,
                      views_lost=0.0, endings={"completed": 24}, limit="none", folder="cells/x", forecast=forecast)


def _envelope(go: bool) -> Envelope:
    cells = (_cell(0.0, 6.0, 1.0 if go else 0.5, "meets" if go else "fails", forecast=True),
             _cell(0.0, 8.0, 1.0, "meets"), _cell(180.0, 4.0, 0.2, "fails"))
    bounds = (DirectionBoundary(0.0, "bow", 10.0, 8.0, (10.0, 10.5), False, "returned: no headway (7)"),
              DirectionBoundary(180.0, "stern", None, None, (None, 4.0), False, "lost: no headway (8)"))
    rule = {"threshold": 0.8, "confidence": 0.95, "spec_error_m": 0.0277, "spec_completeness": 0.95,
            "look_flights": 8, "max_flights": 32, "looks": 4, "test": "repeated intervals"}
    return Envelope(cells, bounds, ForecastWind(6.0, 30.0, 0.0, "wind: section"), go, rule,
                    {"speeds_m_s": [0.0, 4.0, 8.0, 12.0]}, 72, 72, 1.0, {})


def test_the_first_page_gives_the_verdict_the_boundaries_and_the_earth_frame_warning():
    text = "\n".join(envelope_section(_envelope(go=True), "initial", "envelope/envelope.png", "figures/risk.png"))
    assert text.startswith("## Go / no-go: **GO** at the forecast (path `initial`)")
    assert "P(meets spec) **1.00** [0.85, 1] over 24 simulated flights" in text     # the repeated interval
    assert "nominal fixed-n [0.9, 1]" in text
    assert "| bow | 10 m/s (fails at 10.5) | 8 m/s | returned: no headway (7) |" in text
    assert "| stern | below 4 m/s (not even the lowest speed meets the spec) | - | lost: no headway (8) |" in text
    assert "| bow 6 m/s | 1 | 1 | 362.8 | 0 | 25.1 | 26.2 |" in text
    assert "![envelope](envelope/envelope.png)" in text and "figures/risk.png" in text
    assert text.rstrip().endswith(EARTH_FRAME_WARNING)
    no_go = "\n".join(envelope_section(_envelope(go=False), "iswrp", "e.png", None))
    assert no_go.startswith("## Go / no-go: **NO-GO**") and "per-view risk" not in no_go
    unknown = dataclasses.replace(_envelope(go=True), go=None, forecast=None)
    assert "\n".join(envelope_section(unknown, "initial", "e.png", None)).startswith(
        "## Go / no-go: **no forecast**")


def _ev(recommended: bool) -> EvaluationResult:
    row = {"trials": 16, "succeeded": 16, "failure_rate": 0.0, "failure_rate_ci": [0.0, 0.0], "mean_error_m": 0.0253,
           "mean_error_m_ci": [0.025, 0.0256], "std_error_m": 0.0005, "std_error_m_ci": None, "p95_error_m": 0.0261,
           "p95_error_m_ci": None, "spec_error_m": 0.0277, "spec_completeness": 0.95, "p_meets_spec": 1.0,
           "p_meets_spec_ci": [0.8, 1.0]}
    return EvaluationResult.from_json_dict({
        "confidence": 0.95, "bootstrap_resamples": 200, "paths": [{**row, "path": "initial"}, {**row, "path": "iswrp"}],
        "paired": [{"path": "iswrp", "versus": "initial", "paired_trials": 16, "both_succeeded": 16,
                    "mean_error_diff_m": -0.0004, "mean_error_diff_ci": [-0.0006, -0.0002], "wins": 12, "losses": 4,
                    "failure_rate_diff": 0.0, "failure_rate_diff_ci": None, "p95_error_diff_m": -0.0002,
                    "p95_error_diff_ci": [-0.0005, 0.0001], "p_meets_spec_diff": 0.0625,
                    "p_meets_spec_diff_ci": [0.0, 0.125]}],
        "windfree_error_m": {"initial": 0.0252, "iswrp": 0.0250},
        "robustness": {"iswrp": {"gain_m": 0.0004, "gain_ci_m": [0.0002, 0.0006], "paired_trials": 16,
                                 "placebos_flown": 2, "placebo_gains_m": [0.0, 0.0001], "placebo_gain_p95_m": 0.0001,
                                 "recommended": recommended, "reason": "its gain's CI includes 0"}},
        "recommended_path": "iswrp" if recommended else "initial"})


def test_the_robustness_table_states_each_verdict_and_the_path_to_fly():
    text = "\n".join(robustness_section(_ev(True)))
    assert "| iswrp | +0.40 | [+0.20, +0.60] | +0.10 | 2 | **recommended** |" in text
    assert "**Path to fly: iswrp.**" in text
    assert ("| iswrp | -0.0004 | [-0.0006, -0.0002] | -0.0002 | [-0.0005, 0.0001] | 0.0625 | [0, 0.125] | 16 | "
            "+0.0 points |") in text
    kept = "\n".join(robustness_section(_ev(False)))
    assert "not recommended: its gain's CI includes 0" in kept and "**Path to fly: initial.**" in kept


def test_the_risk_table_lists_the_riskiest_views_first():
    risk = ViewRisk(loss_m=np.array([0.001, 0.004, 0.0, 0.002]), p_missed=np.array([0.5, 0.5, 0.0, 0.25]),
                    risk_m=np.array([0.0005, 0.002, 0.0, 0.0008]), base_error_m=0.025)
    rows = [line for line in risk_section(risk, top_views=3) if line.startswith("| ") and line[2].isdigit()]
    assert [int(r.split("|")[1]) for r in rows] == [1, 3, 0]
    assert rows[0] == "| 1 | 2.00 | 50 % | +4.00 |"


def test_the_table3_rows_carry_ours_and_the_papers():
    row = Table3Row(kind="iswrp", threshold_m=0.3, offset_rate_pct=10.0, position_offset_m=4.0,
                    rotation_offset_deg=12.0, time_s=0.5, viewpoints=46, moved=5, surrogate_error_m=0.025,
                    e_original_m=0.025, forward_calls=10, queries=1000, iterations_scored=100, oracle_error_m=0.0251)
    lines = wrp_section({"iswrp": row, "swrp": row})
    assert lines[-2].startswith("| ISWRP | 0.3 | 10 | 4 | 12 | 0.5 | 0.0251 | 28.57 /")
    assert lines[-1].startswith("| SWRP |")


def test_the_operator_section_gives_the_forecast_verdict_and_reads_the_older_wind_key():
    doc = _ev(True).to_json_dict()
    forecast = {**doc["paths"][1], "p_completed": 0.9375, "p_completed_ci": [0.7, 1.0], "p_one_sortie": 0.875,
                "p_one_sortie_ci": [0.6, 0.98], "expected_sorties": 1.0667, "expected_sorties_ci": [1.0, 1.2],
                "mean_mission_time_s": 363.21, "mean_mission_time_s_ci": [360.0, 366.0], "go": False,
                "go_probability": 0.8, "wind_speed_10m_mps": 6.0, "wind_direction_deg": 270.0,
                "summary": "NO-GO", "stress_notes": ["a stress note"]}
    ev = EvaluationResult.from_json_dict({**doc, "forecast": forecast})
    assert ev.forecast is not None and ev.forecast.wind_speed_10m_m_s == 6.0
    assert "wind_speed_10m_m_s" in ev.to_json_dict()["forecast"]
    text = "\n".join(operator_section(ev))
    assert text.startswith("## Go / no-go: **NO-GO** (path `iswrp`)")
    assert "In the forecast wind (6 m/s at 10 m from 270 deg" in text and "16 simulated flights" in text
    assert "| 1 | [0.8, 1] | n/a | 0.938 | 0.875 | 1.07 | [1, 1.2] | 363.2 |" in text
    assert "a stress note" in text and "lower 95% bound of P(meets spec) >= 0.8" in text
    assert operator_section(_ev(True)) == []          # no forecast, no first page


def _ship() -> ResolvedShip:
    particulars = ShipParticulars(length_bp_m=140.0, breadth_m=20.0, depth_m=12.0, superstructure_height_m=13.0,
                                  draft_m=6.0)
    proxy = build_proxy(particulars, no_fly_margin_m=5.0)
    mesh = trimesh.creation.box(extents=(140.0, 20.0, 19.0))
    mesh.apply_translation((0.0, 0.0, 9.5))
    return ResolvedShip(particulars, {}, proxy, mesh, "box", mesh_surface_complexity(mesh, proxy))


def test_the_header_names_the_run_the_seed_and_the_proxy():
    ship = _ship()
    lines = header_section("demo", "experiments/demo.yaml", 7, ship)
    assert lines[0] == "# wrp-eval run `demo`"
    assert lines[2].startswith(f"Config `experiments/demo.yaml`, seed 7; ship: stylized (140 x 20 x "
                               f"{ship.proxy.height_m:.1f} m proxy above the waterline, no-fly margin 5 m)")


def test_the_ship_section_puts_the_paths_figures_beside_table_7():
    ship = _ship()
    path = FlightPath(positions=np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 12.0]]),
                      yaw=np.zeros(3), pitch=np.zeros(3), face_id=np.array([0, -1, 1]),
                      kind=np.array([KIND_SURFACE, KIND_TRANSITION, KIND_SURFACE]), sortie=np.zeros(3, dtype=int))
    metrics = {"n_transition_views": 1, "timings": {"min_s": 1.5, "max_s": 0.25, "tsp_s": 0.5, "total_s": 2.5}}
    lines = ship_section(ship.complexity, path, metrics)
    assert "| per face | " + " | ".join(ship.proxy.face_names) + " |" in lines
    assert "| viewpoints | 3 (1 transition) | 49 |" in lines
    assert "| length (m) | 17.0 | 684.566 |" in lines              # 5 m + 12 m
    assert "| flight time (s) | 9.4 | 159.764 |" in lines          # 17 m at 5 m/s + 3 photos x 2 s dwell
    assert "| tour (s) | 0.5 | 25.537 (GA) |" in lines and "| planning total (s) | 2.5 | |" in lines


def test_the_campaign_section_says_what_was_flown_and_the_flights_share_of_the_offsets():
    campaign = CampaignRun("logs/demo/campaign", 256, 3, 120.0, None)
    with_share = SurrogateFit(0.9, 0.0004, 0.0003, 40, {"position": 0.953, "yaw": 0.914})
    text = "\n".join(campaign_section(campaign, "physical", with_share))
    assert "256 trials (3 failed) in `logs/demo/campaign`; the path flown as planned (`physical` design" in text
    assert "position 0.953, yaw 0.914" in text
    box = "\n".join(campaign_section(campaign, "box", dataclasses.replace(with_share, physical_variance_share=None)))
    assert "commanded offsets from the campaign's `box` perturbation design" in box and "Share of" not in box


def test_the_surrogate_section_puts_the_held_out_figures_beside_the_papers():
    lines = surrogate_section(SurrogateFit(0.91234, 0.00041, 0.0003, 400, None))
    assert "| R^2 | 0.912 | 0.98 |" in lines and "| RMSE (m) | 0.00041 | 0.16 (on errors of ~3 m) |" in lines
    assert "| trials | 400 | 300 experiments in all |" in lines


def test_the_missions_and_timings_sections_list_files_relative_to_the_run():
    out = Path("/runs/demo")
    missions = missions_section({"initial": [str(out / "missions/initial.plan"), str(out / "missions/initial.kmz")]},
                                out)
    assert missions[-1] == "- initial: `missions/initial.plan`, `missions/initial.kmz`"
    timings = timings_section({"plan": 0.42, "campaign": 61.26}, out)
    assert "| plan | 0.4 |" in timings and "| campaign | 61.3 |" in timings
    assert "Recording: `rerun /runs/demo/run.rrd`" in timings


def test_the_levers_section_gives_each_levers_band_and_what_each_capture_error_costs():
    from wrp_eval.report import levers_section
    verdict = {"gain_m": 0.00001, "gain_ci_m": [-0.00001, 0.00003], "paired_trials": 24, "placebos_flown": 20,
               "placebo_gains_m": [0.0] * 20, "placebo_gain_p95_m": 0.0004, "recommended": False,
               "reason": "the gain does not exceed the placebo 95th percentile"}
    screen = {"lever": "redundant", "views": [3, 9], "flights": 24, "verdict": verdict, "error_gain_m": 0.00005,
              "p95_gain_m": 0.00003, "windfree_gain_m": 0.00004, "placebo_error_gains_m": [0.0] * 20,
              "placebo_p95_gains_m": [-0.00001, 0.005]}
    row = {"mean_m": 0.0157, "std_m": 0.0002, "p95_m": 0.016, "mean_gain_m": 0.00026, "p95_gain_m": 0.0028}
    text = "\n".join(levers_section({
        "views": [3, 9], "risk_source": "the campaign's view_registered column, 64 flights",
        "screen_flights": list(range(24)), "levers": {"redundant": screen}, "applied": [], "apply": "recommended",
        "robust_s": 0.8, "screen_s": 348.0,
        "error_sources": {"flown": {"mean_m": 0.016, "std_m": 0.0015, "p95_m": 0.0189}, "position": row}}))
    assert ("| redundant | 2 | +0.010 | [-0.010, +0.030] | +0.400 | +0.050 | +0.030 | +0.040 | -0.010 / +5.000 | "
            "not recommended: the gain does not exceed the placebo 95th percentile |") in text
    assert "| position | 15.700 | 0.200 | 16.000 | +0.260 | +2.800 |" in text
    assert "none (the robust path is the initial path)" in text and "screening them 348.0 s" in text
