"""``wrp-eval validate-oracle``: the synthetic oracle against COLMAP on good, degraded and broken paths.

Capture sets are built around the configured ship's above-water bounding box (known by construction):
good = rings of oblique views (the shape of a well-planned path); degraded = the same with position and
yaw offsets (wind), thinned, or flown farther; broken = per-face views with no transition views between
faces (the failure the paper's transition viewpoints exist to prevent, Sec. 3.3) and a sparse ring.
Both oracles measure each; we report the Spearman rank correlation of error_m and the agreement of the
failed verdicts (issue 6 target: rho >= 0.8, same verdicts).

``--perturbed`` (:func:`validate_perturbed`): both oracles on small, realistic perturbations of ONE planned path
(:mod:`wrp_eval.recon.perturbed`); we report each oracle's change of error_m and completeness from the
unperturbed set, the Spearman rho of the two oracles' changes (issue 17 target: >= 0.6) and their sign agreement.
"""

from __future__ import annotations

import csv
import json
import logging
import traceback
from pathlib import Path
from typing import Any, TypeGuard, cast

import numpy as np
import trimesh
from matplotlib.figure import Figure
from scipy.stats import spearmanr

from wrp_eval.atomic import atomic_path, write_text_atomic
from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.calibration import colmap_equivalent
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recon.colmap import ColmapOracle
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.oracle import ReconResult
from wrp_eval.recon.scenarios import orbit_capture_set
from wrp_eval.recon.synthetic import SyntheticOracle
from wrp_eval.sim.captures import CaptureSet

log = logging.getLogger(__name__)


def _subset(cs: CaptureSet, keep: np.ndarray) -> CaptureSet:
    return cs.subset(keep)  # roll and position priors carried along


def _perturbed(cs: CaptureSet, rng: np.random.Generator, sigma_m: float, sigma_yaw_deg: float) -> CaptureSet:
    """Wind-like offsets: Gaussian position (m) and yaw (deg) errors, pitch and roll kept (gimbal-stabilised).

    Recorded positions (if any) move with the true ones: the navigation error (prior - true) is kept."""
    pos = cs.positions + rng.normal(0.0, sigma_m, cs.positions.shape)
    pos[:, 2] = np.maximum(pos[:, 2], 1.0)
    yaw = cs.yaw + np.radians(rng.normal(0.0, sigma_yaw_deg, len(cs)))
    prior = None if cs.prior_positions is None else cs.prior_positions + (pos - cs.positions)
    return CaptureSet(pos, yaw, cs.pitch, cs.planned_index, cs.camera, cs.roll, prior)


def _per_face_views(lo: np.ndarray, hi: np.ndarray, standoff: float, camera: Camera) -> CaptureSet:
    """Views square-on to each proxy face with no transition views between faces."""
    cx, cy = (lo[:2] + hi[:2]) / 2
    zc = hi[2] / 2
    xs = np.linspace(lo[0] + 8, hi[0] - 8, 9)
    port = np.column_stack([xs, np.full(9, hi[1] + standoff), np.full(9, zc)])
    starboard = np.column_stack([xs, np.full(9, lo[1] - standoff), np.full(9, zc)])
    bow = np.array([[hi[0] + standoff, cy + d, zc] for d in (-4.0, 0.0, 4.0)])
    stern = np.array([[lo[0] - standoff, cy + d, zc] for d in (-4.0, 0.0, 4.0)])
    top = np.column_stack([xs, np.full(9, cy), np.full(9, hi[2] + standoff)])
    positions = np.vstack([port, starboard, bow, stern, top])
    targets = np.vstack([port * [1, 0, 1] + [0, hi[1], 0], starboard * [1, 0, 1] + [0, lo[1], 0],
                         bow * [0, 1, 1] + [hi[0], 0, 0], stern * [0, 1, 1] + [lo[0], 0, 0],
                         top * [1, 1, 0] + [0, 0, hi[2]]])
    yaw, pitch = yaw_pitch_towards(positions, targets)
    top_rows = slice(len(positions) - 9, None)
    yaw[top_rows] = 0.0
    pitch[top_rows] = np.radians(-89.0)  # nadir (the gimbal's limit), heading along the ship
    return CaptureSet(positions, yaw, pitch, np.arange(len(positions)), camera)


