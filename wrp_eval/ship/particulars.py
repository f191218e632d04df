"""Ship particulars: the main dimensions a cuboid proxy is built from (paper Sec. 3.1, Fig. 2)."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum


class ShipType(str, Enum):
    """Ship families with their own procedural mesh, derived-dimension ratios and no-fly margin."""

    STYLIZED = "stylized"    # the paper's reference ship, 140 m x 20 m x 25 m above the waterline
    CRUISE = "cruise"
    CONTAINER = "container"
    FISHING = "fishing"
    TANKER = "tanker"        # tanker / bulk carrier


@dataclass(frozen=True)
class ShipParticulars:
    """Main dimensions in metres, position in degrees.

    length_bp_m: length between perpendiculars; breadth_m: moulded breadth; depth_m: moulded depth
    (keel to main deck); superstructure_height_m: from the main deck to the top of the superstructure;
    draft_m: current draught. ``derived`` names the fields that were not given but derived from the ship
    type (AIS carries no depth or superstructure height).
    """

    length_bp_m: float
    breadth_m: float
    depth_m: float
    superstructure_height_m: float
    draft_m: float
    ship_type: ShipType = ShipType.STYLIZED
    lat_deg: float = 0.0
    lon_deg: float = 0.0
    heading_deg: float = 0.0
    name: str = ""
    mmsi: int | None = None
    derived: frozenset[str] = field(default_factory=frozenset)

    @property
    def freeboard_m(self) -> float:
        """Hull height above the waterline (depth - draft)."""
        return self.depth_m - self.draft_m

    @property
    def height_above_water_m(self) -> float:
        """Height of the proxy: freeboard plus superstructure."""
        return self.freeboard_m + self.superstructure_height_m
