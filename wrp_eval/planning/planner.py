"""The planning pipeline (paper Sec. 3) from a proxy and its face complexities to a :class:`FlightPath`.

ours:     complexity-scaled radii and thresholds, Min-Max, tour, transition viewpoints (Alg. 2).
zhou2020: one radius, one threshold (the most complex face's), Min-Max, tour, no transition viewpoints.
oblique:  five lawnmower sub-paths (see :mod:`wrp_eval.planning.oblique`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.planning.config import PlanningSection
from wrp_eval.planning.minmax import MinResult, maximise, minimise, set_metrics
from wrp_eval.planning.oblique import oblique_views
from wrp_eval.planning.path import KIND_SURFACE, KIND_TRANSITION, FlightPath
from wrp_eval.planning.reconstructability import SlotTable
from wrp_eval.planning.sampling import Samples, base_radius_m, poisson_samples
from wrp_eval.planning.tour import (
    detour_waypoints,
    flight_costs,
    open_at_longest_edge,
    solve_genetic,
    solve_multistart,
    solve_ortools,
    tour_length,
)
from wrp_eval.planning.transitions import (
    TransitionResult,
    TransitionScene,
    proxy_axis_targets,
    transition_views,
)
from wrp_eval.planning.views import ViewSet, candidate_views
from wrp_eval.planning.visibility import ProxyRaycaster, visibility
from wrp_eval.ship.nofly import segments_intrude
from wrp_eval.ship.proxy import Proxy

# Stream id of the planning stage inside the run seed (other stages spawn their own).
PLANNING_SEED_STREAM = 3

_Views = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def planning_rng(seed: int) -> np.random.Generator:
    """The planning stage's generator for run seed ``seed``."""
    return np.random.default_rng(np.random.SeedSequence([seed, PLANNING_SEED_STREAM]))


@dataclass(frozen=True)
class PlanResult:
    """The path, the metrics (plan_metrics.json) and the intermediate sets (for logging and tests).

    samples / candidates / chosen are None for the oblique baseline; chosen holds the surface views in
    flight order; visible (n_candidates, n_samples) bool; chosen_obs rows of the chosen views;
    thresholds (n_s,) the effective per-sample thresholds; h (n_s,) the final reconstructability."""

    path: FlightPath
    metrics: dict
    samples: Samples | None = None
    candidates: ViewSet | None = None
    chosen: ViewSet | None = None
    visible: np.ndarray | None = None
    thresholds: np.ndarray | None = None
    h: np.ndarray | None = None


def relative_complexity(complexity: np.ndarray, max_factor: float) -> np.ndarray:
    """c_i / c_max clipped to [1/max_factor, 1] (5,): the common scale of radii and thresholds."""
    c = np.asarray(complexity, dtype=float)
    if c.shape != (5,) or not np.all(np.isfinite(c)) or np.any(c < 0) or c.max() <= 0:
        raise ValueError(f"complexity must be 5 finite non-negative values, not all zero; got {c}")
    return np.clip(c / c.max(), 1.0 / max_factor, 1.0)


def face_thresholds(complexity: np.ndarray, section: PlanningSection) -> np.ndarray:
    """Per-face reconstructability thresholds (5,) (paper Sec. 3.2; see README for the scaling choice)."""
    if section.method == "zhou2020":
        return np.full(5, section.threshold)
    rel = relative_complexity(complexity, section.max_radius_factor)
    return section.threshold * (rel if section.threshold_scaling == "proportional" else 1.0 / rel)


def assign_sorties(positions: np.ndarray, speed_m_s: float, dwell_s: float, endurance_s: float) -> np.ndarray:
    """Sortie index (n,) of each view: a new sortie starts when the cumulative flight time (cruise plus
    dwell) passes a multiple of the endurance (the paper's pause-and-resume, Sec. 5.1)."""
    legs = np.concatenate([[0.0], np.linalg.norm(np.diff(positions, axis=0), axis=1)])
    elapsed = np.cumsum(legs / speed_m_s + dwell_s)
    return np.floor((elapsed - 1e-9) / endurance_s).astype(int)


