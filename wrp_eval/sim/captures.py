"""Capture sets: where the camera really was at each photo, the value type the simulator hands the oracle."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wrp_eval.camera import Camera, camera_rotations

# captures.parquet columns of the optional pose fields (degrees / metres at the edge, as the other columns):
# the camera roll and the navigation estimate of the position (the photo's GPS tag)
ROLL_COLUMN = "roll_deg"
BLUR_COLUMN = "blur_px"
PRIOR_COLUMNS = ("prior_x_m", "prior_y_m", "prior_z_m")


@dataclass(frozen=True)
class CaptureSet:
    """Camera poses actually flown for one trial.

    positions (n, 3) m, true camera centres; yaw (n,) rad (follows the airframe); pitch (n,) rad
    (gimbal-stabilised, so the planned pitch unless the gimbal range was exceeded); planned_index (n,) int,
    the path viewpoint each capture belongs to; roll (n,) rad about the optical axis, the roll the gimbal
    left (sign: :mod:`wrp_eval.camera`, positive = right side of the image down), None = level (0);
    prior_positions (n, 3) m, the position the drone's navigation (GNSS) recorded for each photo, what a
    photogrammetry tool gets as the image's position prior; None = the true positions (a perfect fix);
    blur_px (n,) motion blur during the exposure in pixels of ``camera`` (the length of the image-centre
    smear, :mod:`wrp_eval.sim.blur`), None = sharp (0); view_id (n,) int, the plan's viewpoint of each view
    when the path flies its viewpoints in another order or has views inserted
    (:attr:`wrp_eval.planning.path.FlightPath.view_id`), None = its planned_index.
    Views never taken (a failed flight) are simply absent. Every field after ``planned_index`` has a default.
    """

    positions: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    planned_index: np.ndarray
    camera: Camera = Camera()
    roll: np.ndarray | None = None
    prior_positions: np.ndarray | None = None
    blur_px: np.ndarray | None = None
    view_id: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.positions.shape[0])

    def rotations(self) -> np.ndarray:
        """World-from-camera rotations (n, 3, 3) of the views, roll included."""
        return camera_rotations(self.yaw, self.pitch, self.roll)

    def position_priors(self) -> np.ndarray:
        """(n, 3) m: the recorded (navigation) positions, or the true ones where none were recorded."""
        return np.asarray(self.positions if self.prior_positions is None else self.prior_positions, dtype=float)

    def blur(self) -> np.ndarray:
        """(n,) px: the recorded motion blur, 0 where none was recorded."""
        return np.zeros(len(self)) if self.blur_px is None else np.asarray(self.blur_px, dtype=float)

    def view_ids(self) -> np.ndarray:
        """(n,) int: the plan's viewpoint of each view (:attr:`view_id`, else planned_index): what the oracle keys
        each view's random draws by."""
        return np.asarray(self.planned_index if self.view_id is None else self.view_id, dtype=int)

    def subset(self, keep: np.ndarray) -> CaptureSet:
        """The views selected by ``keep`` (boolean mask (n,) or indices), every field carried along."""
        def part(values: np.ndarray | None) -> np.ndarray | None:
            return None if values is None else np.asarray(values)[keep]
        return CaptureSet(self.positions[keep], self.yaw[keep], self.pitch[keep], self.planned_index[keep],
                          self.camera, part(self.roll), part(self.prior_positions), part(self.blur_px),
                          part(self.view_id))


def pose_columns(capture_sets: Sequence[CaptureSet], n_views: int) -> dict[str, np.ndarray]:
    """Per trial x view columns (flattened, trial-major, NaN where a view was not taken) of the poses in
    ``capture_sets`` (one per trial): x_m, y_m, z_m, yaw_deg, pitch_deg, and ``roll_deg`` / ``prior_*_m``
    / ``blur_px`` when any capture set has a roll / position priors / blur (a set without them writes 0 / its
    true positions / 0, what None means). The layout of ``captures.parquet``; :mod:`wrp_eval.recon.capture_io`
    reads it back."""
    b = len(capture_sets)
    pos = np.full((b, n_views, 3), np.nan)
    ang = np.full((b, n_views, 3), np.nan)  # yaw, pitch, roll
    prior = np.full((b, n_views, 3), np.nan)
    blur = np.full((b, n_views), np.nan)
    for i, cs in enumerate(capture_sets):  # one row per trial (a handful of arrays each), not per time step
        idx = np.asarray(cs.planned_index, dtype=int)
        pos[i, idx] = cs.positions
        ang[i, idx] = np.column_stack([cs.yaw, cs.pitch, np.zeros(len(cs)) if cs.roll is None else cs.roll])
        prior[i, idx] = cs.position_priors()
        blur[i, idx] = cs.blur()
    cols = {"x_m": pos[..., 0].ravel(), "y_m": pos[..., 1].ravel(), "z_m": pos[..., 2].ravel(),
            "yaw_deg": np.degrees(ang[..., 0]).ravel(), "pitch_deg": np.degrees(ang[..., 1]).ravel()}
    if any(cs.roll is not None for cs in capture_sets):
        cols[ROLL_COLUMN] = np.degrees(ang[..., 2]).ravel()
    if any(cs.prior_positions is not None for cs in capture_sets):
        cols.update({name: prior[..., k].ravel() for k, name in enumerate(PRIOR_COLUMNS)})
    if any(cs.blur_px is not None for cs in capture_sets):
        cols[BLUR_COLUMN] = blur.ravel()
    return cols
