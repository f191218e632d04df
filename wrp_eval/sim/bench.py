"""``wrp-eval bench --only sim``: simulator throughput, open loop vs our closed-loop flights, same model.

sim.raw_rollout_steps_per_s: drone-steps/s of an open-loop ``mujoco.rollout`` of the flight model (same
scene, same drones per model, same batch, constant hover thrust), in calls of 100 steps.
sim.closed_loop_steps_per_s: drone-steps/s of our flights (wind, drag, SE(3) control, reference, photo
triggers, failure checks, recording between chunks) hovering in gusty wind for the same simulated time.
Both are the best of 3 interleaved runs (the machine is shared with other jobs).
sim.ratio = closed / raw (target >= 0.7). sim.path_flight_s: wall seconds per flight of a 50-view ~700 m
path flown by a batch of 32.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from wrp_eval.bench import BenchRecord
from wrp_eval.planning.path import Path
from wrp_eval.sim.config import SimSection
from wrp_eval.wind.config import TurbulenceSection, WindSection
from wrp_eval.wind.field import build_wind_field


def bench_path(n_views: int = 50, length_m: float = 700.0) -> Path:
    """A ~``length_m`` loop of ``n_views`` viewpoints around a 140 m x 20 m ship footprint, facing it."""
    ang = np.linspace(0.0, 2 * np.pi, n_views, endpoint=False)
    a, b = 100.0, 20.0
    # ellipse with semi-axes scaled so the polygon perimeter is ~length_m
    per = np.sum(np.hypot(np.diff(a * np.cos(np.r_[ang, 0])), np.diff(b * np.sin(np.r_[ang, 0]))))
    s = length_m / per
    pos = np.stack([s * a * np.cos(ang), s * b * np.sin(ang), 20 + 5 * np.sin(3 * ang)], axis=1)
    yaw = np.arctan2(-pos[:, 1], -pos[:, 0])
    n = n_views
    return Path(pos, yaw, np.full(n, -0.3), np.zeros(n, int), np.zeros(n, int), np.zeros(n, int),
                speed_m_s=5.0, dwell_s=1.0)


# open-loop calls of 100 steps: one call for the whole run would write a (batch, nstep, nstate) trajectory
# of hundreds of MB and measure memory bandwidth rather than physics
RAW_CALL_STEPS = 100


def raw_rollout_rate(section: SimSection, batch: int, sim_seconds: float) -> float:
    from wrp_eval.sim.flight import FlightSimulator
    with FlightSimulator(section) as sim:
        n_models, padded, qpos_flat, _, motor_flat, _ = sim._layout(batch)
        state = np.tile(sim._initial_state, (n_models, 1))
        q = np.zeros((padded, 7))
        q[:, 2] = 30.0 + np.arange(padded)
        q[:, 3] = 1.0
        state.reshape(-1)[qpos_flat] = q
        nstep = int(round(sim_seconds / section.timestep_s))
        calls = -(-nstep // RAW_CALL_STEPS)
        control = np.zeros((n_models, 1, sim.ncontrol))
        control.reshape(-1)[motor_flat] = sim.params.weight_n / 4
        control = np.broadcast_to(control, (n_models, RAW_CALL_STEPS, sim.ncontrol)).copy()
        models = [sim.scene.model] * n_models
        out = np.empty((n_models, RAW_CALL_STEPS, sim.nstate))
        start = time.perf_counter()
        for _ in range(calls):
            sim._pool.rollout(models, sim._datas, state, control, control_spec=sim.control_spec,
                              skip_checks=True, nstep=RAW_CALL_STEPS, state=out)
            state = np.ascontiguousarray(out[:, -1])
        wall = time.perf_counter() - start
        nstep = calls * RAW_CALL_STEPS
    return batch * nstep / wall


def _moderate_wind(section: SimSection, batch: int, seed: int):
    """Synthetic marine wind 6 m/s at 10 m + moderate Dryden turbulence, one stream per flight."""
    wind = WindSection(speed_10m_mps=6.0, turbulence=TurbulenceSection(severity="moderate"))
    return build_wind_field(wind, (0.0, 0.0, 0.0), batch, np.random.SeedSequence(seed),
                            section.timestep_s * section.chunk_steps)


def closed_loop_rate(section: SimSection, batch: int, sim_seconds: float) -> float:
    from wrp_eval.sim.flight import FlightSimulator
    wind = _moderate_wind(section, batch, 0)
    with FlightSimulator(section) as sim:
        start = time.perf_counter()
        result = sim.hover(wind, [0.0, 0.0, 30.0], 0.0, sim_seconds, batch=batch)
        wall = time.perf_counter() - start
    steps = result.flight_time_s.max() / section.timestep_s
    return batch * steps / wall


def run_bench() -> list[BenchRecord]:
    section = SimSection()
    rec = []
    note_common = (f"timestep {section.timestep_s} s, chunk {section.chunk_steps} steps "
                   f"(control {1 / (section.timestep_s * section.chunk_steps):.0f} Hz), "
                   f"{section.drones_per_model} drones/model, mujoco {mujoco.__version__}")
    for batch in (1024, 32):
        # interleaved, best of 3: this machine is shared, so the ratio is taken between neighbouring runs
        raw = closed = 0.0
        for _ in range(3):
            raw = max(raw, raw_rollout_rate(section, batch, 10.0))
            closed = max(closed, closed_loop_rate(section, batch, 10.0))
        suffix = "" if batch == 1024 else f"_batch{batch}"
        rec += [
            BenchRecord(f"sim.raw_rollout_steps_per_s{suffix}", raw, "drone-steps/s",
                        note=f"open-loop mujoco.rollout, batch {batch}; " + note_common),
            BenchRecord(f"sim.closed_loop_steps_per_s{suffix}", closed, "drone-steps/s",
                        note=f"hover in moderate Dryden turbulence, batch {batch}; " + note_common),
            BenchRecord(f"sim.ratio{suffix}", closed / raw, "ratio", anchor="issue 5 target", anchor_value=0.7,
                        note=f"batch {batch}"),
        ]
    from wrp_eval.sim.flight import FlightSimulator
    path = bench_path()
    batch = 32
    wind = _moderate_wind(section, batch, 1)
    with FlightSimulator(section) as sim:
        start = time.perf_counter()
        result = sim.fly(path, wind, batch)
        wall = time.perf_counter() - start
    rec.append(BenchRecord("sim.path_flight_s", wall / batch, "s wall per flight",
                           anchor="paper Table 1 flight time (s), 51 views", anchor_value=170.832,
                           note=f"{len(path)} views, {path.length_m:.0f} m, batch {batch}, simulated "
                                f"{result.flight_time_s.mean():.0f} s per flight, {int(result.failed.sum())} "
                                f"failed; " + note_common))
    return rec
