"""``wrp-eval bench --only scaling``: how the cost grows with the work.

Four curves, each point timed once on this machine, each fitted as cost ~ a x^k on log-log axes (the exponent k
is a record; ``scaling.*_exponent``):

* planning: wall time of the ``ours`` planner and its view count against ship length, the five procedural
  families at 30 m (fishing), 140 m (stylized, the paper's), 250 m (cruise), 350 m (container), 400 m (tanker).
  Target: <= 2 s for the 350 m container ship.
* oracle: the synthetic oracle's wall time on 25-400 views (a ring of views at three heights around the
  stylized ship, facing it; median of 3 after a warm-up call). Target: <= 1 s for 200 views.
* flight: wall seconds per simulated drone-second of the closed loop (the sim bench's path and wind, every
  ``sim:`` default on, 30 s simulated) against the batch size 1-1,024, after an untimed warm-up flight (the
  compiled kernels load or compile first).
* campaign: wall time of a real campaign (the campaign bench's reference config) against its trial count,
  64 to ``WRP_EVAL_BENCH_SCALING_MAX_TRIALS`` (default 2,048; ~13 min in all on 2 cores), exponent fitted from
  128 trials up (the workers' start-up is a constant). Target: linear, exponent <= 1.1.

* views: planning, oracle and campaign cost against the view count of one ship (:mod:`view_scaling`, also its
  own group ``views``).

The figure (four log-log panels, the first four curves) is written beside the JSON records as ``scaling.png``.
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FixedFormatter, FixedLocator, NullFormatter

from wrp_eval.atomic import atomic_path
from wrp_eval.bench_record import BenchRecord
from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.campaign.bench import reference_config
from wrp_eval.campaign.jobs import campaign_job
from wrp_eval.campaign.view_scaling import exponent, target_anchor, view_count_points, view_count_records
from wrp_eval.config import ExperimentConfig
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.config import PlanningSection
from wrp_eval.planning.planner import plan, planning_rng
from wrp_eval.recon.bench import reference_ship
from wrp_eval.recon.synthetic import SyntheticOracle
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.resolve import resolve_ship_full
from wrp_eval.sim.bench import bench_path, moderate_wind, ship_in_scene, warm_up_kernels
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.flight import FlightSimulator

SHIPS = (("fishing", 30.0), ("stylized", 140.0), ("cruise", 250.0), ("container", 350.0), ("tanker", 400.0))
ORACLE_VIEWS = (25, 50, 100, 200, 400)
BATCHES = (1, 4, 16, 64, 256, 1024)
FLIGHT_SIM_S = 30.0
MAX_TRIALS = int(os.environ.get("WRP_EVAL_BENCH_SCALING_MAX_TRIALS", "2048"))


def planning_curve() -> list[tuple[str, float, float, int]]:
    """(family, length m, planning wall s, views) per ship."""
    out = []
    for family, length in SHIPS:
        overrides = {} if family == "stylized" else {"particulars": {"length_bp_m": length}}
        ship = resolve_ship_full(ShipSection.model_validate({"type": family, **overrides}))
        start = time.perf_counter()
        result = plan(ship.proxy, ship.complexity.complexity, PlanningSection(method="ours"), planning_rng(0))
        out.append((family, float(ship.proxy.length_m), time.perf_counter() - start, len(result.path)))
    return out


def ring_captures(n_views: int) -> CaptureSet:
    """``n_views`` views on an ellipse 40 m off the stylized ship's 140 x 20 m footprint at 10 / 20 / 30 m,
    facing its centre line."""
    k = np.arange(n_views)
    angle = 2 * np.pi * k / n_views * 3 % (2 * np.pi)         # three interleaved turns, one per height
    pos = np.column_stack([110 * np.cos(angle), 50 * np.sin(angle), 10.0 + 10.0 * (k % 3)])
    target = np.column_stack([np.clip(pos[:, 0], -60, 60), np.zeros(n_views), np.full(n_views, 10.0)])
    yaw, pitch = yaw_pitch_towards(pos, target)
    return CaptureSet(pos, yaw, pitch, k, Camera())


def oracle_curve() -> list[tuple[int, float]]:
    """(views, median wall s of 3) of the synthetic oracle."""
    mesh, _ = reference_ship()
    oracle = SyntheticOracle()
    oracle.evaluate(ring_captures(25), mesh)                 # prepare the ground truth once
    out = []
    for n in ORACLE_VIEWS:
        cs = ring_captures(n)
        times = []
        for _ in range(3):
            start = time.perf_counter()
            oracle.evaluate(cs, mesh)
            times.append(time.perf_counter() - start)
        out.append((n, float(np.median(times))))
    return out


def flight_curve() -> list[tuple[int, float]]:
    """(batch, wall s per simulated drone-second) of the closed loop."""
    section = SimSection().model_copy(update={"max_flight_time_s": FLIGHT_SIM_S})
    warm_up_kernels()
    out = []
    with FlightSimulator(section) as sim:
        for batch in BATCHES:
            wind = moderate_wind(section, batch, 0)
            start = time.perf_counter()
            result = sim.fly(bench_path(), wind, batch, ship=ship_in_scene(), flight_rngs=0)
            wall = time.perf_counter() - start
            out.append((batch, wall / float(np.sum(result.flight_time_s))))
    return out


def campaign_curve() -> list[tuple[int, float]]:
    """(trials, wall s) of real campaigns of the reference path."""
    counts = [n for n in (64, 128, 256, 512, 1024, 2048, 4096) if n <= MAX_TRIALS]
    out = []
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        path_file = tmp / "path.json"
        ExperimentContext(ExperimentConfig()).campaign_path.save(path_file)
        for n in counts:
            config = reference_config(path_file, n, tmp / f"c{n}", False, None)
            summary = campaign_job(ExperimentContext(config))
            out.append((n, float(summary.wall_s)))
    return out


def scaling_figure(curves: dict, file: Path) -> None:
    fig = Figure(figsize=(9, 7), dpi=110)
    axes = fig.subplots(2, 2).ravel()
    labels = {"planning": ("ship length (m)", "planning wall (s)"), "oracle": ("views", "oracle wall (s)"),
              "flight": ("batch (drones)", "wall s per drone-second"), "campaign": ("trials", "campaign wall (s)")}
    for ax, (name, (x, y, k)) in zip(axes, curves.items(), strict=True):
        ax.loglog(x, y, "o-")
        # the measured sizes as the x ticks, in plain numbers (log axes' minor labels overlapped)
        ax.xaxis.set_major_locator(FixedLocator(x))
        ax.xaxis.set_major_formatter(FixedFormatter([f"{v:g}" for v in x]))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.tick_params(axis="x", labelsize=8, labelrotation=45)
        ax.set_xlabel(labels[name][0])
        ax.set_ylabel(labels[name][1])
        ax.set_title(f"{name}: exponent {k:.2f}", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    with atomic_path(file) as tmp:
        fig.savefig(tmp, format="png")


def run_bench(out_dir: Path | None = None) -> list[BenchRecord]:
    records: list[BenchRecord] = []
    curves: dict[str, tuple[Sequence[float], Sequence[float], float]] = {}
    ships = planning_curve()
    lengths, plan_s = [s[1] for s in ships], [s[2] for s in ships]
    curves["planning"] = (lengths, plan_s, exponent(lengths, plan_s))
    for family, length, seconds, n_views in ships:
        target = target_anchor("issue 19 target (350 m container)", 2.0, family == "container")
        records += [BenchRecord(f"scaling.plan_s.{family}", seconds, "s", *target, f"{length:.0f} m proxy"),
                    BenchRecord(f"scaling.plan_views.{family}", n_views, "views", None, None, f"{length:.0f} m")]
    records.append(BenchRecord("scaling.plan_exponent", curves["planning"][2], "", None, None,
                               "planning wall ~ length^k, five ships 30-400 m"))
    oracle = oracle_curve()
    views, oracle_s = [o[0] for o in oracle], [o[1] for o in oracle]
    curves["oracle"] = (views, oracle_s, exponent(views, oracle_s))
    records += [BenchRecord(f"scaling.oracle_s.views{n}", s, "s",
                            *target_anchor("issue 19 target", 1.0, n == 200),
                            "synthetic oracle, ring of views around the stylized ship, median of 3")
                for n, s in oracle]
    records.append(BenchRecord("scaling.oracle_exponent", curves["oracle"][2], "", None, None,
                               f"oracle wall ~ views^k, {views[0]}-{views[-1]} views"))
    flight = flight_curve()
    batches, per_s = [f[0] for f in flight], [f[1] for f in flight]
    walls = [b * p for b, p in zip(batches, per_s, strict=True)]
    curves["flight"] = (batches, per_s, exponent(batches, per_s))
    records += [BenchRecord(f"scaling.flight_wall_per_drone_s.batch{b}", p, "s/s", None, None,
                            f"closed loop, {FLIGHT_SIM_S:g} s simulated, every sim default on") for b, p in flight]
    records.append(BenchRecord("scaling.flight_exponent", exponent(batches, walls), "", None, None,
                               "batch wall ~ batch^k (1: no gain from batching; 0: batching is free)"))
    campaign = campaign_curve()
    trials, wall = [c[0] for c in campaign], [c[1] for c in campaign]
    fit = [(t, w) for t, w in campaign if t >= 128] or campaign
    k = exponent([t for t, _ in fit], [w for _, w in fit])
    curves["campaign"] = (trials, wall, k)
    records += [BenchRecord(f"scaling.campaign_s.trials{t}", w, "s", None, None, "reference config, 2 workers")
                for t, w in campaign]
    records.append(BenchRecord("scaling.campaign_exponent", k, "", "issue 19 target (linear)", 1.1,
                               f"campaign wall ~ trials^k over {fit[0][0]}-{fit[-1][0]} trials"))
    records += view_count_records(view_count_points())
    if out_dir is not None:
        scaling_figure(curves, Path(out_dir) / "scaling.png")
    return records
