"""``wrp-eval wind turbulence`` and ``wrp-eval wind field``."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from wrp_eval.errors import InputError
from wrp_eval.wind.boundary_layer import log_law_factor
from wrp_eval.wind.dryden import FT_M, DrydenTurbulence, dryden_parameters

MIL_SHEAR_Z0_M = 0.15 * FT_M   # MIL-F-8785C mean-wind shear roughness (DESIGN.md)


def save_npz_atomic(path: Path, **arrays) -> None:
    """np.savez_compressed to a temporary file in the same folder, then rename (no pickles)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    os.replace(tmp, path)


def turbulence_series(altitude_m: float, w20_mps: float, dt_s: float, duration_s: float, seed: int,
                      airspeed_mps: float | None = None, airspeed_floor_mps: float = 2.0) -> dict:
    """One Dryden series at fixed altitude: t (n,), uvw (n, 3) along/across/vertical, sigma_uvw, length_uvw,
    airspeed. Default airspeed: the MIL-F-8785C mean wind at that altitude,
    W20 ln(h/z0)/ln(20 ft/z0) with z0 = 0.15 ft, floored (hover)."""
    if airspeed_mps is None:
        shear = float(log_law_factor(max(altitude_m, 10 * FT_M), MIL_SHEAR_Z0_M, 20 * FT_M))
        airspeed_mps = w20_mps * shear
    airspeed = max(airspeed_mps, airspeed_floor_mps)
    n_steps = int(round(duration_s / dt_s))
    turb = DrydenTurbulence(1, dt_s, np.random.default_rng(seed).spawn(1), w20_mps,
                            airspeed_floor_mps=airspeed_floor_mps)
    uvw = turb.generate(n_steps, altitude_m, airspeed)[0]
    sigma, length = dryden_parameters(altitude_m, w20_mps)
    return {"t": dt_s * np.arange(n_steps), "uvw": uvw, "sigma_uvw": sigma, "length_uvw": length,
            "airspeed": np.float64(airspeed)}


def _positive(name: str, value: float) -> float:
    if not np.isfinite(value) or value <= 0:
        raise InputError(name, f"must be a positive number, got {value}")
    return value


def _cmd_turbulence(args: argparse.Namespace) -> int:
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


def _ship_pose(config, config_dir: Path, args) -> tuple[float, float, float]:
    lat = lon = heading = None
    try:  # the ship stage resolves AIS data and overrides; a missing ship stage leaves the pose to the flags
        from wrp_eval.ship.resolve import resolve_particulars
        particulars, _ = resolve_particulars(config.ship, config_dir)
        lat, lon, heading = particulars.lat_deg, particulars.lon_deg, particulars.heading_deg
    except ImportError:
        pass
    lat = args.lat if args.lat is not None else lat
    lon = args.lon if args.lon is not None else lon
    heading = args.heading if args.heading is not None else heading
    if config.wind.source != "synthetic" and (lat is None or lon is None):
        raise InputError("ship", "a WRF/MM5 wind field needs the ship's lat/lon (AIS, ship.particulars, "
                                 "or --lat/--lon)")
    return float(lat or 0.0), float(lon or 0.0), float(heading or 0.0)


def sample_mean_field(section, pose, config_dir: Path):
    """The configured mean field on its grid nodes above the sea: x (nx,), y (ny,), z (nz,) m and velocity
    (nx, ny, nz, 3) m/s in the ship frame. ``pose``: ShipParticulars or (lat, lon, heading) degrees."""
    from wrp_eval.wind.field import build_mean_grid, grid_axes
    from wrp_eval.wind.grid import GriddedMeanWind
    mean = GriddedMeanWind(build_mean_grid(section, pose, config_dir), section.interpolation,
                           section.idw_power, section.clamp)
    x, y, z = grid_axes(section.grid)
    z = z[z > 0] if np.any(z > 0) else z
    gx, gy, gz = np.meshgrid(x, y, z, indexing="ij")
    points = np.stack([gx, gy, gz], -1).reshape(-1, 3)
    return x, y, z, mean.velocity(points, 0.0).reshape(gx.shape + (3,))


