"""``wrp-eval ship CONFIG``: particulars, proxy and per-face surface complexity of the configured ship."""

from __future__ import annotations

import argparse
import json

from wrp_eval.experiment import ExperimentContext
from wrp_eval.ship.rerun_log import save_ship_recording


def _ship(args: argparse.Namespace) -> int:
    ship = ExperimentContext.load(args.config).ship
    report = ship.report()
    if args.rerun:
        save_ship_recording(ship, args.rerun)
    if args.json:
        print(json.dumps(report, indent=1))
        return 0
    p = report["particulars"]
    print(f"{p['ship_type']} ship {p['name']!r}: L={p['length_bp_m']:.1f} m, B={p['breadth_m']:.1f} m, "
          f"D={p['depth_m']:.2f} m, T={p['draft_m']:.2f} m, H={p['superstructure_height_m']:.2f} m "
          f"(derived: {', '.join(p['derived']) or 'none'})")
    print(f"proxy {ship.proxy.length_m:.1f} x {ship.proxy.breadth_m:.1f} x {ship.proxy.height_m:.2f} m, "
          f"no-fly margin {ship.proxy.no_fly_margin_m:g} m; mesh {report['mesh']['triangles']} triangles")
    for name, entry in report["complexity"].items():
        print(f"  {name:10s} area {entry['area_m2']:9.1f} m2  triangles {entry['triangles']:6d}  "
              f"complexity {entry['complexity_per_m2']:.4f} /m2")
    if args.rerun:
        print(f"rerun recording: {args.rerun}")
    return 0


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "ship", help="ship particulars, proxy and surface complexity of a config's ship",
        description="Resolve the config's ship (AIS, overrides, type defaults), build its proxy and mesh, "
                    "and compute the per-face surface complexity (paper Sec. 3.1).")
    parser.add_argument("config", help="experiment YAML file")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    parser.add_argument("--rerun", metavar="FILE.rrd", help="also log mesh, proxy and complexity to a rerun file")
    parser.set_defaults(func=_ship)
