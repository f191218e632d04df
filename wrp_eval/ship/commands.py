"""``wrp-eval ship CONFIG``: particulars, proxy and per-face surface complexity of the configured ship."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from wrp_eval.ship.resolve import ResolvedShip


def ship_report(ship: ResolvedShip) -> dict:
    """The JSON document printed by ``wrp-eval ship --json``."""
    p, proxy = ship.particulars, ship.proxy
    particulars = {
        "ship_type": p.ship_type.value, "name": p.name, "mmsi": p.mmsi,
        "length_bp_m": p.length_bp_m, "breadth_m": p.breadth_m, "depth_m": p.depth_m,
        "superstructure_height_m": p.superstructure_height_m, "draft_m": p.draft_m,
        "freeboard_m": p.freeboard_m, "height_above_water_m": p.height_above_water_m,
        "lat_deg": p.lat_deg, "lon_deg": p.lon_deg, "heading_deg": p.heading_deg,
        "derived": sorted(p.derived), "provenance": ship.provenance,
    }
    faces = [{"name": name, "area_m2": float(area), "normal": proxy.normals[i].tolist(),
              "center": proxy.centers[i].tolist(), "half_extents_m": proxy.half_extents[i].tolist()}
             for i, (name, area) in enumerate(zip(proxy.face_names, proxy.areas))]
    mesh = ship.mesh
    return {
        "particulars": particulars,
        "proxy": {"length_m": proxy.length_m, "breadth_m": proxy.breadth_m, "height_m": proxy.height_m,
                  "no_fly_margin_m": proxy.no_fly_margin_m, "no_fly_bounds": proxy.no_fly_bounds().tolist(),
                  "faces": faces},
        "complexity": ship.complexity.as_dict(),
        "mesh": {"source": ship.mesh_source, "triangles": int(len(mesh.faces)),
                 "watertight": bool(mesh.is_watertight), "bounds": mesh.bounds.tolist()},
    }


def _run_ship(args: argparse.Namespace) -> int:
    from wrp_eval.config import load_experiment
    from wrp_eval.ship.resolve import resolve_ship_full

    config_path = Path(args.config)
    config = load_experiment(config_path)
    ship = resolve_ship_full(config.ship, config_path.parent, str(config_path))
    report = ship_report(ship)
    if args.rerun:
        from wrp_eval.ship.rerun_log import save_ship_recording
        save_ship_recording(ship, args.rerun)
    if args.json:
        print(json.dumps(report, indent=1))
    else:
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
    parser.set_defaults(func=_run_ship)
