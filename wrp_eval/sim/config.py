"""The ``sim:`` section of the experiment config (all values SI; angles in degrees at this edge)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from wrp_eval.validation import StrictModel


class SimSection(StrictModel):
    """Simulator settings. Defaults: 5 ms physics step (attitude loop 200 Hz inside MuJoCo), position loop,
    wind and drag every 10 steps (20 Hz)."""

    timestep_s: float = Field(0.005, gt=0.0, le=0.02, description="MuJoCo physics step (the attitude loop "
                                                                  "runs inside MuJoCo at this rate)")
    chunk_steps: int = Field(10, ge=1, le=50,
                             description="physics steps per mujoco.rollout call; the position loop, wind and "
                                         "drag are held over a chunk (position-loop rate = "
                                         "1/(chunk_steps*timestep_s))")
    drones_per_model: int = Field(4, ge=1, le=64,
                                  description="quadrotors per MuJoCo model; a batch of flights is split "
                                              "into ceil(batch/drones_per_model) rollouts")
    threads: int = Field(0, ge=0, description="mujoco.rollout threads (0: all CPUs)")
    prefetch_wind: bool = Field(True, description="sample the next chunk's wind (at the positions predicted "
                                                   "for the chunk's end) while the rollout runs")
    gains: Literal["default", "soft", "stiff"] = Field("default", description="controller gain preset")
    drag_coefficient: float = Field(1.0, gt=0.0, le=3.0, description="C_d of the windward area")
    air_density_kg_m3: float = Field(1.225, gt=0.0, le=2.0, description="rho (ISA sea level)")
    acceleration_m_s2: float = Field(2.5, gt=0.0, le=10.0, description="reference accel/decel along a segment")
    jerk_m_s3: float | None = Field(4.0, gt=0.0, description="jerk limit of the reference (PX4 MPC_JERK_AUTO "
                                                            "default 4); None: plain trapezoid")
    settle_position_m: float = Field(0.5, gt=0.0, description="settled when within this of the viewpoint "
                                                                "(a waypoint's acceptance radius)")
    settle_speed_m_s: float = Field(0.5, gt=0.0, description="... slower than this")
    settle_yaw_deg: float = Field(5.0, gt=0.0, description="... and yaw within this")
    settle_timeout_s: float = Field(4.0, gt=0.0,
                                    description="take the photo anyway after this long trying to settle "
                                                "(what a waypoint mission does in gusts)")
    dwell_s: float | None = Field(None, ge=0.0, description="hover before each photo; None: the path's dwell")
    fail_distance_m: float = Field(5.0, gt=0.0, description="lost position: farther than this from the "
                                                               "reference ...")
    fail_time_s: float = Field(3.0, gt=0.0, description="... for longer than this -> failed flight")
    leash_m: float = Field(2.0, gt=0.0, description="in transit the reference waits while the vehicle is "
                                                    "farther than this behind it (head wind)")
    stall_time_s: float = Field(20.0, gt=0.0, description="held back by the leash for longer than this -> "
                                                          "failed flight (no headway against the wind)")
    record_interval_s: float = Field(0.2, gt=0.0, description="trajectory down-sampling interval")
    max_flight_time_s: float = Field(3600.0, gt=0.0, description="abort a flight after this (failed)")