def validation_capture_sets(mesh: trimesh.Trimesh, seed: int = 0,
                            camera: Camera = Camera()) -> list[tuple[str, str, CaptureSet]]:
    """(name, category, capture set) triples spanning good, degraded and broken paths."""
    verts = np.asarray(mesh.vertices)
    above = verts[verts[:, 2] >= 0]
    lo, hi = above.min(axis=0), np.maximum(above.max(axis=0), 1.0)
    lo[2] = 0.0
    half_l, half_b = (hi[0] - lo[0]) / 2, (hi[1] - lo[1]) / 2
    h = hi[2]
    rng = np.random.default_rng(seed)
    good = orbit_capture_set(half_l, half_b, 0.35 * h, 40.0, (0.5 * h, 1.6 * h), 25, camera)
    good3 = orbit_capture_set(half_l, half_b, 0.35 * h, 50.0, (0.4 * h, 1.2 * h, 2.2 * h), 16, camera)
    sets = [
        ("good_2rings", "good", good),
        ("good_3rings", "good", good3),
        ("offset_3m", "degraded", _perturbed(good, rng, 3.0, 8.0)),
        ("offset_8m", "degraded", _perturbed(good, rng, 8.0, 15.0)),
        ("thinned_half", "degraded", _subset(good, np.arange(len(good)) % 2 == 0)),
        ("far_90m", "degraded", orbit_capture_set(half_l, half_b, 0.35 * h, 90.0, (0.8 * h, 2.8 * h), 25, camera)),
        ("faces_no_transitions", "broken", _per_face_views(lo, hi, 30.0, camera)),
        ("cluster_8", "broken", _subset(good, np.arange(len(good)) % 25 < 4)),
    ]
    return sets


def planned_capture_sets(paths: dict[str, FlightPath]) -> list[tuple[str, str, CaptureSet]]:
    """The planning stage's paths of the configured ship (e.g. ours, with transition views, and Zhou et al.
    2020's Min-Max path, without; name -> Path) as flown without wind."""
    return [(f"planned_{method}", "planned", captures_from_path(path)) for method, path in paths.items()]


ROW_METRICS = ("error_m", "hole_part_m", "accuracy_part_m", "accuracy_m", "completeness", "fscore", "n_points",
               "registered_views", "failed", "time_s")


def oracle_columns(syn: ReconResult, col: ReconResult | None, metrics: tuple[str, ...] = ROW_METRICS) -> dict:
    """Both oracles' ``metrics`` (None where a result lacks one or there is no COLMAP result), reasons, and
    COLMAP's model sizes and camera residual, as ``<oracle>_<metric>`` columns."""
    row = {}
    for prefix, r in (("synthetic", syn), ("colmap", col)):
        for key in metrics:
            row[f"{prefix}_{key}"] = None if r is None else getattr(r, key, None)
        row[f"{prefix}_reason"] = None if r is None else r.reason
    row["colmap_model_sizes"] = None if col is None else " ".join(str(k) for k in col.extra.get("model_sizes", []))
    row["colmap_camera_residual_m"] = None if col is None else col.extra.get("camera_residual_m")
    return row


def _row(name: str, category: str, cs: CaptureSet, syn: ReconResult, col: ReconResult | None) -> dict:
    return {"name": name, "category": category, "views": len(cs), **oracle_columns(syn, col)}


def add_calibration(row: dict, synthetic: SyntheticOracle, cs: CaptureSet, mesh: trimesh.Trimesh, seed: int,
                    render_width_px: int) -> None:
    """Issue 17 item 6: COLMAP's error over the synthetic oracle's, and the synthetic reconstruction under
    COLMAP's conditions (render width, thinned to COLMAP's point count; :mod:`wrp_eval.recon.calibration`)."""
    syn, col, n_points = row.get("synthetic_error_m"), row.get("colmap_error_m"), row.get("colmap_n_points")
    row["error_ratio_colmap_to_synthetic"] = (col / syn if _finite(syn) and _finite(col) and syn > 0 else None)
    if not n_points:
        return
    eq = colmap_equivalent(synthetic, cs, mesh, int(n_points), render_width_px, seed)
    row.update({f"synthetic_{k}": (v if np.isfinite(v) else None) for k, v in eq.items()})
    for key in ("width", "sparse"):
        ref = row.get(f"synthetic_{key}_error_m")
        row[f"error_ratio_colmap_to_{key}_equivalent"] = (col / ref if _finite(ref) and _finite(col) and ref > 0
                                                          else None)