def _replacement_pool(samples: Samples, candidates: ViewSet, radii: np.ndarray):
    """replacements(view) -> candidate views generated from samples within 1.5 radii on the same face."""
    tree = cKDTree(samples.points)
    order = np.argsort(candidates.sample, kind="stable")
    ptr = np.concatenate([[0], np.cumsum(np.bincount(candidates.sample, minlength=len(samples)))])

    def replacements(view: int) -> np.ndarray:
        s = candidates.sample[view]
        near = np.array(tree.query_ball_point(samples.points[s], 1.5 * radii[samples.face[s]]), dtype=int)
        near = near[samples.face[near] == samples.face[s]]
        return np.concatenate([order[ptr[k]:ptr[k + 1]] for k in near]) if near.size else np.zeros(0, int)

    return replacements


def finish_path(positions, yaw, pitch, face, kind, proxy: Proxy, section: PlanningSection, camera: Camera,
                 method: str, metadata: dict) -> tuple[FlightPath, int]:
    """Insert over-the-top detour waypoints where a leg would cross the no-fly box; split into sorties."""
    box = proxy.no_fly_bounds()
    blocked = segments_intrude(positions[:-1], positions[1:], box) if len(positions) > 1 else np.zeros(0, bool)
    legs = np.flatnonzero(blocked)
    if legs.size:
        # two corners of the over-the-top detour after the start of every blocked leg
        corners = np.concatenate([detour_waypoints(positions[i], positions[i + 1], box) for i in legs])
        c_yaw, c_pitch = yaw_pitch_towards(corners, proxy_axis_targets(proxy, corners))
        at = np.repeat(legs + 1, 2)
        positions = np.insert(positions, at, corners, axis=0)
        yaw, pitch = np.insert(yaw, at, c_yaw), np.insert(pitch, at, c_pitch)
        face, kind = np.insert(face, at, -1), np.insert(kind, at, KIND_TRANSITION)
    n_detour = 2 * int(legs.size)
    sortie = assign_sorties(positions, section.speed_m_s, section.dwell_s, section.endurance_s)
    path = FlightPath(positions, yaw, pitch, face.astype(int), kind.astype(int), sortie, camera, section.speed_m_s,
                section.dwell_s, method, metadata)
    return path, n_detour


def _path_metrics(path: FlightPath) -> dict:
    return {"length_m": path.length_m, "flight_time_s": path.flight_time_s,
            "sorties": int(path.sortie.max()) + 1 if len(path) else 0,
            "n_path_views": len(path), "n_transition_views": int(np.sum(path.kind == KIND_TRANSITION))}


def plan_oblique(proxy: Proxy, section: PlanningSection) -> PlanResult:
    start = time.perf_counter()
    camera = section.camera()
    distance = section.planned_distance_m()
    pos, yaw, pitch, face = oblique_views(proxy, camera, distance, section.oblique_pitch_deg,
                                          section.front_overlap, section.side_overlap, section.min_altitude_m)
    meta = {"planned_distance_m": distance, "altitude_m": proxy.height_m + distance,
            "oblique_pitch_deg": section.oblique_pitch_deg, "front_overlap": section.front_overlap,
            "side_overlap": section.side_overlap}
    path, n_detour = finish_path(pos, yaw, pitch, face, np.full(len(pos), KIND_SURFACE), proxy, section,
                                  camera, "oblique", meta)
    metrics = {"method": "oblique", **meta, "n_views": len(pos), "n_detour_views": n_detour,
               "per_face": {name: {"views": int(np.sum(face == i))} for i, name in enumerate(proxy.face_names)},
               **_path_metrics(path), "timings": {"total_s": time.perf_counter() - start}}
    return PlanResult(path, metrics)


