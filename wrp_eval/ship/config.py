"""The ``ship:`` section of an experiment config."""

from __future__ import annotations

from pydantic import Field

from wrp_eval.ship.particulars import ShipType
from wrp_eval.validation import StrictModel


class ShipSection(StrictModel):
    """Which ship, and any particulars that override the type's defaults or the AIS data."""

    type: ShipType = Field(ShipType.STYLIZED, description="procedural ship family")
    no_fly_margin_m: float | None = Field(None, ge=0, description="override of the per-type margin r")
