"""The camera gimbal: three axes with mechanical limits, a rate limit and a finite bandwidth, batch-first.

Model (per flight, advanced once per position-loop chunk, 20 Hz by default):

* DJI "follow" mode (DJI Onboard SDK, ``Gimbal::AngleData``: roll and pitch are held against the ground,
  yaw follows the aircraft's heading): the camera's world pitch is commanded to the view's planned pitch,
  its world roll to 0, its yaw is the airframe's heading.
* Each stabilised axis's joint angle (relative to the airframe) follows its target ``wanted - body angle``
  as a first-order loop of bandwidth ``bandwidth_hz`` (exact discretisation over the chunk: gain
  1 - exp(-2 pi f dt)), limited to ``rate_limit_deg_s`` and clipped to the mechanical range
  (``pitch_range_deg`` -90..+30 and ``roll_range_deg`` -35..+35: the DJI Onboard SDK's gimbal angle input
  ranges, [-900, 300] and [-350, 350] in 0.1 deg; Phantom 4 spec sheet: pitch -90..+30 deg, max
  controllable angular speed 90 deg/s).
* What the gimbal does not cancel reaches the camera: the lag of the loop, the rate limit, a saturated joint.
  The camera's world pitch and roll are the airframe's angles plus the joints'; the residual roll is the
  camera's world roll (wanted: 0).

The airframe's angles are the elevation of its nose (x axis) and of its left wing (y axis) above the
horizontal, which the gimbal's pitch and roll joints cancel for the tilts a quadrotor flies (< 35 deg).
Resolution: the loop sees the airframe at the chunk rate; motion faster than that (propeller vibration:
the Phantom 4's spec gives an angular vibration range of +-0.02 deg) is not modelled.
The bandwidth is assumed (10 Hz: brushless camera gimbals stabilise with loops of tens of Hz; no DJI
figure is published).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from wrp_eval.compiled import as_rows, kernel
from wrp_eval.schema import StrictModel


class GimbalSection(StrictModel):
    """The ``sim.gimbal`` section (degrees and hertz at this edge)."""

    pitch_range_deg: tuple[float, float] = Field((-90.0, 30.0), description="mechanical pitch range of the camera "
                                                 "against the airframe (Phantom 4: -90..+30)")
    roll_range_deg: tuple[float, float] = Field((-35.0, 35.0), description="roll joint range (DJI OSDK: +-35)")
    rate_limit_deg_s: float = Field(90.0, gt=0.0, description="max joint rate (Phantom 4: 90 deg/s pitch)")
    bandwidth_hz: float = Field(10.0, gt=0.0, description="first-order stabilisation loop bandwidth (assumed)")

    @model_validator(mode="after")
    def _ordered(self) -> GimbalSection:
        for name in ("pitch_range_deg", "roll_range_deg"):
            lo, hi = getattr(self, name)
            if not hi > lo:
                raise ValueError(f"sim.gimbal.{name} needs [low, high] with high > low, got [{lo}, {hi}]")
        return self


@dataclass(frozen=True)
class GimbalParams:
    """Resolved gimbal settings, radians and seconds: pitch_range, roll_range (2,) rad; rate_limit rad/s;
    bandwidth rad/s."""

    pitch_range: np.ndarray
    roll_range: np.ndarray
    rate_limit: float
    bandwidth: float

    @classmethod
    def of(cls, section: GimbalSection) -> GimbalParams:
        return cls(np.radians(section.pitch_range_deg), np.radians(section.roll_range_deg),
                   float(np.radians(section.rate_limit_deg_s)), 2.0 * np.pi * section.bandwidth_hz)


class CameraAttitude(NamedTuple):
    """The camera's world attitude, (n,) rad each: yaw (the airframe's heading), pitch above the horizontal,
    roll (the residual roll); saturated (n,) bool: a joint at its mechanical stop."""

    yaw: np.ndarray
    pitch: np.ndarray
    roll: np.ndarray
    saturated: np.ndarray


@kernel
def _airframe_row(rot: NDArray[np.float64]) -> tuple[float, float]:
    """(nose elevation, wing elevation) rad of one airframe ``rot`` (3, 3) world from body."""
    nose = np.arcsin(np.minimum(np.maximum(rot[2, 0], -1.0), 1.0))
    return nose, np.arcsin(np.minimum(np.maximum(rot[2, 1], -1.0), 1.0))


@kernel
def _airframe_rows(rot: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.empty((2, rot.shape[0]))
    for row in range(rot.shape[0]):
        out[0, row], out[1, row] = _airframe_row(rot[row])
    return out


def airframe_angles(rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(nose elevation, wing elevation) (n,) rad of airframes ``rot`` (n, 3, 3) world from body."""
    nose, wing = _airframe_rows(np.asarray(rot, dtype=float))
    return nose, wing


