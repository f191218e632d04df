"""Capture sets: where the camera really was at each photo, the value type the simulator hands the oracle."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.camera import Camera


@dataclass(frozen=True)
class CaptureSet:
    """Camera poses actually flown for one trial.

    positions (n, 3) m; yaw (n,) rad (follows the airframe); pitch (n,) rad (gimbal-stabilised, so the
    planned pitch unless the gimbal range was exceeded); planned_index (n,) int, the path viewpoint each
    capture belongs to. Views never taken (a failed flight) are simply absent.
    """

    positions: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    planned_index: np.ndarray
    camera: Camera = Camera()

    def __len__(self) -> int:
        return int(self.positions.shape[0])
