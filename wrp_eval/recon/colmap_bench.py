"""Bench group "colmap": COLMAP's time against the render width, and what a perturbed validation of the
inspection path (experiments/inspection.yaml: the quickstart ship planned at gsd 4 mm) would take.

Measured: the whole planned inspection path (every view, exhaustive matching) once at ``BASE_WIDTH_PX``; the
first ``SWEEP_VIEWS`` views of the path (neighbours along the tour, so they match as the full set does) at each
width of ``WIDTHS_PX``. Projection of one full set at width W: each stage of the full run at the base width
scaled by that stage's ratio W / base in the sweep (render and SIFT grow with the pixels, matching with the
features, mapping with the points). The validation's time is that per-set figure times the sets it scores
(``validate-oracle --perturbed`` with its default flights, plus its COLMAP repeats). Needs pycolmap
(``pip install .[photogrammetry]``); without it the group has no records.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from wrp_eval.bench_record import BenchRecord
from wrp_eval.planning.config import PlanningSection
from wrp_eval.planning.planner import plan, planning_rng
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.perturbed import (
    FLIGHT_MODES,
    FLIGHT_SPEEDS_M_S,
    FLIGHTS_PER_SPEED,
    NAV_PRESETS,
    RECORDED_BLUR_MIN_SPEED_M_S,
    perturbed_capture_sets,
)
from wrp_eval.recon.validate import REPEAT_SEED_OFFSETS
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.resolve import resolve_ship_full

INSPECTION_GSD_MM = 4.0           # experiments/inspection.yaml
BASE_WIDTH_PX = 800
WIDTHS_PX = (800, 1200, 1600, 2400)
SWEEP_VIEWS = 24
BUDGET_MIN = 30.0                 # the oracle issue's validation budget
STAGES = ("render_s", "features_s", "matching_s", "mapping_s")


def _colmap_run(captures, mesh, width: int) -> dict:
    """Stage timings (s) and the result of one COLMAP run at ``width`` px in a temporary folder."""
    from wrp_eval.recon.colmap import ColmapOracle

    section = OracleSection()
    section = section.model_copy(update={"colmap": section.colmap.model_copy(update={"image_width_px": width})})
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="wrp-colmap-bench-") as tmp:
        result = ColmapOracle(section, work_dir=Path(tmp)).evaluate(captures, mesh, seed=0)
    return {**{k: float(result.extra.get(k, 0.0)) for k in STAGES}, "wall_s": time.perf_counter() - start,
            "registered": result.registered_views, "views": result.total_views, "error_m": result.error_m}


def validation_set_count(path, own_preset: str = "consumer") -> int:
    """Capture sets ``validate-oracle --perturbed`` scores with COLMAP on ``path`` with the default flights:
    the path's own sets (jitter copies included), the flown ones and the reference's repeats."""
    own = len(perturbed_capture_sets(path, 0))
    flights = len(FLIGHT_MODES) * len(FLIGHT_SPEEDS_M_S) * FLIGHTS_PER_SPEED
    navigation = sum(p != own_preset for p in NAV_PRESETS) * FLIGHTS_PER_SPEED
    recorded = sum(u >= RECORDED_BLUR_MIN_SPEED_M_S for u in FLIGHT_SPEEDS_M_S) * FLIGHTS_PER_SPEED
    return own + flights + navigation + recorded + len(REPEAT_SEED_OFFSETS)


def project(full: dict, sweep: dict[int, dict], base: int = BASE_WIDTH_PX) -> dict[int, float]:
    """Projected seconds of one full set per width: each stage of ``full`` (measured at ``base``) times that
    stage's ratio width / base in ``sweep`` ({width: stage timings})."""
    return {w: sum(full[k] * sweep[w][k] / max(sweep[base][k], 1e-9) for k in STAGES) for w in sweep}


def run_bench() -> list[BenchRecord]:
    try:
        import pycolmap  # noqa: F401  # lazily: the optional [photogrammetry] extra
    except ImportError:
        return []
    ship = resolve_ship_full(ShipSection(), ".")
    path = plan(ship.proxy, ship.complexity.complexity, PlanningSection(gsd_mm=INSPECTION_GSD_MM),
                planning_rng(0)).path
    captures = captures_from_path(path)
    full = _colmap_run(captures, ship.mesh, BASE_WIDTH_PX)
    sweep = {w: _colmap_run(captures.subset(np.arange(min(SWEEP_VIEWS, len(path)))), ship.mesh, w)
             for w in WIDTHS_PX}
    per_set = project(full, sweep)
    sets = validation_set_count(path)
    minutes = {w: sets * s / 60.0 for w, s in per_set.items()}
    fits = [w for w in WIDTHS_PX if minutes[w] <= BUDGET_MIN]
    stages = ", ".join(f"{k} {full[k]:.0f}" for k in STAGES)
    note_full = (f"inspection path (gsd {INSPECTION_GSD_MM:g} mm), all {len(path)} views at {BASE_WIDTH_PX} px, "
                 f"exhaustive matching: {stages} s; {full['registered']}/{full['views']} registered, error "
                 f"{1e3 * full['error_m']:.1f} mm")
    records = [BenchRecord("colmap.set_s.full", full["wall_s"], "s", None, None, note_full)]
    for w in WIDTHS_PX:
        note = (f"first {SWEEP_VIEWS} views at {w} px: " + ", ".join(f"{k} {sweep[w][k]:.1f}" for k in STAGES)
                + f" s; full set projected {per_set[w]:.0f} s; validation = {sets} sets x that")
        records += [BenchRecord(f"colmap.sweep_s.w{w}", sweep[w]["wall_s"], "s", None, None, note),
                    BenchRecord(f"colmap.validation_projected_min.w{w}", minutes[w], "min",
                                "oracle issue budget (at most)", BUDGET_MIN, note)]
    records.append(BenchRecord("colmap.widest_width_px_within_budget", float(max(fits)) if fits else 0.0, "px",
                               "oracle issue (at least)", 1600.0,
                               f"widest of {list(WIDTHS_PX)} whose projected validation ({sets} sets) fits "
                               f"{BUDGET_MIN:g} min on this machine; 0: none"))
    return records
