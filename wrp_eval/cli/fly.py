"""``wrp-eval fly CONFIG --path P --trials N --out DIR`` / ``--hover``: fly a path N times (Parquet capture
poses and offsets), or hold a hover in wind.

Wind: a path flight flies through the config's ``wind:`` section (mean field + Dryden turbulence + gusts,
built by :func:`wrp_eval.wind.field.build_wind_field`, one turbulence stream per trial from the seed);
``--wind-speed`` / ``--wind-dir`` override the synthetic field's 10 m speed and direction. A hover holds a
constant wind of ``--wind-speed`` from ``--wind-dir`` (no ship air wake, no ship motion) with the config's
``sim:`` settings, the navigation estimate included (the config's preset: GNSS + IMU fused errors, which the
airframe answers with a few tenths of a degree of tilt noise), and prints its statistics beside the analytic
weight/drag balance; ``--airframe-only`` flies it with ideal navigation (the controller sees the true state):
the airframe alone, whose steady tilt is the analytic balance.
``--wind-dir`` is, for both, the project's one convention: the compass bearing the wind blows FROM, degrees
clockwise from true north (the config's ``wind.direction_deg``); the hover turns it into the ship frame with
the ship's heading from the config's ``ship:`` section (before, a hover's ``--wind-dir`` was counter-clockwise
from the bow).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath
from wrp_eval.sim.flight import FlightSimulator
from wrp_eval.sim.hover import airframe_only, analytic_hover_balance, hover_statistics
from wrp_eval.sim.onboard import ShipInScene
from wrp_eval.sim.outputs import write_flight_tables, write_rerun
from wrp_eval.sim.simple_wind import ConstantWind
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.field import build_wind_field


def _wind_section(args: argparse.Namespace, config: ExperimentConfig) -> WindSection:
    """The ``wind:`` section with the --wind-speed / --wind-dir overrides (synthetic source only)."""
    overrides = {}
    if args.wind_speed is not None:
        overrides["speed_10m_m_s"] = args.wind_speed
    if args.wind_dir is not None:
        overrides["direction_deg"] = args.wind_dir % 360.0
    if overrides and config.wind.source != "synthetic":
        raise InputError("--wind-speed/--wind-dir", f"only apply to the synthetic wind, not {config.wind.source}")
    return config.wind.model_copy(update=overrides)


def _fly(args: argparse.Namespace) -> int:
    if args.wind_speed is not None and args.wind_speed < 0:
        raise InputError("--wind-speed", "must be >= 0")
    ctx = ExperimentContext.load(args.config)
    config, config_dir = ctx.config, ctx.config_dir
    seed = config.run.seed if args.seed is None else args.seed
    if args.hover:
        if args.duration <= 0:
            raise InputError("--duration", "must be > 0")
        hover_wind = ConstantWind.blowing_from(args.wind_speed or 0.0, args.wind_dir or 0.0,
                                               ctx.particulars.heading_deg)
        section = airframe_only(config.sim) if args.airframe_only else config.sim
        with FlightSimulator(section) as sim:
            result = sim.hover(hover_wind, [0.0, 0.0, args.altitude], 0.0, args.duration, batch=args.trials,
                               flight_rngs=np.random.SeedSequence(seed).spawn(2)[1])
        stats = hover_statistics(result)
        stats["analytic"] = analytic_hover_balance(hover_wind.vector, config.sim)
        if args.json:
            print(json.dumps(stats, indent=1))
        else:
            for k, v in stats.items():
                print(f"{k:18s} {v}")
        return 0
    if args.airframe_only:
        raise InputError("--airframe-only", "only applies to --hover")
    if args.path is None or args.out is None:
        raise InputError("fly", "--path and --out are required unless --hover is given")
    if args.trials < 1:
        raise InputError("--trials", "must be >= 1")
    path = FlightPath.load(args.path)
    wind_section = _wind_section(args, config)
    dt = config.sim.timestep_s * config.sim.chunk_steps          # the wind is stepped at the controller rate
    wind_seed, flight_seed = np.random.SeedSequence(seed).spawn(2)
    wind = build_wind_field([wind_section] * args.trials, ctx.particulars, wind_seed, dt, config_dir)
    ship = ShipInScene.of(ctx.ship.mesh, config.ship.motion, ctx.particulars, wind.speed_10m_at_ship(args.trials))
    with FlightSimulator(config.sim) as sim:
        result = sim.fly(path, wind, args.trials, ship=ship, flight_rngs=flight_seed)
    out = Path(args.out)
    a, b = write_flight_tables(result, path, out, seed)
    if args.rerun:
        write_rerun(result, path, Path(args.rerun))
    print(f"flew {result.batch} trial(s) of {len(path)} views: {int(result.failed.sum())} failed; "
          f"median |offset| {np.nanmedian(np.linalg.norm(result.offsets[..., :3], axis=-1)):.3f} m; "
          f"wrote {a} and {b}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fly", help="fly a path in MuJoCo through wind (or hover) and record capture poses",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config", help="experiment YAML (its sim:, wind: and ship: sections)")
    p.add_argument("--path", help="path.json to fly")
    p.add_argument("--trials", type=int, default=1, help="number of flights (batched)")
    p.add_argument("--seed", type=int, default=None,
                   help="seed of the turbulence, the navigation errors and the ship's motion (default: run.seed)")
    p.add_argument("--out", help="output folder for captures.parquet and trials.parquet")
    p.add_argument("--rerun", help="write a rerun .rrd recording here")
    p.add_argument("--hover", action="store_true",
                   help="hold a hover in a constant wind instead and print statistics and the analytic balance "
                        "(default: the config's sim settings, its navigation errors included; no air wake, no "
                        "ship motion)")
    p.add_argument("--airframe-only", action="store_true",
                   help="with --hover: ideal navigation (no air wake, still sea as always for a hover): the "
                        "airframe alone, whose tilt is the exact analytic balance")
    p.add_argument("--wind-speed", type=float, default=None,
                   help="mean wind m/s (path: overrides wind.speed_10m_m_s; hover: the constant wind, default 0)")
    p.add_argument("--wind-dir", type=float, default=None,
                   help="compass bearing the wind blows FROM, deg clockwise from true north (path: overrides "
                        "wind.direction_deg; hover: turned into the ship frame with the config's ship heading, "
                        "default 0)")
    p.add_argument("--duration", type=float, default=30.0, help="hover duration s")
    p.add_argument("--altitude", type=float, default=30.0, help="hover altitude m")
    p.add_argument("--json", action="store_true", help="print hover statistics as JSON")
    p.set_defaults(func=_fly)