def plan(proxy: Proxy, complexity: np.ndarray, section: PlanningSection, rng: np.random.Generator) -> PlanResult:
    """Plan with ``section.method``. complexity (5,): per-face surface complexity (paper Def. 3.3).

    Every random draw (Poisson disk, genetic algorithm) comes from ``rng``."""
    if section.method == "oblique":
        return plan_oblique(proxy, section)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    geometry = _ViewGeometry.of(section)
    camera, distance, d_max, max_inc = geometry
    r0 = base_radius_m(camera, distance, section.sample_overlap)
    ours = section.method == "ours"
    radii = r0 / relative_complexity(complexity, section.max_radius_factor) if ours else np.full(5, r0)
    thr_face = face_thresholds(complexity, section)

    samples, candidates, raycaster, visible = _candidates_seen(proxy, section, geometry, radii, rng, timings, t0)
    thr_asked = thr_face[samples.face]
    active, h, thr, set_doc = _min_max(samples, candidates, visible, thr_asked, radii, d_max, section, timings)
    t4 = time.perf_counter()

    chosen_idx = np.flatnonzero(active)
    order, closed_length = _tour(candidates.positions[chosen_idx], proxy, section, rng)
    chosen = candidates.subset(chosen_idx[order])
    chosen_obs = visible[chosen_idx[order]]
    t5 = time.perf_counter()
    timings["tsp_s"] = t5 - t4

    views = (chosen.positions, chosen.yaw, chosen.pitch, chosen.face.copy(), np.full(len(chosen), KIND_SURFACE))
    violations = checked = 0
    if ours and section.transitions:
        scene = TransitionScene(proxy, samples.points, samples.normals, samples.face, radii, camera, raycaster,
                                d_max, max_inc, section.min_altitude_m, section.overlap_min, section.overlap_max,
                                clearance_m=0.5 * distance)
        views, violations, checked = _with_transitions(views, chosen, chosen_obs, samples, scene)
    t6 = time.perf_counter()
    timings["transitions_s"] = t6 - t5

    meta = {"planned_distance_m": distance, "d_max_m": d_max, "tour_solver": section.tour_solver}
    path, n_detour = finish_path(*views, proxy, section, camera, section.method, meta)
    timings["total_s"] = time.perf_counter() - t0

    metrics = {"method": section.method, "n_samples": len(samples), "n_candidates": len(candidates),
               "n_views": int(len(chosen_idx)), "n_views_after_min": set_doc.pop("n_views_after_min"),
               "n_detour_views": n_detour,
               "per_face": _per_face(proxy, samples, candidates, chosen_idx, radii, thr_face, complexity),
               **set_doc, "min_h": float(h.min()) if h.size else 0.0,
               "samples_below_asked_threshold": int(np.sum(h < thr_asked - 1e-9)),
               "tour_cost_m": closed_length, "osmc_violations": violations, "osmc_pairs": checked,
               **_path_metrics(path), "planned_distance_m": distance, "d_max_m": d_max,
               "timings": timings}
    return PlanResult(path, metrics, samples, candidates, chosen, visible, thr, h)


class _ViewGeometry(NamedTuple):
    """What the views are planned and judged with: the camera, the planned distance (m), the view range d_max (m)
    and the incidence limit (rad) of the visibility test."""

    camera: Camera
    distance_m: float
    d_max_m: float
    max_incidence_rad: float

    @classmethod
    def of(cls, section: PlanningSection) -> "_ViewGeometry":
        distance = section.planned_distance_m()
        return cls(section.camera(), distance, section.max_view_distance_factor * distance,
                   float(np.radians(section.max_incidence_deg)))


def _candidates_seen(proxy: Proxy, section: PlanningSection, geometry: _ViewGeometry, radii: np.ndarray,
                     rng: np.random.Generator, timings: dict, t0: float):
    """The Poisson-disk samples, the candidate views, the proxy raycaster and the visibility (candidates x
    samples) bool matrix; sampling_s and visibility_s (from ``t0``) into ``timings``."""
    samples = poisson_samples(proxy, radii, rng)
    t1 = time.perf_counter()
    timings["sampling_s"] = t1 - t0
    candidates = candidate_views(samples, proxy, geometry.distance_m, tilt_rad=np.radians(section.tilt_deg),
                                 n_tilts=section.n_tilts, min_altitude_m=section.min_altitude_m)
    raycaster = ProxyRaycaster(proxy)
    visible = visibility(samples.points, samples.normals, candidates.positions, candidates.yaw,
                         candidates.pitch, geometry.camera, raycaster, geometry.d_max_m, geometry.max_incidence_rad)
    timings["visibility_s"] = time.perf_counter() - t1
    return samples, candidates, raycaster, visible


