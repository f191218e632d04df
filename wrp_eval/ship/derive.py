"""Complete a partial set of ship particulars from per-type defaults and naval-architecture ratios.

AIS carries length (to_bow + to_stern), breadth (to_port + to_starboard) and draught, but no moulded depth
and no superstructure height (paper Sec. 3.1 needs both). The missing values are derived per ship type:

* moulded depth D from the draught T by the draught/depth ratio T/D (preliminary-design range ~0.63-0.78),
  or, when no draught is known either, from the length by the length/depth ratio L/D (range ~9.7-13.2),
  and then T = (T/D) * D. Ranges as in the project issue; they agree with the main-dimension statistics of
  preliminary ship design (e.g. D. G. M. Watson, *Practical Ship Design*, 1998, ch. 3; A. Papanikolaou,
  *Ship Design: Methodologies of Preliminary Design*, 2014, sec. 3.2: deep-loaded tankers/bulkers have the
  largest T/D, volume carriers such as container and passenger ships the smallest).
* superstructure height H (main deck to the highest point the UAV must clear: bridge, funnel, mast) as a
  fraction of L. No standard source gives this; the fractions below are our estimates from typical ships of
  each family (e.g. a 250 m cruise ship ~45 m above the waterline, a 300 m container ship ~35 m). Override
  them in the config when the real value is known.

The per-type default length and breadth are typical ships of the family; the stylized ship reproduces the
paper's reference ship: 140 m x 20 m and 25 m above the waterline (T/D = 2/3, L/D = 11.67, H = 0.15 L
gives D = 12 m, T = 8 m, freeboard 4 m, superstructure 21 m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from wrp_eval.errors import InputError
from wrp_eval.ship.particulars import ShipParticulars, ShipType

DIMENSION_FIELDS = ("length_bp_m", "breadth_m", "depth_m", "superstructure_height_m", "draft_m")
POSITION_FIELDS = ("lat_deg", "lon_deg", "heading_deg")


@dataclass(frozen=True)
class TypeRatios:
    """Per-type design ratios and default main dimensions (metres)."""

    draft_over_depth: float          # T/D
    length_over_depth: float         # L/D
    superstructure_over_length: float  # H/L (our estimate, see module docstring)
    default_length_m: float
    default_breadth_m: float


TYPE_RATIOS: dict[ShipType, TypeRatios] = {
    ShipType.STYLIZED: TypeRatios(2.0 / 3.0, 140.0 / 12.0, 0.15, 140.0, 20.0),
    ShipType.CRUISE: TypeRatios(0.63, 13.2, 0.16, 250.0, 32.0),
    ShipType.CONTAINER: TypeRatios(0.63, 12.5, 0.085, 300.0, 48.0),
    ShipType.FISHING: TypeRatios(0.70, 9.7, 0.25, 40.0, 9.0),
    ShipType.TANKER: TypeRatios(0.78, 11.5, 0.07, 240.0, 42.0),
}


def ship_type_from_ais_code(code: int | None) -> ShipType | None:
    """Map an AIS "type of ship and cargo" code (ITU-R M.1371, table 53) to our families.

    30 fishing; 60-69 passenger -> cruise; 70-79 cargo -> container; 80-89 tanker -> tanker/bulk.
    Every other code (tugs, pilot, SAR, pleasure craft, "other", 0 = not available) has no family: None.
    """
    if code is None:
        return None
    code = int(code)
    if code == 30:
        return ShipType.FISHING
    if 60 <= code <= 69:
        return ShipType.CRUISE
    if 70 <= code <= 79:
        return ShipType.CONTAINER
    if 80 <= code <= 89:
        return ShipType.TANKER
    return None


def complete_particulars(ship_type: ShipType, known: dict[str, float], source: str,
                         given_by: dict[str, str] | None = None, name: str = "",
                         mmsi: int | None = None) -> tuple[ShipParticulars, dict[str, str]]:
    """Fill the missing fields of ``known`` and validate the result.

    known: any of DIMENSION_FIELDS and POSITION_FIELDS (metres, degrees) that were given;
    given_by: field -> where it came from ("ais", "config"); default "config".
    Returns the particulars and a provenance map field -> "ais" | "config" | "type default" | "derived: ...".
    ``ShipParticulars.derived`` names every dimension not given (type default or ratio) and ``ship_type``
    when the type was not given. Raises :class:`InputError` naming ``source`` for impossible values.
    """
    given_by = dict(given_by or {})
    ratios = TYPE_RATIOS[ship_type]
    values = dict(known)
    provenance = {k: given_by.get(k, "config") for k in known}
    for key in ("length_bp_m", "breadth_m"):
        if key not in values:
            values[key] = ratios.default_length_m if key == "length_bp_m" else ratios.default_breadth_m
            provenance[key] = "type default"
    if "depth_m" not in values:
        if "draft_m" in values:
            values["depth_m"] = values["draft_m"] / ratios.draft_over_depth
            provenance["depth_m"] = f"derived: draft / (T/D = {ratios.draft_over_depth:.3g})"
        else:
            values["depth_m"] = values["length_bp_m"] / ratios.length_over_depth
            provenance["depth_m"] = f"derived: length / (L/D = {ratios.length_over_depth:.4g})"
    if "draft_m" not in values:
        values["draft_m"] = values["depth_m"] * ratios.draft_over_depth
        provenance["draft_m"] = f"derived: depth * (T/D = {ratios.draft_over_depth:.3g})"
    if "superstructure_height_m" not in values:
        values["superstructure_height_m"] = values["length_bp_m"] * ratios.superstructure_over_length
        provenance["superstructure_height_m"] = (
            f"derived: length * (H/L = {ratios.superstructure_over_length:.3g})")
    for key in POSITION_FIELDS:
        if key not in values:
            values[key] = 0.0
            provenance[key] = "default (unknown)"
    derived = {k for k in DIMENSION_FIELDS if provenance[k] not in ("ais", "config")}
    if given_by.get("ship_type") is None:
        derived.add("ship_type")
    particulars = ShipParticulars(
        length_bp_m=float(values["length_bp_m"]), breadth_m=float(values["breadth_m"]),
        depth_m=float(values["depth_m"]), superstructure_height_m=float(values["superstructure_height_m"]),
        draft_m=float(values["draft_m"]), ship_type=ship_type, lat_deg=float(values["lat_deg"]),
        lon_deg=float(values["lon_deg"]), heading_deg=float(values["heading_deg"]) % 360.0,
        name=name, mmsi=mmsi, derived=frozenset(derived))
    check_particulars(particulars, source, provenance)
    return particulars, provenance


def check_particulars(p: ShipParticulars, source: str, provenance: dict[str, str] | None = None) -> None:
    """Raise :class:`InputError` for impossible particulars (non-finite, non-positive, draft >= depth, ...)."""
    provenance = provenance or {}

    def where(key: str) -> str:
        return f"{key} ({provenance[key]})" if key in provenance else key

    for key in DIMENSION_FIELDS:
        value = getattr(p, key)
        if not math.isfinite(value) or value <= 0:
            raise InputError(source, f"{where(key)} must be a positive finite number of metres, got {value}")
    if p.draft_m >= p.depth_m:
        raise InputError(source, f"draft {p.draft_m:.3g} m must be less than the moulded depth "
                                 f"{p.depth_m:.3g} m (the hull would be under water): check "
                                 f"{where('draft_m')} and {where('depth_m')}")
    if p.breadth_m > p.length_bp_m:
        raise InputError(source, f"breadth {p.breadth_m:.3g} m exceeds length {p.length_bp_m:.3g} m")
    if not (math.isfinite(p.lat_deg) and -90.0 <= p.lat_deg <= 90.0):
        raise InputError(source, f"latitude {p.lat_deg} is outside [-90, 90] degrees")
    if not (math.isfinite(p.lon_deg) and -180.0 <= p.lon_deg <= 180.0):
        raise InputError(source, f"longitude {p.lon_deg} is outside [-180, 180] degrees")
    if not math.isfinite(p.heading_deg):
        raise InputError(source, f"heading {p.heading_deg} is not finite")
