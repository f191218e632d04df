"""``wrp-eval validate-oracle``: the synthetic oracle against COLMAP on good, degraded and broken paths.

Capture sets are built around the configured ship's above-water bounding box (known by construction):
good = rings of oblique views (the shape of a well-planned path); degraded = the same with position and
yaw offsets (wind), thinned, or flown farther; broken = per-face views with no transition views between
faces (the failure the paper's transition viewpoints exist to prevent, Sec. 3.3) and a sparse ring.
Both oracles measure each; we report the Spearman rank correlation of error_m and the agreement of the
failed verdicts (issue 6 target: rho >= 0.8, same verdicts).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import trimesh
from matplotlib.figure import Figure
from scipy.stats import spearmanr

from wrp_eval.atomic import atomic_path, write_text_atomic
from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.errors import InputError
from wrp_eval.planning.path import Path as FlightPath
from wrp_eval.recon.base import ReconResult
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recon.colmap import ColmapOracle
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.scenarios import orbit_capture_set
from wrp_eval.recon.synthetic import SyntheticOracle
from wrp_eval.sim.captures import CaptureSet


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


def _row(name: str, category: str, cs: CaptureSet, syn: ReconResult, col: ReconResult | None) -> dict:
    row = {"name": name, "category": category, "views": len(cs)}
    for prefix, r in (("synthetic", syn), ("colmap", col)):
        for key in ("error_m", "accuracy_m", "completeness", "fscore", "registered_views", "failed", "time_s"):
            row[f"{prefix}_{key}"] = None if r is None else getattr(r, key)
        row[f"{prefix}_reason"] = None if r is None else r.reason
    row["colmap_model_sizes"] = None if col is None else " ".join(str(k) for k in col.extra.get("model_sizes", []))
    row["colmap_camera_residual_m"] = None if col is None else col.extra.get("camera_residual_m")
    return row


def summarize(rows: list[dict]) -> dict:
    """Spearman rho of error_m between the oracles (rows where both are finite) and verdict agreement."""
    both = [r for r in rows if r["colmap_failed"] is not None]
    pairs = [(r["synthetic_error_m"], r["colmap_error_m"]) for r in both
             if r["synthetic_error_m"] is not None and r["colmap_error_m"] is not None
             and np.isfinite(r["synthetic_error_m"]) and np.isfinite(r["colmap_error_m"])]
    rho = float(spearmanr(*zip(*pairs)).statistic) if len(pairs) >= 3 else float("nan")
    comp = [(r["synthetic_completeness"], r["colmap_completeness"]) for r in both]
    rho_c = float(spearmanr(*zip(*comp)).statistic) if len(comp) >= 3 else float("nan")
    agree = [r["synthetic_failed"] == r["colmap_failed"] for r in both]
    return {"capture_sets": len(rows), "compared": len(both), "spearman_rho_error_m": rho,
            "spearman_rho_completeness": rho_c, "pairs_for_rho": len(pairs),
            "failed_verdict_agreement": float(np.mean(agree)) if agree else float("nan"),
            "disagreements": [r["name"] for r, a in zip(both, agree) if not a]}


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
        rows.append(row)
        print(f"{name:22s} synthetic err {syn.error_m:.4f} comp {syn.completeness:.3f} "
              f"reg {syn.registered_views}/{len(cs)} failed {syn.failed} | colmap err {row['colmap_error_m']:.4f} "
              f"comp {row['colmap_completeness']:.3f} reg {row['colmap_registered_views']}/{len(cs)} "
              f"failed {row['colmap_failed']} ({row['colmap_time_s']:.0f} s)", flush=True)
        write_outputs(rows, summarize(rows), out)  # partial results survive an interruption
    summary = summarize(rows)
    write_outputs(rows, summary, out)
    return summary
