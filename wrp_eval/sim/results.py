"""Value types the simulator hands on: per-flight captures, offsets, failures and trajectories."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.sim.captures import CaptureSet


@dataclass(frozen=True)
class Trajectory:
    """Down-sampled flight records. time (T,) s; the rest batch-first (batch, T, ...).

    position (batch, T, 3) m of the body centre of mass; reference (batch, T, 3) m; yaw (batch, T) rad;
    tilt (batch, T) rad; thrust (batch, T) N (sum of the four motors); wind (batch, T, 3) m/s at the vehicle;
    drag (batch, T, 3) N.
    """

    time: np.ndarray
    position: np.ndarray
    reference: np.ndarray
    yaw: np.ndarray
    tilt: np.ndarray
    thrust: np.ndarray
    wind: np.ndarray
    drag: np.ndarray


@dataclass(frozen=True)
class FlightResult:
    """A batch of flights of one path.

    captures: one :class:`CaptureSet` per flight (views not taken are absent).
    offsets (batch, n_views, 4): actual camera pose minus the plan, (dx, dy, dz) m and dyaw rad;
    NaN where the view was not taken. taken (batch, n_views) bool; capture_time_s (batch, n_views);
    camera_pitch (batch, n_views) rad actually achieved by the gimbal; residual_roll (batch, n_views) rad the
    gimbal could not compensate; gimbal_saturated (batch, n_views) bool.
    failed (batch,) bool with failure_reason (batch,) str ("" when the flight completed);
    flight_time_s (batch,): time of the last photo (or of the failure).
    """

    captures: tuple[CaptureSet, ...]
    offsets: np.ndarray
    taken: np.ndarray
    capture_time_s: np.ndarray
    camera_pitch: np.ndarray
    residual_roll: np.ndarray
    gimbal_saturated: np.ndarray
    failed: np.ndarray
    failure_reason: tuple[str, ...]
    flight_time_s: np.ndarray
    trajectory: Trajectory
    timestep_s: float
    chunk_steps: int

    @property
    def batch(self) -> int:
        return int(self.offsets.shape[0])

    @property
    def n_views(self) -> int:
        return int(self.offsets.shape[1])