def summarize(rows: list[dict]) -> dict:
    """Spearman rho of error_m between the oracles (rows where both are finite) and verdict agreement."""
    both = [r for r in rows if r["colmap_failed"] is not None]
    pairs = [(r["synthetic_error_m"], r["colmap_error_m"]) for r in both
             if r["synthetic_error_m"] is not None and r["colmap_error_m"] is not None
             and np.isfinite(r["synthetic_error_m"]) and np.isfinite(r["colmap_error_m"])]
    rho = float(spearmanr(*zip(*pairs, strict=True)).statistic) if len(pairs) >= 3 else float("nan")
    comp = [(r["synthetic_completeness"], r["colmap_completeness"]) for r in both]
    rho_c = float(spearmanr(*zip(*comp, strict=True)).statistic) if len(comp) >= 3 else float("nan")
    agree = [r["synthetic_failed"] == r["colmap_failed"] for r in both]
    good = [r for r in both if not r["synthetic_failed"] and not r["colmap_failed"]]
    ratios = {key: [r[key] for r in good if _finite(r.get(key))]
              for key in ("error_ratio_colmap_to_synthetic", "error_ratio_colmap_to_width_equivalent",
                          "error_ratio_colmap_to_sparse_equivalent")}
    return {"capture_sets": len(rows), "compared": len(both), "spearman_rho_error_m": rho,
            **{f"median_{key}_not_failed": (float(np.median(v)) if v else None) for key, v in ratios.items()},
            "spearman_rho_completeness": rho_c, "pairs_for_rho": len(pairs),
            "failed_verdict_agreement": float(np.mean(agree)) if agree else float("nan"),
            "disagreements": [r["name"] for r, a in zip(both, agree, strict=True) if not a]}


def write_outputs(rows: list[dict], summary: dict, out: Path) -> None:
    with atomic_path(out / "table.csv") as tmp, tmp.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    write_text_atomic(out / "summary.json", json.dumps({**summary, "rows": rows}, indent=1, default=float))
    fig = Figure(figsize=(5.5, 4.5))
    ax = fig.subplots()
    colours = {"good": "tab:green", "degraded": "tab:orange", "broken": "tab:red", "planned": "tab:blue"}
    for r in rows:
        if r["colmap_error_m"] is None or r["synthetic_error_m"] is None:
            continue
        marker = "x" if (r["synthetic_failed"] or r["colmap_failed"]) else "o"
        ax.scatter(r["synthetic_error_m"], r["colmap_error_m"], c=colours[r["category"]], marker=marker)
        ax.annotate(r["name"], (r["synthetic_error_m"], r["colmap_error_m"]), fontsize=7)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("synthetic oracle error_m (m)")
    ax.set_ylabel("COLMAP oracle error_m (m)")
    ax.set_title(f"Spearman rho = {summary['spearman_rho_error_m']:.2f}; "
                 f"verdict agreement = {summary['failed_verdict_agreement']:.2f}\n(x = failed by either)",
                 fontsize=9)
    fig.tight_layout()
    with atomic_path(out / "scatter.png") as tmp:
        fig.savefig(tmp, dpi=120, format="png")


def _read_colmap_rows(file: Path) -> dict[str, dict]:
    """COLMAP columns of a previous summary.json, by capture-set name (to re-score only the synthetic side)."""
    try:
        rows = json.loads(Path(file).read_text())["rows"]
        return {r["name"]: {k: v for k, v in r.items() if k.startswith("colmap_")} for r in rows}
    except FileNotFoundError:
        raise InputError(file, "no such summary file") from None
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise InputError(file, f"not a validate-oracle summary.json: {err}") from None


