"""Capture sets from the files other stages write: a planned path.json, or one trial of captures.parquet."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.sim.captures import BLUR_COLUMN, PRIOR_COLUMNS, ROLL_COLUMN, CaptureSet

CAPTURE_COLUMNS = ("trial", "view", "taken", "x_m", "y_m", "z_m", "yaw_deg", "pitch_deg")
# optional columns (files written before them still load): camera roll, recorded (GNSS) positions, motion blur
OPTIONAL_COLUMNS = (ROLL_COLUMN, *PRIOR_COLUMNS, BLUR_COLUMN)


def captures_from_path(path: FlightPath, offsets: np.ndarray | None = None, pitch: np.ndarray | None = None,
                       roll: np.ndarray | None = None, prior_positions: np.ndarray | None = None,
                       blur_px: np.ndarray | None = None) -> CaptureSet:
    """Every view of a path as a capture set: the planned poses (a windless, perfectly flown trial), moved by
    ``offsets`` (n, 4: dx, dy, dz m, dyaw rad) when given; the gimbal at ``pitch`` (n,) rad where given and
    finite (an achieved pitch from a campaign), else at its planned pitch; ``roll`` (n,) rad and the recorded
    ``prior_positions`` (n, 3) m and the motion ``blur_px`` (n,) passed through (None: level camera, priors =
    true positions, sharp images)."""
    pose = np.concatenate([np.asarray(path.positions, dtype=float), np.asarray(path.yaw, dtype=float)[:, None]],
                          axis=1)
    if offsets is not None:
        pose = pose + np.asarray(offsets, dtype=float).reshape(pose.shape)
    planned_pitch = np.asarray(path.pitch, dtype=float)
    if pitch is not None:
        pitch = np.asarray(pitch, dtype=float).reshape(planned_pitch.shape)
        planned_pitch = np.where(np.isfinite(pitch), pitch, planned_pitch)
    if roll is not None:
        roll = np.asarray(roll, dtype=float).reshape(planned_pitch.shape)
    if prior_positions is not None:
        prior_positions = np.asarray(prior_positions, dtype=float).reshape(pose[:, :3].shape)
    if blur_px is not None:
        blur_px = np.asarray(blur_px, dtype=float).reshape(planned_pitch.shape)
    return CaptureSet(pose[:, :3], pose[:, 3], planned_pitch, np.arange(len(path)), path.camera, roll,
                      prior_positions, blur_px, path.view_id)


def _read_columns(file: Path) -> dict[str, np.ndarray]:
    """The required capture columns and whichever optional ones the file has, as numpy arrays."""
    try:
        names = set(pq.read_schema(file).names)
        wanted = list(CAPTURE_COLUMNS) + [c for c in OPTIONAL_COLUMNS if c in names]
        table = pq.read_table(file, columns=wanted)
    except FileNotFoundError:
        raise InputError(file, "no such captures file") from None
    except Exception as err:  # pyarrow raises several types for unreadable / schema-less files
        raise InputError(file, f"not a captures table with columns {', '.join(CAPTURE_COLUMNS)}: {err}") from None
    present = [c for c in PRIOR_COLUMNS if c in names]
    if present and len(present) != len(PRIOR_COLUMNS):
        raise InputError(file, f"has {', '.join(present)} but not all of {', '.join(PRIOR_COLUMNS)}")
    return {c: table.column(c).to_numpy(zero_copy_only=False) for c in wanted}


def captures_from_parquet(file: str | Path, trial: int, path: FlightPath) -> CaptureSet:
    """The views actually taken in ``trial`` of a ``captures.parquet`` (the simulator's table; one row per
    trial x view, degrees at the edge); the camera comes from ``path``. The optional ``roll_deg`` and
    ``prior_x_m`` / ``prior_y_m`` / ``prior_z_m`` columns (:func:`wrp_eval.sim.captures.pose_columns`) become
    the capture set's roll and position priors, ``blur_px`` its motion blur; a file without them gives None
    (level camera, exact priors, sharp images: a record from before these columns is still scored)."""
    file = Path(file)
    cols = _read_columns(file)
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
    roll = np.radians(cols[ROLL_COLUMN][rows].astype(float)) if ROLL_COLUMN in cols else None
    prior = (np.column_stack([cols[c][rows] for c in PRIOR_COLUMNS]).astype(float) if PRIOR_COLUMNS[0] in cols
             else None)
    blur = cols[BLUR_COLUMN][rows].astype(float) if BLUR_COLUMN in cols else None
    values = [pos, yaw, pitch] + [a for a in (roll, prior, blur) if a is not None]
    if not all(np.all(np.isfinite(a)) for a in values):
        raise InputError(file, f"trial {trial}: a taken view has non-finite pose values")
    return CaptureSet(pos, yaw, pitch, view, path.camera, roll, prior, blur, path.view_ids_of(view))