def _min_max(samples, candidates, visible: np.ndarray, thr_asked: np.ndarray, radii: np.ndarray, d_max: float,
             section: PlanningSection, timings: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Minimisation then maximisation (min_s, max_s, metrics_s into ``timings``): (active candidates, h per
    sample, the effective thresholds, {n_views_after_min, H, R, H_min_only, R_min_only, max_swaps})."""
    t2 = time.perf_counter()
    start_idx, min_res = _minimised(samples, candidates, visible, thr_asked, d_max, section.n_tilts)
    active = np.zeros(len(candidates), dtype=bool)
    active[start_idx[min_res.active]] = True
    t3 = time.perf_counter()
    timings["min_s"] = t3 - t2
    table = SlotTable.build(visible, samples.points, samples.normals, candidates.positions, d_max)
    thr = min_res.threshold
    h_min_only, r_min_only = set_metrics(table, active, thr)
    n_views_min = int(active.sum())
    t3b = time.perf_counter()
    active, h, swaps = maximise(table, active, thr, _replacement_pool(samples, candidates, radii),
                                section.max_rounds)
    t4 = time.perf_counter()
    timings["max_s"] = t4 - t3b
    H, R = set_metrics(table, active, thr)
    timings["metrics_s"] = (t3b - t3) + (time.perf_counter() - t4)
    return active, h, thr, {"n_views_after_min": n_views_min, "H": H, "R": R, "H_min_only": h_min_only,
                            "R_min_only": r_min_only, "max_swaps": swaps}


def _minimised(samples, candidates, visible: np.ndarray, thr_asked: np.ndarray, d_max: float,
               n_tilts: int) -> tuple[np.ndarray, MinResult]:
    """Minimisation (the candidates it started from, its result). It starts from the normal candidates;
    samples they cannot lift to the threshold (sparse faces, hull edges) also bring their own tilted candidates
    into the starting set."""
    start_idx = np.flatnonzero(candidates.tilt == 0)
    table_min = SlotTable.build(visible[start_idx], samples.points, samples.normals,
                                candidates.positions[start_idx], d_max, cache=True)
    short = table_min.h(np.ones(len(start_idx), dtype=bool)) < thr_asked - 1e-9
    if np.any(short) and n_tilts:
        start_idx = np.flatnonzero((candidates.tilt == 0) | short[candidates.sample])
        table_min = SlotTable.build(visible[start_idx], samples.points, samples.normals,
                                    candidates.positions[start_idx], d_max, cache=True)
    return start_idx, minimise(table_min, np.ones(len(start_idx), dtype=bool), thr_asked)


def _tour(positions: np.ndarray, proxy: Proxy, section: PlanningSection,
          rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """(the open tour's order of the views at ``positions`` (n, 3), the closed tour's cost m) by the section's
    solver."""
    cost, _ = flight_costs(positions, proxy.no_fly_bounds())
    if section.tour_solver == "multistart":
        order = solve_multistart(cost, rng)
    elif section.tour_solver == "ortools":
        order = solve_ortools(cost, section.tour_time_limit_s)
    else:
        order = solve_genetic(cost, rng, section.ga_population, section.ga_generations)
    return open_at_longest_edge(order, cost), tour_length(order, cost)


def _with_transitions(views: _Views, chosen, chosen_obs: np.ndarray, samples,
                      scene: TransitionScene) -> tuple[_Views, int, int]:
    """(positions, yaw, pitch, face, kind) of the surface ``views`` in tour order with each segment's transition
    views after its first view (face -1, KIND_TRANSITION); the OSMC violations left and the pairs checked."""
    tr = transition_views(chosen.positions, chosen.face, chosen_obs, samples.points[chosen.sample], scene)
    return _interleaved(views, tr), tr.violations, tr.checked_pairs


def _interleaved(views: _Views, tr: TransitionResult) -> _Views:
    """The surface ``views`` with each segment's transition views of ``tr`` after its first view."""
    pos, yaw, pitch, face, kind = views
    out = []
    for i in range(len(pos)):
        out.append((pos[i:i + 1], yaw[i:i + 1], pitch[i:i + 1], face[i:i + 1], kind[i:i + 1]))
        if i < len(tr.positions) and len(tr.positions[i]):
            k = len(tr.positions[i])
            out.append((tr.positions[i], tr.yaw[i], tr.pitch[i], np.full(k, -1), np.full(k, KIND_TRANSITION)))
    pos, yaw, pitch, face, kind = (np.concatenate([o[j] for o in out]) for j in range(5))
    return pos, yaw, pitch, face, kind


def _per_face(proxy: Proxy, samples, candidates, chosen_idx: np.ndarray, radii: np.ndarray, thr_face: np.ndarray,
              complexity: np.ndarray) -> dict:
    views_per_face = np.bincount(candidates.face[chosen_idx], minlength=len(proxy.face_names))
    return {name: {"samples": int(np.sum(samples.face == i)),
                   "candidates": int(np.sum(candidates.face == i)),
                   "views": int(views_per_face[i]), "radius_m": float(radii[i]),
                   "threshold": float(thr_face[i]), "complexity": float(np.asarray(complexity)[i])}
            for i, name in enumerate(proxy.face_names)}