def validate_oracle(oracle: OracleSection, mesh: trimesh.Trimesh, out: Path, seed: int = 0,
                    planned: dict[str, FlightPath] | None = None, reuse_colmap: Path | None = None) -> dict:
    """Run both oracles on every validation capture set (plus the planner's ``planned`` paths, method -> Path);
    write table.csv, summary.json, scatter.png (and COLMAP's databases under OUT/colmap/). With
    ``reuse_colmap`` (a previous summary.json of the same config and seed), the COLMAP figures are taken from
    it and only the synthetic oracle runs."""
    synthetic = SyntheticOracle(oracle)
    previous = _read_colmap_rows(reuse_colmap) if reuse_colmap is not None else None
    if previous is None:
        colmap = ColmapOracle(oracle)
    rows = []
    for name, category, cs in validation_capture_sets(mesh, seed) + planned_capture_sets(planned or {}):
        syn = synthetic.evaluate(cs, mesh, seed=seed)
        if previous is not None:
            if name not in previous:
                continue
            row = _row(name, category, cs, syn, None)
            row.update(previous[name])
        else:
            # features and matches are kept per capture set under OUT/colmap/NAME: a re-run into the same
            # folder (other mapper settings) maps again without rendering and matching (see colmap.py)
            colmap.work_dir = out / "colmap" / name
            col = colmap.evaluate(cs, mesh, seed=seed)
            row = _row(name, category, cs, syn, col)
        add_calibration(row, synthetic, cs, mesh, seed, oracle.colmap.image_width_px)
        rows.append(row)
        log.info(f"{name:22s} synthetic err {syn.error_m:.4f} comp {syn.completeness:.3f} "
              f"reg {syn.registered_views}/{len(cs)} failed {syn.failed} | colmap err {row['colmap_error_m']:.4f} "
              f"comp {row['colmap_completeness']:.3f} reg {row['colmap_registered_views']}/{len(cs)} "
              f"failed {row['colmap_failed']} ({row['colmap_time_s']:.0f} s)")
        write_outputs(rows, summarize(rows), out)  # partial results survive an interruption
    summary = summarize(rows)
    write_outputs(rows, summary, out)
    return summary


# -- perturbed capture sets of one path (issue 17, item 5; wrp_eval/recon/perturbed.py) ----------------------

PERTURBED_METRICS = ("error_m", "accuracy_m", "completeness", "fscore", "registered_views", "failed", "time_s",
                     "hole_part_m", "accuracy_part_m")
DELTA_METRICS = ("error_m", "completeness")
REPEAT_SEED_OFFSETS = (1, 2)   # the reference again with seed + 1, seed + 2: each oracle's repeat noise
SPEARMAN_TARGET = 0.6          # issue 17: rank correlation of the two oracles' deltas
KIND_COLOURS = {"single_view": "tab:blue", "nav_drift": "tab:orange", "heading_bias": "tab:green",
                "blur": "tab:purple", "flight": "tab:red"}


