"""``wrp-eval export DIR/path.json --format FORMAT --out FILE [--config CONFIG]``: flyable missions."""

from __future__ import annotations

import argparse
from pathlib import Path

from wrp_eval.config import ExperimentConfig
from wrp_eval.experiment import ExperimentContext
from wrp_eval.export.formats import FORMATS, export_path
from wrp_eval.export.mission import FlightStyle
from wrp_eval.planning.path import FlightPath

POSITION_FIELDS = ("lat_deg", "lon_deg", "heading_deg")


def _export(args: argparse.Namespace) -> int:
    ctx = (ExperimentContext.load(args.config) if args.config
           else ExperimentContext(ExperimentConfig(), Path("."), "embedded defaults"))
    path = FlightPath.load(args.path)
    # Only the particulars (position, heading, dimensions) and the proxy are needed: no mesh is built.
    particulars, provenance = ctx.particulars_with_provenance
    unknown = [k for k in POSITION_FIELDS if provenance.get(k, "").startswith("default")]
    sim = ctx.config.sim
    # the mission is flown as the simulator flies it: sim.capture.mode / heading_mode, sim.dwell_s, the path's speed
    style = FlightStyle.of(path, sim.capture, sim.dwell_s)
    written = export_path(path, particulars, ctx.flight_proxy, args.format, args.out, ctx.config.export, str(args.path),
                          style)
    print(f"ship at {particulars.lat_deg:.6f}, {particulars.lon_deg:.6f}, heading {particulars.heading_deg:.1f} deg; "
          f"altitudes relative to the take-off point ({written[0][1].home_alt_m:.2f} m above the sea)")
    if unknown:
        print(f"warning: ship {', '.join(unknown)} not given (ship.particulars or an AIS position report in "
              f"{ctx.source}): the default 0 was used, so these waypoints are not where the ship is")
    print(f"capture mode {style.mode} (sim.capture.mode), heading {style.heading_mode}, hold {style.hold_s:g} s, "
          f"speed {style.speed_m_s:g} m/s")
    if path.capture is not None:
        stops = int(path.stops(style.mode).sum())
        print(f"per-view capture modes from the path: {stops} stop, {len(path) - stops} fly-through")
    if path.leg_speed_m_s is not None:
        legs = path.leg_speeds()
        print(f"speeds per leg from the path: {int((legs != style.speed_m_s).sum())} of {legs.size} legs at their "
              f"own speed ({legs.min():g} - {legs.max():g} m/s)")
    for file, mission in written:
        print(f"sortie {mission.sortie}: {len(mission)} waypoints -> {file}")
    return 0


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "export", help="export a planned path as drone missions (QGC .plan / WPL, DJI WPML KMZ, Litchi CSV)",
        description="Turn a path.json (ship frame) into geographic waypoint missions using the ship's position "
                    "and heading from the config (AIS or ship.particulars). One file per sortie: FILE, or "
                    "FILE_sortie<k>.ext when the path has several sorties. The config's sim.capture.mode (stop | "
                    "fly-through), sim.capture.heading_mode and sim.dwell_s say how it is flown, as in the "
                    "simulator. Waypoints below "
                    "export.min_altitude_m or inside the no-fly zone are refused (exit 2).")
    parser.add_argument("path", help="path.json written by `wrp-eval plan`")
    parser.add_argument("--format", required=True, choices=sorted(FORMATS), help="mission file format")
    parser.add_argument("--out", required=True, help="output file (sorties add _sortie<k> before the extension)")
    parser.add_argument("--config", help="experiment YAML giving the ship and the export section "
                                         "(default: the embedded defaults)")
    parser.set_defaults(func=_export)
