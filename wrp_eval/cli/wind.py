"""``wrp-eval wind turbulence`` and ``wrp-eval wind field``: parse, call the wind stage, print."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.frames import ShipPose, ship_pose
from wrp_eval.wind.dryden import turbulence_series
from wrp_eval.wind.field import sample_mean_field
from wrp_eval.wind.outputs import log_mean_field_rerun, quiver_png, save_npz_atomic


def _positive(name: str, value: float) -> float:
    if not np.isfinite(value) or value <= 0:
        raise InputError(name, f"must be a positive number, got {value}")
    return value


def _turbulence(args: argparse.Namespace) -> int:
    for name in ("altitude", "dt", "duration"):
        _positive(f"--{name}", getattr(args, name))
    if not np.isfinite(args.w20) or args.w20 < 0:
        raise InputError("--w20", f"must be >= 0, got {args.w20}")
    if args.duration < args.dt:
        raise InputError("--duration", "must be at least one time step --dt")
    if args.airspeed is not None:
        _positive("--airspeed", args.airspeed)
    series = turbulence_series(args.altitude, args.w20, args.dt, args.duration, args.seed, args.airspeed)
    save_npz_atomic(Path(args.out), **series)
    s, L = series["sigma_uvw"], series["length_uvw"]
    print(f"wrote {args.out}: {len(series['t'])} samples; sigma_uvw {np.round(s, 3).tolist()} m/s, "
          f"L_uvw {np.round(L, 1).tolist()} m, V {float(series['airspeed']):.2f} m/s; "
          f"sample std {np.round(series['uvw'].std(axis=0), 3).tolist()} m/s")
    return 0


def _field(args: argparse.Namespace) -> int:
    ctx = ExperimentContext.load(args.config)
    section = ctx.config.wind
    pose = ship_pose(ctx.particulars)             # the ship stage's pose (AIS / particulars), flags override it
    pose = ShipPose(pose.lat_deg if args.lat is None else args.lat, pose.lon_deg if args.lon is None else args.lon,
                    pose.heading_deg if args.heading is None else args.heading)
    x, y, z, velocity = sample_mean_field(section, pose, ctx.config_dir)
    points = np.stack(np.meshgrid(x, y, z, indexing="ij"), -1).reshape(-1, 3)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    save_npz_atomic(out / "wind_field.npz", x_m=x, y_m=y, z_m=z, velocity_mps=velocity,
                    ship_lat_lon_heading_deg=np.array([pose.lat_deg, pose.lon_deg, pose.heading_deg]),
                    source=np.array(section.source))
    quiver_png(out / "wind_field.png", x, y, z, velocity, section.source)
    if args.rerun:
        log_mean_field_rerun(Path(args.rerun), points, velocity.reshape(-1, 3), args.rerun_fraction)
    speed = np.linalg.norm(velocity, axis=-1)
    print(f"wrote {out}/wind_field.npz and wind_field.png: {points.shape[0]} nodes, speed "
          f"{speed.min():.2f}..{speed.max():.2f} m/s")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    wind = subparsers.add_parser("wind", help="wind field and Dryden turbulence tools")
    sub = wind.add_subparsers(dest="wind_command", metavar="WIND_COMMAND", required=True)

    p = sub.add_parser("turbulence", help="generate one Dryden (MIL-F-8785C) turbulence series to an .npz")
    p.add_argument("--altitude", type=float, required=True, help="altitude above the sea, m")
    p.add_argument("--w20", type=float, required=True, help="mean wind speed at 20 ft, m/s")
    p.add_argument("--dt", type=float, default=0.01, help="time step, s (default 0.01)")
    p.add_argument("--duration", type=float, default=600.0, help="series length, s (default 600)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--airspeed", type=float, default=None,
                   help="frozen-field speed V, m/s (default: MIL-F-8785C mean wind at the altitude, >= 2)")
    p.add_argument("--out", required=True, help="output .npz (t, uvw, sigma_uvw, length_uvw, airspeed)")
    p.set_defaults(func=_turbulence)

    p = sub.add_parser("field", help="sample the configured mean wind around the ship (npz + quiver PNG)")
    p.add_argument("config", help="experiment YAML (its wind: and ship: sections)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--rerun", default=None, help="also log the field as arrows to this .rrd file")
    p.add_argument("--rerun-fraction", type=float, default=0.2, help="share of nodes drawn (default 0.2)")
    p.add_argument("--lat", type=float, default=None, help="ship latitude, deg (overrides the config)")
    p.add_argument("--lon", type=float, default=None, help="ship longitude, deg (overrides the config)")
    p.add_argument("--heading", type=float, default=None, help="ship heading, deg clockwise from north")
    p.set_defaults(func=_field)
