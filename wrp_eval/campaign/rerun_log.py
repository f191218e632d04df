"""One rerun recording per campaign: the ship and the planned path static, every trial on a ``trial`` timeline.

Entities (world frame, metres):
  world/ship (static mesh), world/path (static planned line + viewpoints),
  world/trial/trajectory (flown, down-sampled), world/trial/frusta (capture frusta as line strips),
  world/trial/wind (arrows at the capture points, 1 m per m/s), world/trial/recorded_positions (where the
  navigation believed each photo was taken), metrics/<name> (scalars per trial: the oracle's metrics, failed,
  views_taken_fraction, blur_px_p95, returned_home).
The recording is written to a temporary beside ``<out>/campaign.rrd`` while the campaign runs and renamed to
``campaign.rrd`` when it ends (:func:`wrp_eval.recording.recording`). On a resume the stored trials are
logged again from the Parquet store first (it holds everything drawn here), so the file always covers the
whole campaign.
Read it back with :func:`read_trial_ids` (rerun's own ``rerun.chunk.RrdReader``).
"""

from __future__ import annotations

import time
from contextlib import ExitStack
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.chunk import RrdReader

from wrp_eval.campaign.records import METRIC_NAMES
from wrp_eval.planning.path import FlightPath, digest_of_document
from wrp_eval.recording import recording

TIMELINE = "trial"
FRUSTUM_DEPTH_M = 4.0


def blueprint():
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(name="flights", origin="/world"),
            rrb.Vertical(
                rrb.TimeSeriesView(name="error (m)", origin="/metrics/error_m"),
                rrb.TimeSeriesView(name="completeness", origin="/metrics/completeness"),
                rrb.TimeSeriesView(name="failed", origin="/metrics/failed"),
                rrb.TimeSeriesView(name="views taken", origin="/metrics/views_taken_fraction"),
                rrb.TimeSeriesView(name="blur p95 (px)", origin="/metrics/blur_px_p95"),
            ),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(state="expanded"),
        collapse_panels=True,
    )


def frustum_strips(positions: np.ndarray, yaw: np.ndarray, pitch: np.ndarray, half_fov_x: float,
                   half_fov_y: float, depth: float = FRUSTUM_DEPTH_M) -> np.ndarray:
    """(n, 10, 3) one line strip per camera: apex -> 4 image corners at ``depth`` (closed) -> apex edges.

    Built from the camera's optical axis (yaw CCW from +x, pitch above horizontal) with right = axis x z."""
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    forward = np.stack([cp * cy, cp * sy, sp], axis=-1)
    right = np.stack([sy, -cy, np.zeros_like(yaw)], axis=-1)
    up = np.cross(right, forward)
    tx, ty = np.tan(half_fov_x), np.tan(half_fov_y)
    signs = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float)
    corners = positions[:, None] + depth * (forward[:, None] + signs[None, :, :1] * tx * right[:, None]
                                            + signs[None, :, 1:] * ty * up[:, None])
    apex = positions[:, None]
    order = [apex, corners[:, 0:1], corners[:, 1:2], apex, corners[:, 2:3], corners[:, 3:4], apex,
             corners[:, 0:1], corners[:, 3:4], corners[:, 2:3]]
    return np.concatenate(order, axis=1)


def campaign_recording_id(path: FlightPath) -> str:
    """The recording id of a path's campaign: other recordings of the same run (ship, plan) that use it merge
    into the same recording (``rerun rrd merge``)."""
    return f"campaign-{path.digest()}"


