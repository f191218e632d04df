"""The ``sim:`` section of the experiment config (all values SI; angles in degrees at this edge)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from wrp_eval.schema import StrictModel
from wrp_eval.sim.capture_mode import CaptureSection
from wrp_eval.sim.gimbal import GimbalSection
from wrp_eval.sim.mission import MissionSection
from wrp_eval.sim.navigation import NavigationSection
from wrp_eval.sim.power import BatterySection


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
    leash_m: float = Field(2.0, gt=0.0, description="in transit the reference waits while the vehicle is "
                                                    "farther than this behind it (head wind)")
    record_interval_s: float = Field(0.2, gt=0.0, description="trajectory down-sampling interval")
    max_flight_time_s: float = Field(3600.0, gt=0.0, description="the simulator's own limit: a sortie still "
                                                                 "flying after this long has failed (timed out)")
    navigation: NavigationSection = NavigationSection()
    gimbal: GimbalSection = GimbalSection()
    capture: CaptureSection = CaptureSection()
    battery: BatterySection = BatterySection()
    mission: MissionSection = MissionSection()

    @model_validator(mode="before")
    @classmethod
    def _old_wind_rule(cls, data: Any) -> Any:
        """Configs and stored campaigns from before ``sim.mission`` say ``wind_limit_m_s`` / ``wind_average_s``
        (a 30 s average over 10 m/s sent the vehicle home): read them as the operator policy they were."""
        if not isinstance(data, dict) or not ({"wind_limit_m_s", "wind_average_s"} & data.keys()):
            return data
        data = dict(data)
        mission = data.get("mission") or {}
        mission = mission.model_dump(exclude_unset=True) if isinstance(mission, StrictModel) else dict(mission)
        if "wind_limit_m_s" in data:
            mission.setdefault("operator_wind_limit_m_s", data.pop("wind_limit_m_s"))
        if "wind_average_s" in data:
            mission.setdefault("operator_wind_average_s", data.pop("wind_average_s"))
        data["mission"] = mission
        return data
