"""What ``wrp-eval fly`` writes from a :class:`FlightResult`: Parquet tables of the capture poses and a rerun
recording. Each file is written through :func:`wrp_eval.atomic.atomic_path` (a temporary beside its target,
fsync'ed and renamed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import rerun as rr

from wrp_eval.atomic import atomic_path
from wrp_eval.camera import camera_rotations
from wrp_eval.planning.path import FlightPath
from wrp_eval.recording import recording
from wrp_eval.sim.flight_state import OUTCOME_NAMES
from wrp_eval.sim.results import FlightResult


def _atomic_parquet(table: pa.Table, target: Path) -> None:
    with atomic_path(target) as tmp:
        pq.write_table(table, tmp)


def write_flight_tables(result: FlightResult, path: FlightPath, out_dir: Path, seed: int) -> tuple[Path, Path]:
    """captures.parquet (one row per trial x view) and trials.parquet (one row per trial), atomically."""
    b, n = result.batch, result.n_views
    trial = np.repeat(np.arange(b), n)
    view = np.tile(np.arange(n), b)
    pos = np.full((b, n, 3), np.nan)
    yaw = np.full((b, n), np.nan)
    for i, cs in enumerate(result.captures):
        pos[i, cs.planned_index] = cs.positions
        yaw[i, cs.planned_index] = cs.yaw
    est = result.estimated_offsets
    captures = pa.table({
        "trial": trial, "view": view, "taken": result.taken.ravel(),
        "x_m": pos[..., 0].ravel(), "y_m": pos[..., 1].ravel(), "z_m": pos[..., 2].ravel(),
        "yaw_deg": np.degrees(yaw).ravel(), "pitch_deg": np.degrees(result.camera_pitch).ravel(),
        "dx_m": result.offsets[..., 0].ravel(), "dy_m": result.offsets[..., 1].ravel(),
        "dz_m": result.offsets[..., 2].ravel(), "dyaw_deg": np.degrees(result.offsets[..., 3]).ravel(),
        "roll_deg": np.degrees(result.camera_roll).ravel(),
        "est_dx_m": est[..., 0].ravel(), "est_dy_m": est[..., 1].ravel(), "est_dz_m": est[..., 2].ravel(),
        "est_dyaw_deg": np.degrees(est[..., 3]).ravel(), "blur_px": result.blur_px.ravel(),
        "battery_charge": result.battery_charge.ravel(),
        "ship_heave_m": result.ship_motion[..., 0].ravel(),
        "ship_roll_deg": np.degrees(result.ship_motion[..., 1]).ravel(),
        "ship_pitch_deg": np.degrees(result.ship_motion[..., 2]).ravel(),
        "ship_yaw_deg": np.degrees(result.ship_motion[..., 3]).ravel(),
        "gimbal_saturated": result.gimbal_saturated.ravel(), "capture_time_s": result.capture_time_s.ravel(),
        "sortie": result.view_sortie.ravel(),
    })
    trials = pa.table({
        "trial": np.arange(b), "seed": np.full(b, seed), "failed": result.failed,
        "outcome": list(result.outcome_reason), "views_taken": result.taken.sum(axis=1),
        "flight_time_s": result.flight_time_s, "sorties": result.sorties,
        "ending": [OUTCOME_NAMES[int(c)] for c in result.outcome],
    })
    out_dir.mkdir(parents=True, exist_ok=True)
    a, c = out_dir / "captures.parquet", out_dir / "trials.parquet"
    _atomic_parquet(captures, a)
    _atomic_parquet(trials, c)
    return a, c


def write_rerun(result: FlightResult, path: FlightPath, file: Path, max_trials: int = 8) -> None:
    """Trajectories, capture frusta (first trial) and wind arrows into a .rrd recording (atomic)."""
    with recording(file, application_id="wrp-eval-fly") as rec:
        _log_flights(rec, result, path, max_trials)


def _log_flights(rec: rr.RecordingStream, result: FlightResult, path: FlightPath, max_trials: int) -> None:
    traj = result.trajectory
    shown = min(result.batch, max_trials)
    rec.log("plan/viewpoints", rr.Points3D(path.positions, radii=0.3, colors=[[40, 160, 255]]), static=True)
    rec.log("flights/trajectories", rr.LineStrips3D([traj.position[i] for i in range(shown)]), static=True)
    for i in range(shown):
        step = max(1, len(traj.time) // 200)
        rec.log(f"flights/{i}/wind", rr.Arrows3D(origins=traj.position[i, ::step], vectors=traj.wind[i, ::step]),
                static=True)
    cs = result.captures[0]
    if len(cs):
        rots = camera_rotations(cs.yaw, cs.pitch, cs.roll)
        cam = cs.camera
        for j in range(len(cs)):
            ent = f"captures/trial0/view{int(cs.planned_index[j])}"
            rec.log(ent, rr.Transform3D(translation=cs.positions[j], mat3x3=rots[j]), static=True)
            rec.log(ent, rr.Pinhole(focal_length=cam.focal_px, width=cam.image_width_px,
                                    height=cam.image_height_px, image_plane_distance=2.0), static=True)