class CampaignRecorder:
    """Writes the campaign's recording. ``seconds`` accumulates the time spent logging (for the overhead)."""

    def __init__(self, out_dir: Path, path_doc: dict, ship_mesh=None):
        self.rr = rr
        self.final = Path(out_dir) / "campaign.rrd"
        self.seconds = 0.0
        start = time.perf_counter()
        # the stream stays open across log_trial calls: the recording's block ends in close()
        self._file = ExitStack()
        # the id campaign_recording_id gives the path this document is (its digest is the document's)
        recording_id = f"campaign-{digest_of_document(path_doc)}"
        self.rec = self._file.enter_context(recording(self.final, recording_id=recording_id,
                                                      default_blueprint=blueprint()))
        vps = path_doc["viewpoints"]
        self.planned = np.array([[v["x_m"], v["y_m"], v["z_m"]] for v in vps], dtype=float)
        self.planned_yaw = np.radians([v["yaw_deg"] for v in vps])
        self.planned_pitch = np.radians([v["gimbal_pitch_deg"] for v in vps])
        cam = path_doc["camera"]
        width_mm = cam["sensor_width_mm"]
        height_mm = width_mm * cam["image_height_px"] / cam["image_width_px"]
        self.half_fov = (np.arctan(width_mm / 2 / cam["focal_mm"]), np.arctan(height_mm / 2 / cam["focal_mm"]))
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        if ship_mesh is not None:
            self.rec.log("world/ship", rr.Mesh3D(vertex_positions=np.asarray(ship_mesh.vertices, np.float32),
                                                 triangle_indices=np.asarray(ship_mesh.faces, np.uint32),
                                                 albedo_factor=[0.6, 0.6, 0.65]), static=True)
        self.rec.log("world/path/line", rr.LineStrips3D([self.planned], colors=[[80, 160, 255]]), static=True)
        self.rec.log("world/path/viewpoints", rr.Points3D(self.planned, radii=0.3, colors=[[80, 160, 255]]),
                     static=True)
        self.seconds += time.perf_counter() - start

    def log_trial(self, record: dict) -> None:
        """Log one stored trial record (a dict of :data:`records.SCHEMA`)."""
        rr, rec = self.rr, self.rec
        start = time.perf_counter()
        rec.set_time(TIMELINE, sequence=int(record["trial_id"]))
        traj = record.get("trajectory")
        if traj:
            rec.log("world/trial/trajectory", rr.LineStrips3D([np.asarray(traj)], colors=[[255, 140, 0]]))
        flown = np.asarray(record["flown_offsets"], dtype=float)
        taken = np.all(np.isfinite(flown), axis=1)
        capture = self.planned[taken] + flown[taken, :3]
        if capture.size:
            pitch = self.planned_pitch[taken]
            if record.get("camera_pitch"):    # the achieved pitch (absent in campaigns stored before it)
                achieved = np.asarray(record["camera_pitch"], dtype=float)[taken]
                pitch = np.where(np.isfinite(achieved), achieved, pitch)
            strips = frustum_strips(capture, self.planned_yaw[taken] + flown[taken, 3], pitch, *self.half_fov)
            rec.log("world/trial/frusta", rr.LineStrips3D(strips, colors=[[255, 220, 0]], radii=0.03))
            wind = record.get("wind_at_views")
            if wind:
                rec.log("world/trial/wind", rr.Arrows3D(origins=capture, vectors=np.asarray(wind)[taken],
                                                        colors=[[120, 220, 255]]))
            estimated = record.get("estimated_offsets")
            if estimated:      # where the navigation believed each photo was taken (the image's position prior)
                recorded = self.planned[taken] + np.asarray(estimated, dtype=float)[taken, :3]
                rec.log("world/trial/recorded_positions", rr.Points3D(recorded, radii=0.15, colors=[[255, 80, 200]]))
        self._log_capture_metrics(record, taken)
        for name in METRIC_NAMES:
            value = record.get(name)
            if value is not None and np.isfinite(value):
                rec.log(f"metrics/{name}", rr.Scalars(float(value)))
        rec.log("metrics/failed", rr.Scalars(1.0 if record["failed"] else 0.0))
        self.seconds += time.perf_counter() - start

    def _log_capture_metrics(self, record: dict, taken: np.ndarray) -> None:
        """Per-trial figures of the capture realism: views taken, blur p95, sent home early."""
        rr, rec = self.rr, self.rec
        rec.log("metrics/views_taken_fraction", rr.Scalars(float(taken.mean()) if taken.size else 0.0))
        blur = record.get("blur_px")
        if blur:
            blur = np.asarray(blur, dtype=float)
            if np.isfinite(blur).any():
                rec.log("metrics/blur_px_p95", rr.Scalars(float(np.nanpercentile(blur, 95))))
        outcome = record.get("flight_outcome")
        if outcome:
            rec.log("metrics/returned_home", rr.Scalars(1.0 if outcome.startswith("returned") else 0.0))

    def close(self) -> Path:
        """Flush, close and move the recording to ``campaign.rrd``."""
        start = time.perf_counter()
        self._file.close()  # the end of the recording's block: flush, close, rename onto campaign.rrd
        self.seconds += time.perf_counter() - start
        return self.final


def read_trial_ids(rrd_file: str | Path) -> np.ndarray:
    """Sorted unique values of the ``trial`` timeline at which ``metrics/failed`` was logged in a .rrd file,
    read with rerun's own reader (every logged trial has exactly one such row)."""
    ids = []
    for chunk in RrdReader(str(rrd_file)).stream():
        if chunk.entity_path == "/metrics/failed" and TIMELINE in chunk.timeline_names:
            ids.extend(chunk.to_record_batch().column(TIMELINE).to_pylist())
    return np.unique(np.asarray(ids, dtype=np.int64))
