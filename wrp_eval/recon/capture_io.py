"""Capture sets from the files other stages write: a planned path.json, or one trial of captures.parquet."""

from __future__ import annotations

from pathlib import Path as FsPath

import numpy as np
import pyarrow.parquet as pq

from wrp_eval.errors import InputError
from wrp_eval.planning.path import Path
from wrp_eval.sim.captures import CaptureSet

CAPTURE_COLUMNS = ("trial", "view", "taken", "x_m", "y_m", "z_m", "yaw_deg", "pitch_deg")


def captures_from_path(path: Path, offsets: np.ndarray | None = None, pitch: np.ndarray | None = None
                       ) -> CaptureSet:
    """Every view of a path as a capture set: the planned poses (a windless, perfectly flown trial), moved by
    ``offsets`` (n, 4: dx, dy, dz m, dyaw rad) when given; the gimbal at ``pitch`` (n,) rad where given and
    finite (an achieved pitch from a campaign), else at its planned pitch."""
    pose = np.concatenate([np.asarray(path.positions, dtype=float), np.asarray(path.yaw, dtype=float)[:, None]],
                          axis=1)
    if offsets is not None:
        pose = pose + np.asarray(offsets, dtype=float).reshape(pose.shape)
    planned_pitch = np.asarray(path.pitch, dtype=float)
    if pitch is not None:
        pitch = np.asarray(pitch, dtype=float).reshape(planned_pitch.shape)
        planned_pitch = np.where(np.isfinite(pitch), pitch, planned_pitch)
    return CaptureSet(pose[:, :3], pose[:, 3], planned_pitch, np.arange(len(path)), path.camera)


def captures_from_parquet(file: str | FsPath, trial: int, path: Path) -> CaptureSet:
    """The views actually taken in ``trial`` of a ``captures.parquet`` (the simulator's table; one row per
    trial x view, degrees at the edge); the camera comes from ``path``."""
    file = FsPath(file)
    try:
        table = pq.read_table(file, columns=list(CAPTURE_COLUMNS))
    except FileNotFoundError:
        raise InputError(file, "no such captures file") from None
    except Exception as err:  # pyarrow raises several types for unreadable / schema-less files
        raise InputError(file, f"not a captures table with columns {', '.join(CAPTURE_COLUMNS)}: {err}") from None
    cols = {c: table.column(c).to_numpy(zero_copy_only=False) for c in CAPTURE_COLUMNS}
    rows = (cols["trial"] == trial) & cols["taken"].astype(bool)
    if not np.any(cols["trial"] == trial):
        raise InputError(file, f"no rows for trial {trial} (trials {int(cols['trial'].min())}.."
                               f"{int(cols['trial'].max())})")
    view = cols["view"][rows].astype(int)
    if view.size and view.max() >= len(path):
        raise InputError(file, f"view index {int(view.max())} beyond the path's {len(path)} viewpoints")
    pos = np.column_stack([cols["x_m"][rows], cols["y_m"][rows], cols["z_m"][rows]]).astype(float)
    yaw = np.radians(cols["yaw_deg"][rows].astype(float))
    pitch = np.radians(cols["pitch_deg"][rows].astype(float))
    if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(yaw)) and np.all(np.isfinite(pitch))):
        raise InputError(file, f"trial {trial}: a taken view has non-finite pose values")
    return CaptureSet(pos, yaw, pitch, view, path.camera)
