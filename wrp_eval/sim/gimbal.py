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
from pydantic import Field, model_validator

from wrp_eval.validation import StrictModel


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


def airframe_angles(rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(nose elevation, wing elevation) (n,) rad of airframes ``rot`` (n, 3, 3) world from body."""
    return np.arcsin(np.clip(rot[:, 2, 0], -1.0, 1.0)), np.arcsin(np.clip(rot[:, 2, 1], -1.0, 1.0))


class Gimbal:
    """Joint angles (n, 2) (pitch, roll) of a batch of gimbals; :meth:`step` advances them one chunk."""

    def __init__(self, params: GimbalParams, rot: np.ndarray, wanted_pitch: np.ndarray, dt_s: float):
        """Start settled on ``wanted_pitch`` (n,) rad with the airframes at ``rot`` (n, 3, 3)."""
        self.params = params
        self.gain = 1.0 - np.exp(-params.bandwidth * dt_s)
        self.max_step = params.rate_limit * dt_s
        nose, wing = airframe_angles(rot)
        self.joint = self._limits(self._targets(nose, wing, wanted_pitch))

    @staticmethod
    def _targets(nose: np.ndarray, wing: np.ndarray, wanted_pitch: np.ndarray) -> np.ndarray:
        return np.stack([wanted_pitch - nose, -wing], axis=1)

    def _limits(self, joint: np.ndarray) -> np.ndarray:
        p = self.params
        return np.stack([np.clip(joint[:, 0], *p.pitch_range), np.clip(joint[:, 1], *p.roll_range)], axis=1)

    def step(self, rot: np.ndarray, yaw: np.ndarray, wanted_pitch: np.ndarray, advance: bool = True) -> CameraAttitude:
        """The cameras' world attitude for airframes ``rot`` (n, 3, 3) with headings ``yaw`` (n,) rad, after
        moving every joint one chunk towards its target (``advance``; False: as they are); saturated where a
        joint's target lies beyond its stop."""
        nose, wing = airframe_angles(rot)
        target = self._targets(nose, wing, wanted_pitch)
        if advance:
            move = np.clip(self.gain * (target - self.joint), -self.max_step, self.max_step)
            self.joint = self._limits(self.joint + move)
        saturated = np.any(np.abs(self._limits(target) - target) > 1e-12, axis=1)
        return CameraAttitude(yaw, nose + self.joint[:, 0], wing + self.joint[:, 1], saturated)
