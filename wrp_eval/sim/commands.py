"""``wrp-eval fly``: fly a path N times (Parquet capture poses and offsets), or hold a hover in wind.

Wind: a path flight flies through the config's ``wind:`` section (mean field + Dryden turbulence + gusts,
built by :func:`wrp_eval.wind.field.build_wind_field`, one turbulence stream per trial from the seed);
``--wind-speed`` / ``--wind-dir`` override the synthetic field's 10 m speed and direction (compass
"from", as in the config). A hover holds a constant wind given in the ship frame (``--wind-dir``: the
direction it blows from, CCW from the bow), so that the analytic balance can be checked exactly.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path as FsPath

import numpy as np

from wrp_eval.errors import InputError
from wrp_eval.planning.path import Path
from wrp_eval.sim.aero import drag_force
from wrp_eval.sim.controller import wrap_angle
from wrp_eval.sim.results import FlightResult
from wrp_eval.sim.simple_wind import ConstantWind, mean_wind_vector


def _path_wind(args, config, batch: int, seed: int, config_dir: FsPath):
    """The configured wind field for ``batch`` flights, stepped at the controller rate."""
    from wrp_eval.ship.resolve import resolve_particulars
    from wrp_eval.wind.field import build_wind_field
    section = config.wind
    overrides = {}
    if args.wind_speed is not None:
        overrides["speed_10m_mps"] = args.wind_speed
    if args.wind_dir is not None:
        overrides["direction_deg"] = args.wind_dir % 360.0
    if overrides:
        if section.source != "synthetic":
            raise InputError("--wind-speed/--wind-dir", f"only apply to the synthetic wind, not {section.source}")
        section = section.model_copy(update=overrides)
    particulars, _ = resolve_particulars(config.ship, config_dir)
    dt = config.sim.timestep_s * config.sim.chunk_steps
    return build_wind_field(section, particulars, batch, np.random.SeedSequence(seed), dt, config_dir)


def _atomic_parquet(table, target: FsPath) -> None:
    import pyarrow.parquet as pq
    tmp = target.with_name(target.name + ".tmp")
    pq.write_table(table, tmp)
    tmp.replace(target)


def write_flight_tables(result: FlightResult, path: Path, out_dir: FsPath, seed: int) -> tuple[FsPath, FsPath]:
    """captures.parquet (one row per trial x view) and trials.parquet (one row per trial), atomically."""
    import pyarrow as pa
    b, n = result.batch, result.n_views
    trial = np.repeat(np.arange(b), n)
    view = np.tile(np.arange(n), b)
    pos = np.full((b, n, 3), np.nan)
    yaw = np.full((b, n), np.nan)
    for i, cs in enumerate(result.captures):
        pos[i, cs.planned_index] = cs.positions
        yaw[i, cs.planned_index] = cs.yaw
    captures = pa.table({
        "trial": trial, "view": view, "taken": result.taken.ravel(),
        "x_m": pos[..., 0].ravel(), "y_m": pos[..., 1].ravel(), "z_m": pos[..., 2].ravel(),
        "yaw_deg": np.degrees(yaw).ravel(), "pitch_deg": np.degrees(result.camera_pitch).ravel(),
        "dx_m": result.offsets[..., 0].ravel(), "dy_m": result.offsets[..., 1].ravel(),
        "dz_m": result.offsets[..., 2].ravel(), "dyaw_deg": np.degrees(result.offsets[..., 3]).ravel(),
        "residual_roll_deg": np.degrees(result.residual_roll).ravel(),
        "gimbal_saturated": result.gimbal_saturated.ravel(), "capture_time_s": result.capture_time_s.ravel(),
    })
    trials = pa.table({
        "trial": np.arange(b), "seed": np.full(b, seed), "failed": result.failed,
        "failure_reason": list(result.failure_reason), "views_taken": result.taken.sum(axis=1),
        "flight_time_s": result.flight_time_s,
    })
    out_dir.mkdir(parents=True, exist_ok=True)
    a, c = out_dir / "captures.parquet", out_dir / "trials.parquet"
    _atomic_parquet(captures, a)
    _atomic_parquet(trials, c)
    return a, c


def write_rerun(result: FlightResult, path: Path, file: FsPath, max_trials: int = 8) -> None:
    """Trajectories, capture frusta (first trial) and wind arrows into a .rrd recording (atomic)."""
    import rerun as rr
    from wrp_eval.camera import camera_rotations
    rec = rr.RecordingStream("wrp-eval-fly")
    tmp = file.with_name(file.name + ".tmp")
    file.parent.mkdir(parents=True, exist_ok=True)
    rec.save(str(tmp))
    traj = result.trajectory
    shown = min(result.batch, max_trials)
    rec.log("plan/viewpoints", rr.Points3D(path.positions, radii=0.3, colors=[[40, 160, 255]]), static=True)
    rec.log("flights/trajectories", rr.LineStrips3D([traj.position[i] for i in range(shown)]), static=True)
    for i in range(shown):
        step = max(1, len(traj.time) // 200)
        rec.log(f"flights/{i}/wind", rr.Arrows3D(origins=traj.position[i, ::step], vectors=traj.wind[i, ::step]),
                static=True)
    cs = result.captures[0]
    if len(cs):
        rots = camera_rotations(cs.yaw, cs.pitch)
        cam = cs.camera
        for j in range(len(cs)):
            ent = f"captures/trial0/view{int(cs.planned_index[j])}"
            rec.log(ent, rr.Transform3D(translation=cs.positions[j], mat3x3=rots[j]), static=True)
            rec.log(ent, rr.Pinhole(focal_length=cam.focal_px, width=cam.image_width_px,
                                    height=cam.image_height_px, image_plane_distance=2.0), static=True)
    rec.flush()
    rec.disconnect()
    tmp.replace(file)


def hover_statistics(result: FlightResult, settle_fraction: float = 0.5) -> dict:
    """Steady-state statistics over the last ``1 - settle_fraction`` of a hover (all flights pooled)."""
    tr = result.trajectory
    s = slice(int(len(tr.time) * settle_fraction), None)
    err = tr.position[:, s] - tr.reference[:, s]
    dist = np.linalg.norm(err, axis=-1)
    yaw_err = np.degrees(np.abs(wrap_angle(tr.yaw[:, s] - tr.yaw[:, :1])))
    drag = np.linalg.norm(tr.drag[:, s], axis=-1)

    def stats(x):
        return {"mean": float(np.mean(x)), "std": float(np.std(x)), "max": float(np.max(x))}
    return {"tilt_deg": stats(np.degrees(tr.tilt[:, s])), "thrust_n": stats(tr.thrust[:, s]),
            "drag_force_n": stats(drag), "position_error_m": stats(dist), "yaw_error_deg": stats(yaw_err),
            "failed": int(result.failed.sum()), "failure_reasons": [r for r in result.failure_reason if r]}


def _cmd_fly(args: argparse.Namespace) -> int:
    from wrp_eval.config import load_experiment
    from wrp_eval.sim.flight import FlightSimulator
    config = load_experiment(args.config)
    if args.wind_speed is not None and args.wind_speed < 0:
        raise InputError("--wind-speed", "must be >= 0")
    seed = config.run.seed if args.seed is None else args.seed
    if args.hover:
        if args.duration <= 0:
            raise InputError("--duration", "must be > 0")
        with FlightSimulator(config.sim) as sim:
            hover_wind = ConstantWind(mean_wind_vector(args.wind_speed or 0.0, args.wind_dir or 0.0))
            result = sim.hover(hover_wind, [0.0, 0.0, args.altitude], 0.0,
                               args.duration, batch=args.trials)
        stats = hover_statistics(result)
        wind = hover_wind.vector
        from wrp_eval.sim.vehicle import PHANTOM4
        f = drag_force(wind[None], np.zeros(1), PHANTOM4, config.sim.drag_coefficient,
                       config.sim.air_density_kg_m3)[0]
        stats["analytic"] = {"drag_force_n": float(np.linalg.norm(f)),
                             "tilt_deg": float(np.degrees(np.arctan2(np.linalg.norm(f), PHANTOM4.weight_n))),
                             "thrust_n": float(np.hypot(np.linalg.norm(f), PHANTOM4.weight_n))}
        if args.json:
            print(json.dumps(stats, indent=1))
        else:
            for k, v in stats.items():
                print(f"{k:18s} {v}")
        return 0
    if args.path is None or args.out is None:
        raise InputError("fly", "--path and --out are required unless --hover is given")
    if args.trials < 1:
        raise InputError("--trials", "must be >= 1")
    path = Path.load(args.path)
    with FlightSimulator(config.sim) as sim:
        result = sim.fly(path, _path_wind(args, config, args.trials, seed, FsPath(args.config).parent),
                         args.trials)
    out = FsPath(args.out)
    a, b = write_flight_tables(result, path, out, seed)
    if args.rerun:
        write_rerun(result, path, FsPath(args.rerun))
    print(f"flew {result.batch} trial(s) of {len(path)} views: {int(result.failed.sum())} failed; "
          f"median |offset| {np.nanmedian(np.linalg.norm(result.offsets[..., :3], axis=-1)):.3f} m; "
          f"wrote {a} and {b}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fly", help="fly a path in MuJoCo through wind (or hover) and record capture poses",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config", help="experiment YAML (its sim: section)")
    p.add_argument("--path", help="path.json to fly")
    p.add_argument("--trials", type=int, default=1, help="number of flights (batched)")
    p.add_argument("--seed", type=int, default=None, help="seed of the turbulence (default: run.seed)")
    p.add_argument("--out", help="output folder for captures.parquet and trials.parquet")
    p.add_argument("--rerun", help="write a rerun .rrd recording here")
    p.add_argument("--hover", action="store_true", help="hold a hover instead and print statistics")
    p.add_argument("--wind-speed", type=float, default=None,
                   help="mean wind m/s (path: overrides wind.speed_10m_mps; hover: the constant wind, default 0)")
    p.add_argument("--wind-dir", type=float, default=None,
                   help="direction the wind blows FROM, deg (path: compass, overrides wind.direction_deg; "
                        "hover: CCW from the bow)")
    p.add_argument("--duration", type=float, default=30.0, help="hover duration s")
    p.add_argument("--altitude", type=float, default=30.0, help="hover altitude m")
    p.add_argument("--json", action="store_true", help="print hover statistics as JSON")
    p.set_defaults(func=_cmd_fly)
