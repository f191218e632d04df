"""Value types the simulator hands on: per-flight captures, offsets, failures and trajectories."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from wrp_eval.sim.captures import CaptureSet


@dataclass(frozen=True)
class Trajectory:
    """Down-sampled flight records. time (T,) s; the rest batch-first (batch, T, ...).

    position (batch, T, 3) m of the body centre of mass; reference (batch, T, 3) m; yaw (batch, T) rad;
    tilt (batch, T) rad; thrust (batch, T) N (sum of the four motors); wind (batch, T, 3) m/s at the vehicle;
    drag (batch, T, 3) N; power (batch, T) W electrical; charge (batch, T) battery fraction left.
    """

    time: np.ndarray
    position: np.ndarray
    reference: np.ndarray
    yaw: np.ndarray
    tilt: np.ndarray
    thrust: np.ndarray
    wind: np.ndarray
    drag: np.ndarray
    power: np.ndarray
    charge: np.ndarray


@dataclass(frozen=True)
class FlightResult:
    """A batch of flights of one path.

    captures: one :class:`CaptureSet` per flight (views not taken are absent), with roll and the navigation's
    positions as priors. Per view (batch, n_views, ...), NaN (False) where the view was not taken:
    offsets (batch, n_views, 4): true camera pose in the ship's frame at the shutter minus the plan,
    (dx, dy, dz) m and dyaw rad; estimated_offsets: the navigation's record of it minus the plan;
    taken bool; capture_time_s; camera_pitch, camera_roll rad (the gimbal's result); gimbal_saturated bool;
    blur_px (motion blur during the exposure); battery_charge (fraction left at the shutter); ship_motion
    (batch, n_views, 4): heave m, roll, pitch, yaw rad of the ship at the shutter.
    outcome (batch,) int (:mod:`wrp_eval.sim.flight_state` codes) with outcome_reason (batch,) str ("" when
    the flight completed); failed (batch,) bool: crashed or timed out (a flight that turned home early on
    its battery or wind limit did not fail: its remaining views are simply not taken);
    flight_time_s (batch,): time of the last photo (or of the end): the mission time, battery swaps included.
    sorties (batch,) int: the sorties flown (a return on energy with sorties left is followed by a battery swap
    and a resumed sortie, sim/mission.py); view_sortie (batch, n_views) int: the sortie that took each view
    (0: not taken by any).
    """

    captures: tuple[CaptureSet, ...]
    offsets: np.ndarray
    estimated_offsets: np.ndarray
    taken: np.ndarray
    capture_time_s: np.ndarray
    camera_pitch: np.ndarray
    camera_roll: np.ndarray
    gimbal_saturated: np.ndarray
    blur_px: np.ndarray
    battery_charge: np.ndarray
    ship_motion: np.ndarray
    outcome: np.ndarray
    outcome_reason: tuple[str, ...]
    failed: np.ndarray
    flight_time_s: np.ndarray
    trajectory: Trajectory
    timestep_s: float
    chunk_steps: int
    sorties: np.ndarray
    view_sortie: np.ndarray

    @property
    def batch(self) -> int:
        return int(self.offsets.shape[0])

    @property
    def n_views(self) -> int:
        return int(self.offsets.shape[1])

    @property
    def views_per_sortie(self) -> np.ndarray:
        """(batch, max sorties) int: the views each sortie took."""
        top = max(int(self.sorties.max(initial=1)), 1)
        counts: NDArray[np.int_] = (self.view_sortie[:, :, None] == np.arange(1, top + 1)).sum(axis=1)
        return counts

    @property
    def failure_reason(self) -> tuple[str, ...]:
        """(batch,) the reasons of the failed flights ("" elsewhere)."""
        return tuple(r if f else "" for r, f in zip(self.outcome_reason, self.failed, strict=True))
