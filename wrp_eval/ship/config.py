"""The ``ship:`` section of an experiment config.

```yaml
ship:
  type: container              # stylized | cruise | container | fishing | tanker (default stylized)
  particulars:                 # optional overrides (metres, degrees); the rest from AIS / type defaults
    length_bp_m: 280
    draft_m: 12.5
  ais: ["!AIVDM,2,1,3,A,...", "!AIVDM,2,2,3,A,..."]   # or  ais_file: ship.nmea  (relative to the config)
  mesh: procedural             # or {path: hull.stl, scale: 0.001, up_axis: y, offset_m: [0, 0, -8]}
  no_fly_margin_m: 10          # overrides the per-type margin r
  proxy_height_error: 0.1      # the proxy 10 % taller than the ship (paper Table 1); the mesh is unchanged
```
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from wrp_eval.schema import StrictModel
from wrp_eval.ship.motion import ShipMotionSection
from wrp_eval.ship.particulars import ShipType

_METRES: dict[str, Any] = {"allow_inf_nan": False}


class ParticularsOverrides(StrictModel):
    """Values that replace the AIS data or the type defaults (metres, degrees)."""

    length_bp_m: float | None = Field(None, gt=0, le=500, description="length between perpendiculars", **_METRES)
    breadth_m: float | None = Field(None, gt=0, le=100, description="moulded breadth", **_METRES)
    depth_m: float | None = Field(None, gt=0, le=100, description="moulded depth, keel to main deck", **_METRES)
    superstructure_height_m: float | None = Field(None, gt=0, le=150, description="main deck to the top",
                                                  **_METRES)
    draft_m: float | None = Field(None, gt=0, le=40, description="current draught", **_METRES)
    lat_deg: float | None = Field(None, ge=-90, le=90, **_METRES)
    lon_deg: float | None = Field(None, ge=-180, le=180, **_METRES)
    heading_deg: float | None = Field(None, ge=0, lt=360, description="true heading, clockwise from north",
                                      **_METRES)

    @model_validator(mode="after")
    def _consistent(self) -> ParticularsOverrides:
        if self.draft_m is not None and self.depth_m is not None and self.draft_m >= self.depth_m:
            raise ValueError(f"draft_m ({self.draft_m}) must be less than depth_m ({self.depth_m})")
        if self.breadth_m is not None and self.length_bp_m is not None and self.breadth_m > self.length_bp_m:
            raise ValueError(f"breadth_m ({self.breadth_m}) exceeds length_bp_m ({self.length_bp_m})")
        return self

    def given(self) -> dict[str, float]:
        """The fields that were set."""
        return {k: v for k, v in self.model_dump().items() if v is not None}


class UserMesh(StrictModel):
    """A ship mesh file (STL, OBJ, PLY, GLB/GLTF) and how to place it in the ship frame (x bow, z up)."""

    path: str = Field(min_length=1, description="mesh file, relative to the config file")
    scale: float = Field(1.0, gt=0, le=1e4, description="multiplies the file's coordinates (e.g. 0.001 for mm)",
                         **_METRES)
    up_axis: Literal["z", "y", "x"] = Field("z", description="the file's up axis (rotated onto +z)")
    offset_m: tuple[float, float, float] = Field((0.0, 0.0, 0.0),
                                                 description="added after scaling and rotating (metres)")

    @model_validator(mode="after")
    def _finite_offset(self) -> UserMesh:
        if not all(abs(v) < 1e6 for v in self.offset_m):  # also rejects nan / inf
            raise ValueError("offset_m must be three finite numbers of metres (|v| < 1e6)")
        return self


class ShipSection(StrictModel):
    """Which ship, and any particulars that override the type's defaults or the AIS data."""

    type: ShipType = Field(ShipType.STYLIZED, description="procedural ship family")
    particulars: ParticularsOverrides = ParticularsOverrides()
    ais: list[str] | None = Field(None, min_length=1, description="raw AIS NMEA sentences (!AIVDM/!AIVDO)")
    ais_file: str | None = Field(None, min_length=1, description="file of AIS NMEA sentences, one per line")
    mesh: UserMesh | None = Field(None, description="'procedural' (None) or a user mesh file")
    no_fly_margin_m: float | None = Field(None, ge=0, le=200, description="override of the per-type margin r",
                                          **_METRES)
    proxy_height_error: float = Field(0.0, gt=-0.9, le=2.0, description="signed error of the proxy's height as a "
                                      "fraction of the true height above the waterline (paper Table 1: an unreliable "
                                      "AIS draught); the mesh (the truth) keeps its height", **_METRES)
    motion: ShipMotionSection = Field(ShipMotionSection(), description="heave, roll, pitch, yaw swing for a sea "
                                     "state; by default the sea each flight's own wind raises (from_wind); 0: a "
                                     "still ship")

    @field_validator("mesh", mode="before")
    @classmethod
    def _procedural_or_file(cls, value: Any) -> Any:
        if value is None or value == "procedural":
            return None
        if not isinstance(value, dict):
            raise ValueError("must be 'procedural' or a mapping {path, scale, up_axis, offset_m}")
        return value

    @model_validator(mode="after")
    def _one_ais_source(self) -> ShipSection:
        if self.ais is not None and self.ais_file is not None:
            raise ValueError("give either ais or ais_file, not both")
        return self

    @property
    def type_given(self) -> bool:
        """True when the config names the type (it then wins over the AIS ship-type code)."""
        return "type" in self.model_fields_set