def _cmd_field(args: argparse.Namespace) -> int:
    from wrp_eval.config import load_experiment

    config_path = Path(args.config)
    config = load_experiment(config_path)
    section = config.wind
    pose = _ship_pose(config, config_path.parent, args)
    x, y, z, velocity = sample_mean_field(section, pose, config_path.parent)
    points = np.stack(np.meshgrid(x, y, z, indexing="ij"), -1).reshape(-1, 3)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    save_npz_atomic(out / "wind_field.npz", x_m=x, y_m=y, z_m=z, velocity_mps=velocity,
                    ship_lat_lon_heading_deg=np.array(pose), source=np.array(section.source))
    quiver_png(out / "wind_field.png", x, y, z, velocity, section.source)
    if args.rerun:
        _log_rerun(Path(args.rerun), points, velocity.reshape(-1, 3), args.rerun_fraction)
    speed = np.linalg.norm(velocity, axis=-1)
    print(f"wrote {out}/wind_field.npz and wind_field.png: {points.shape[0]} nodes, speed "
          f"{speed.min():.2f}..{speed.max():.2f} m/s")
    return 0


def quiver_png(path: Path, x, y, z, velocity, source: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    levels = sorted({0, len(z) // 2, len(z) - 1})
    fig, axes = plt.subplots(1, len(levels), figsize=(5 * len(levels), 4.6), squeeze=False)
    step = max(1, int(np.ceil(max(len(x), len(y)) / 25)))          # at most ~25 arrows per side
    speed = np.linalg.norm(velocity, axis=-1)
    # the fastest arrow spans ~90 % of the spacing between drawn arrows (readable whatever the speeds)
    spacing = step * (float(np.min(np.diff(x))) if len(x) > 1 else 1.0)
    arrow_scale = max(float(speed.max()), 1e-6) / (0.9 * spacing)
    for ax, k in zip(axes[0], levels):
        sl = (slice(None, None, step), slice(None, None, step), k)
        q = ax.quiver(x[::step, None] * np.ones(len(y[::step])), np.ones(len(x[::step]))[:, None] * y[None, ::step],
                      velocity[sl][..., 0], velocity[sl][..., 1], speed[sl], cmap="viridis",
                      angles="xy", scale_units="xy", scale=arrow_scale)
        fig.colorbar(q, ax=ax, label="speed (m/s)")
        ax.plot([-5, 5], [0, 0], "r-", lw=3)
        ax.annotate("bow", (5, 0), color="r")
        ax.set_title(f"{source}: z = {z[k]:.0f} m")
        ax.set_xlabel("x along the ship (m)")
        ax.set_ylabel("y to port (m)")
        ax.set_aspect("equal")
    fig.tight_layout()
    tmp = path.with_name(path.name + ".tmp.png")
    fig.savefig(tmp, dpi=90)
    plt.close(fig)
    os.replace(tmp, path)


def _log_rerun(path: Path, points: np.ndarray, vectors: np.ndarray, fraction: float) -> None:
    """Arrows at a regular subset of the nodes (the paper's Fig. 4 shows 20 %)."""
    import rerun as rr

    every = max(1, int(round(1.0 / max(fraction, 1e-6))))
    keep = slice(None, None, every)
    speed = np.linalg.norm(vectors[keep], axis=1)
    t = (speed - speed.min()) / max(np.ptp(speed), 1e-9)
    colors = np.stack([255 * t, 80 + 0 * t, 255 * (1 - t)], 1).astype(np.uint8)
    rec = rr.RecordingStream("wrp_eval_wind")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp.rrd")
    rec.save(str(tmp))
    rec.log("wind/mean", rr.Arrows3D(origins=points[keep], vectors=vectors[keep], colors=colors), static=True)
    rec.flush()
    rec.disconnect()
    os.replace(tmp, path)


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
    p.set_defaults(func=_cmd_turbulence)

    p = sub.add_parser("field", help="sample the configured mean wind around the ship (npz + quiver PNG)")
    p.add_argument("config", help="experiment YAML (its wind: and ship: sections)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--rerun", default=None, help="also log the field as arrows to this .rrd file")
    p.add_argument("--rerun-fraction", type=float, default=0.2, help="share of nodes drawn (default 0.2)")
    p.add_argument("--lat", type=float, default=None, help="ship latitude, deg (overrides the config)")
    p.add_argument("--lon", type=float, default=None, help="ship longitude, deg (overrides the config)")
    p.add_argument("--heading", type=float, default=None, help="ship heading, deg clockwise from north")
    p.set_defaults(func=_cmd_field)
