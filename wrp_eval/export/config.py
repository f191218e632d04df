"""The ``export:`` section of an experiment config.

```yaml
export:
  min_altitude_m: 5            # refuse waypoints lower than this above the sea surface
  home_m: [-50, 0, 12]         # take-off / home point in the ship frame (default: main deck amidships)
  gimbal_pitch_range_deg: [-90, 30]
  firmware: px4                # QGroundControl .plan firmwareType: px4 | ardupilot
```
The ship's position and heading come from the ``ship:`` section (AIS position report or
``ship.particulars.lat_deg / lon_deg / heading_deg``).
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from wrp_eval.schema import StrictModel

_FINITE: dict[str, Any] = {"allow_inf_nan": False}


class ExportSection(StrictModel):
    """How a ship-frame path becomes geographic waypoint missions."""

    min_altitude_m: float = Field(5.0, gt=0, le=500, description="minimum waypoint height above the sea",
                                  **_FINITE)
    home_m: tuple[float, float, float] | None = Field(
        None, description="take-off/home point (x bow, y port, z up) in metres in the ship frame; "
                          "default: main deck amidships (0, 0, freeboard)")
    gimbal_pitch_range_deg: tuple[float, float] = Field((-90.0, 30.0),
                                                        description="pitch limits of the gimbal, degrees")
    firmware: Literal["px4", "ardupilot"] = Field("px4", description="autopilot named in the QGC .plan")

    @model_validator(mode="after")
    def _consistent(self) -> ExportSection:
        if self.home_m is not None and not all(abs(v) < 1e4 for v in self.home_m):
            raise ValueError("home_m must be three finite numbers of metres (|v| < 1e4)")
        lo, hi = self.gimbal_pitch_range_deg
        if not (-180.0 <= lo < hi <= 180.0):
            raise ValueError(f"gimbal_pitch_range_deg must be [low, high] with -180 <= low < high <= 180, "
                             f"got {list(self.gimbal_pitch_range_deg)}")
        return self