# what _gimbal_rows does to the joints: leave them, move them one chunk, or put them on their (limited) targets
_HOLD, _ADVANCE, _SETTLE = 0, 1, 2


@kernel
def _gimbal_rows(rot: NDArray[np.float64], wanted_pitch: NDArray[np.float64], joint: NDArray[np.float64], mode: int,
                 gain: float, max_step: float, pitch_range: NDArray[np.float64], roll_range: NDArray[np.float64],
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Cameras' (pitch, roll) (n,) rad and saturated (n,) bool for airframes ``rot`` (n, 3, 3) and wanted pitches
    (n,); ``joint`` (n, 2) (pitch, roll) is updated in place as ``mode`` says. A joint's target compensates the
    airframe's nose / wing elevation; a move is first order (``gain``) within the rate limit (``max_step``)."""
    n = rot.shape[0]
    pitch, roll, saturated = np.empty(n), np.empty(n), np.zeros(n, np.bool_)
    lo = (pitch_range[0], roll_range[0])
    hi = (pitch_range[1], roll_range[1])
    for row in range(n):
        nose, wing = _airframe_row(rot[row])
        target = (wanted_pitch[row] - nose, -wing)
        for k in range(2):
            limited = np.minimum(np.maximum(target[k], lo[k]), hi[k])
            if mode == _SETTLE:
                joint[row, k] = limited
            elif mode == _ADVANCE:
                move = np.minimum(np.maximum(gain * (target[k] - joint[row, k]), -max_step), max_step)
                joint[row, k] = np.minimum(np.maximum(joint[row, k] + move, lo[k]), hi[k])
            saturated[row] |= abs(limited - target[k]) > 1e-12
        pitch[row], roll[row] = nose + joint[row, 0], wing + joint[row, 1]
    return pitch, roll, saturated


class Gimbal:
    """Joint angles (n, 2) (pitch, roll) of a batch of gimbals; :meth:`step` advances them one chunk."""

    def __init__(self, params: GimbalParams, rot: np.ndarray, wanted_pitch: np.ndarray, dt_s: float):
        """Start settled on ``wanted_pitch`` (n,) rad with the airframes at ``rot`` (n, 3, 3)."""
        self.params = params
        self.gain = 1.0 - np.exp(-params.bandwidth * dt_s)
        self.max_step = params.rate_limit * dt_s
        self.joint = np.zeros((len(rot), 2))
        self._move(rot, wanted_pitch, _SETTLE)

    def _move(self, rot: np.ndarray, wanted_pitch: np.ndarray,
              mode: int) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
        p = self.params
        n = len(self.joint)
        return _gimbal_rows(as_rows("rot", rot, (n, 3, 3)), as_rows("wanted_pitch", wanted_pitch, (n,)), self.joint,
                            mode, float(self.gain), float(self.max_step), np.asarray(p.pitch_range, dtype=float),
                            np.asarray(p.roll_range, dtype=float))

    def step(self, rot: np.ndarray, yaw: np.ndarray, wanted_pitch: np.ndarray, advance: bool = True) -> CameraAttitude:
        """The cameras' world attitude for airframes ``rot`` (n, 3, 3) with headings ``yaw`` (n,) rad, after
        moving every joint one chunk towards its target (``advance``; False: as they are); saturated where a
        joint's target lies beyond its stop."""
        pitch, roll, saturated = self._move(rot, wanted_pitch, _ADVANCE if advance else _HOLD)
        return CameraAttitude(yaw, pitch, roll, saturated)