def capture_sha(cs: CaptureSet) -> str:
    """Short hash of a capture set's poses, roll, priors, blur and views, and their view ids where set (a reused
    COLMAP row must be of the same set)."""
    import hashlib

    h = hashlib.sha256()
    views = () if cs.view_id is None else (cs.view_ids(),)      # only where set: older hashes stay valid
    for arr in (cs.positions, cs.yaw, cs.pitch, cs.planned_index, cs.rotations(), cs.position_priors(), cs.blur(),
                *views):
        h.update(np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    return h.hexdigest()[:16]


def _finite(x: Any) -> TypeGuard[float]:
    return x is not None and not isinstance(x, bool) and np.isfinite(float(x))


def perturbed_row(name: str, kind: str, cs: CaptureSet, syn: ReconResult, col: ReconResult | None) -> dict:
    """One row of perturbed_table.csv: the set, its perturbation figures and both oracles' results (the
    synthetic oracle's ``hole_part_m`` / ``accuracy_part_m`` where its results carry them, else None)."""
    prior_err = np.linalg.norm(cs.position_priors() - cs.positions, axis=1)
    row = {"name": name, "kind": kind, "views": len(cs), "capture_sha": capture_sha(cs),
           "blur_px_mean": float(cs.blur().mean()) if len(cs) else 0.0,
           "prior_error_rms_m": float(np.sqrt(np.mean(prior_err ** 2))) if len(cs) else 0.0}
    return {**row, **oracle_columns(syn, col, PERTURBED_METRICS)}


def add_deltas(rows: list[dict], reference: str = "unperturbed") -> None:
    """Set ``<oracle>_delta_<metric>`` (this set's value minus the reference row's; None where either is not
    finite) on every row, in place, for ``DELTA_METRICS``."""
    ref = next((r for r in rows if r["name"] == reference), None)
    for r in rows:
        for prefix in ("synthetic", "colmap"):
            for m in DELTA_METRICS:
                a, b = r.get(f"{prefix}_{m}"), None if ref is None else ref.get(f"{prefix}_{m}")
                r[f"{prefix}_delta_{m}"] = float(a) - float(b) if _finite(a) and _finite(b) else None


NOISE_KINDS = ("reference", "repeat", "jitter")   # rows that measure noise, not a perturbation's effect


def _repeat_noise(rows: list[dict], key: str, kinds: tuple[str, ...] = ("reference", "repeat")) -> float | None:
    """Standard deviation (ddof 1) of ``key`` over the reference and the rows of ``kinds`` (seed repeats; with
    "jitter", the reference under an ideal flight's pose noise); None if < 2."""
    values = [float(r[key]) for r in rows if r["kind"] in kinds and _finite(r.get(key))]
    return float(np.std(values, ddof=1)) if len(values) >= 2 else None


def _noise(rows: list[dict], key: str) -> float | None:
    """The larger of the seed-repeat noise and the jitter noise of ``key`` (what a delta must exceed)."""
    found = [v for v in (_repeat_noise(rows, key), _repeat_noise(rows, key, ("reference", "jitter")))
             if v is not None]
    return max(found) if found else None


def _agreement(rows: list[dict], metric: str, noise_syn: float | None, noise_col: float | None) -> dict:
    """Spearman rho and sign agreement of the two oracles' deltas of ``metric`` over ``rows``."""
    pairs = [(r["synthetic_delta_" + metric], r["colmap_delta_" + metric]) for r in rows
             if _finite(r.get("synthetic_delta_" + metric)) and _finite(r.get("colmap_delta_" + metric))]
    syn = np.array([p[0] for p in pairs], dtype=float)
    col = np.array([p[1] for p in pairs], dtype=float)
    same = np.sign(syn) == np.sign(col)
    out = {"pairs": len(pairs),
           "spearman_rho": float(spearmanr(syn, col).statistic) if len(pairs) >= 3 else float("nan"),
           "sign_agreement": float(same.mean()) if len(pairs) else float("nan"),
           "noise_synthetic": noise_syn, "noise_colmap": noise_col,
           "below_noise_sets": None, "sign_agreement_above_noise": None, "pairs_above_noise": None}
    if noise_syn is not None and noise_col is not None:
        small = (np.abs(syn) < noise_syn) | (np.abs(col) < noise_col)  # either delta within its oracle's noise
        out["below_noise_sets"] = int(small.sum())
        out["pairs_above_noise"] = int((~small).sum())
        out["sign_agreement_above_noise"] = float(same[~small].mean()) if np.any(~small) else float("nan")
    return out


def summarize_perturbed(rows: list[dict]) -> dict:
    """Agreement of the two oracles on the perturbed sets (kinds other than reference / repeat / jitter),
    relative to the unperturbed set: per metric of ``DELTA_METRICS`` the Spearman rho of the deltas (target
    >= 0.6), their sign agreement, each oracle's noise (the larger of its seed-repeat and its jitter std;
    both reported) and how many sets have a delta within it; per kind the median deltas and the sign
    agreement of error_m."""
    ref = next((r for r in rows if r["kind"] == "reference"), None)
    perturbed = [r for r in rows if r["kind"] not in NOISE_KINDS]
    summary: dict[str, Any]
    summary = {"capture_sets": len(rows), "perturbed_sets": len(perturbed),
               "compared": sum(r.get("colmap_failed") is not None for r in perturbed),
               "spearman_target": SPEARMAN_TARGET,
               "reference": None if ref is None else {k: ref.get(k) for k in (
                   "synthetic_error_m", "synthetic_completeness", "synthetic_registered_views", "colmap_error_m",
                   "colmap_completeness", "colmap_registered_views", "views")}}
    for m in DELTA_METRICS:
        summary[m] = _agreement(perturbed, m, _noise(rows, f"synthetic_{m}"), _noise(rows, f"colmap_{m}"))
        summary[m].update({f"{kind}_noise_{prefix}": _repeat_noise(rows, f"{prefix}_{m}", ("reference", kind))
                           for kind in ("repeat", "jitter") for prefix in ("synthetic", "colmap")})
    rho = summary["error_m"]["spearman_rho"]
    summary["spearman_target_met"] = bool(np.isfinite(rho) and rho >= SPEARMAN_TARGET)
    per_kind = {}
    for kind in dict.fromkeys(r["kind"] for r in perturbed):
        of_kind = [r for r in perturbed if r["kind"] == kind]
        med = {}
        for prefix in ("synthetic", "colmap"):
            values = [r[f"{prefix}_delta_error_m"] for r in of_kind if _finite(r.get(f"{prefix}_delta_error_m"))]
            med[f"{prefix}_median_delta_error_m"] = float(np.median(values)) if values else None
        per_kind[kind] = {"sets": len(of_kind), **med,
                          "sign_agreement_error_m": _agreement(of_kind, "error_m", None, None)["sign_agreement"]}
    summary["per_kind"] = per_kind
    summary["failed_synthetic"] = [r["name"] for r in rows if r.get("synthetic_failed")]
    summary["failed_colmap"] = [r["name"] for r in rows if r.get("colmap_failed")]
    return summary


def _symlog_threshold(values: list[float]) -> float:
    nonzero = np.abs([v for v in values if v != 0.0])
    return float(max(np.percentile(nonzero, 25), 1e-6)) if nonzero.size else 1e-3


def write_perturbed_outputs(rows: list[dict], summary: dict, out: Path) -> None:
    """perturbed_table.csv, perturbed_summary.json (summary + rows) and perturbed_scatter.png, atomically."""
    fields = list(dict.fromkeys(k for r in rows for k in r))
    with atomic_path(out / "perturbed_table.csv") as tmp, tmp.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    write_text_atomic(out / "perturbed_summary.json", json.dumps({**summary, "rows": rows}, indent=1, default=float))
    fig = Figure(figsize=(7.5, 6.0))
    ax = fig.subplots()
    shown = [r for r in rows if r["kind"] not in NOISE_KINDS
             and _finite(r.get("synthetic_delta_error_m")) and _finite(r.get("colmap_delta_error_m"))]
    for kind in dict.fromkeys(r["kind"] for r in shown):
        of_kind = [r for r in shown if r["kind"] == kind]
        ax.scatter([r["synthetic_delta_error_m"] for r in of_kind], [r["colmap_delta_error_m"] for r in of_kind],
                   c=KIND_COLOURS.get(kind, "tab:gray"), label=kind, s=18,
                   marker="o")
    for r in shown:
        ax.annotate(r["name"], (r["synthetic_delta_error_m"], r["colmap_delta_error_m"]), fontsize=5)
    if shown:
        ax.set_xscale("symlog", linthresh=_symlog_threshold([r["synthetic_delta_error_m"] for r in shown]))
        ax.set_yscale("symlog", linthresh=_symlog_threshold([r["colmap_delta_error_m"] for r in shown]))
        ax.legend(fontsize=7)
    ax.axhline(0.0, color="0.7", lw=0.8)
    ax.axvline(0.0, color="0.7", lw=0.8)
    e = summary["error_m"]
    ax.set_xlabel("synthetic oracle: error_m - unperturbed (m, symlog)")
    ax.set_ylabel("COLMAP oracle: error_m - unperturbed (m, symlog)")
    ax.set_title(f"perturbed sets of one path: Spearman rho = {e['spearman_rho']:.2f} (target >= "
                 f"{SPEARMAN_TARGET}); sign agreement = {e['sign_agreement']:.2f} ({e['pairs']} sets)", fontsize=8)
    fig.tight_layout()
    with atomic_path(out / "perturbed_scatter.png") as tmp:
        fig.savefig(tmp, dpi=130, format="png")


def _fmt(x, spec: str = ".4f") -> str:
    return format(float(x), spec) if _finite(x) else str(x)


def validate_perturbed(oracle: OracleSection, mesh: trimesh.Trimesh, sets: list[tuple[str, str, CaptureSet]],
                       out: Path, seed: int = 0, reuse_colmap: Path | None = None,
                       repeats: tuple[int, ...] = REPEAT_SEED_OFFSETS) -> dict:
    """Both oracles on the perturbed capture sets of one path (``sets`` from
    :func:`wrp_eval.recon.perturbed.perturbed_capture_sets`, the reference first), plus the reference again
    with the seeds ``seed + k`` for ``k`` in ``repeats`` (kind ``repeat``: each oracle's repeat noise); write
    perturbed_table.csv, perturbed_summary.json and perturbed_scatter.png after every set (COLMAP's databases
    under OUT/colmap/NAME/). With ``reuse_colmap`` (a previous perturbed_summary.json of the same config and
    seed) the COLMAP columns are taken from it and only the synthetic oracle runs; sets it lacks are skipped,
    and sets whose poses differ from the ones it scored are listed in ``reuse_mismatched_sets``."""
    out = Path(out)
    sets = list(sets)
    if not sets or sets[0][1] != "reference":
        raise ValueError("the perturbed sets must start with the reference (unperturbed) set")
    reference_name, _, reference = sets[0]
    runs = [(name, kind, cs, seed) for name, kind, cs in sets]
    runs += [(f"{reference_name}_repeat{k}", "repeat", reference, seed + k) for k in repeats]
    synthetic = SyntheticOracle(oracle)
    previous = _read_colmap_rows(reuse_colmap) if reuse_colmap is not None else None
    if previous is not None and reference_name not in previous:
        raise InputError(cast(Path, reuse_colmap), f"has no {reference_name!r} row: not a validate-oracle "
                                       f"perturbed_summary.json")
    colmap = ColmapOracle(oracle) if previous is None else None
    rows, mismatched = [], []
    errors: list[str] = []
    for name, kind, cs, run_seed in runs:
        if previous is not None and name not in previous:
            continue
        syn = _evaluate_or_error(synthetic, cs, mesh, run_seed, f"{name}: synthetic", errors)
        if previous is not None:
            row = perturbed_row(name, kind, cs, syn, None)
            old_sha = previous[name].get("colmap_capture_sha")
            row.update(previous[name])
            if old_sha is not None and old_sha != row["capture_sha"]:
                mismatched.append(name)
        else:
            # features and matches kept per set under OUT/colmap/NAME, as validate_oracle does
            cast(ColmapOracle, colmap).work_dir = out / "colmap" / name
            col = _evaluate_or_error(colmap, cs, mesh, run_seed, f"{name}: colmap", errors)
            row = perturbed_row(name, kind, cs, syn, col)
            row["colmap_capture_sha"] = row["capture_sha"]  # the set COLMAP scored (checked when reused)
        rows.append(row)
        add_deltas(rows, reference_name)
        log.info(f"{name:30s} {kind:12s} synthetic err {_fmt(row['synthetic_error_m'])} "
              f"(d {_fmt(row['synthetic_delta_error_m'], '+.4f')}) "
              f"reg {row['synthetic_registered_views']}/{len(cs)} | colmap err {_fmt(row['colmap_error_m'])} "
              f"(d {_fmt(row['colmap_delta_error_m'], '+.4f')}) reg {row['colmap_registered_views']}/{len(cs)} "
              f"({_fmt(row['colmap_time_s'], '.0f')} s)")
        summary = {**summarize_perturbed(rows), "reuse_mismatched_sets": mismatched, "oracle_errors": errors}
        write_perturbed_outputs(rows, summary, out)  # partial results survive an interruption
    summary = {**summarize_perturbed(rows), "reuse_mismatched_sets": mismatched, "oracle_errors": errors}
    write_perturbed_outputs(rows, summary, out)
    return summary


class _OracleError:
    """Stands in for the :class:`ReconResult` of an oracle that raised: no figures, the error as the reason."""

    def __init__(self, reason: str):
        self.reason = reason
        self.extra: dict[str, Any] = {}

    def __getattr__(self, key):
        return None


def _evaluate_or_error(oracle, cs: CaptureSet, mesh: trimesh.Trimesh, seed: int, what: str, errors: list):
    """``oracle.evaluate``; an exception is recorded (in ``errors`` and as the row's reason, no figures) and
    printed, so that one bad set does not end a run of 40 minutes (re-score it with --reuse-colmap)."""
    try:
        return oracle.evaluate(cs, mesh, seed=seed)
    except Exception as err:  # noqa: BLE001  # recorded, reported in the summary and on stdout
        message = f"oracle error: {type(err).__name__}: {err}"
        errors.append(f"{what}: {message}")
        log.info(f"{what}: {message}")
        traceback.print_exc()  # the log keeps where it failed
        return _OracleError(message)
