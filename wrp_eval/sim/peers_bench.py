"""``wrp-eval bench --only peers``: our closed-loop flights beside RotorPy 3.0.0 in one run.

The scenario, the same for both: N quadrotors of the Phantom 4's mass and inertia (``wrp_eval.sim.vehicle``)
hold a hover 30 m above the sea, 250 m from the ship, for ``SIM_S`` simulated seconds in Dryden turbulence of
the same intensity (our wind stage's synthetic marine field, 6 m/s at 10 m from the west, moderate
MIL-F-8785C turbulence, the same seed; RotorPy gets the series sampled at its own 10 ms step and set in its
state), batch sizes 1, 64 and 1,024.

* ours: :meth:`wrp_eval.sim.flight.FlightSimulator.hover`, MuJoCo at its 5 ms step (implicit-fast integrator
  of the flight model), every ``sim:`` default on (navigation estimate, gimbal, battery, wind limit, air
  wake of no ship here, drag 0.5 rho C_d A |v| v on the body box);
* RotorPy: ``BatchedMultirotor`` (torch, ``integrator="rk4"``, its batched fixed-step choice) at 10 ms with its
  ``BatchedSE3Control`` commanding motor speeds (its default gains), parasitic
  drag ``c_D = 0.5 rho C_d A`` per body axis from the same box and C_d (rotor drag, induced inflow and
  translational lift off: our model has none), thrust coefficient set so that its top rotor speed gives our
  maximum thrust per motor.

Records per batch B: ``peers.ours_drone_s_per_s.bB`` and ``peers.rotorpy_drone_s_per_s.bB`` (simulated
drone-seconds per wall second), ``peers.rotorpy_ratio.bB`` (ours / RotorPy; target >= 10 at 1,024) and the
tracking error of each (``peers.*_tracking_rms_m.bB``: RMS distance of the true position from the hover point
over the second half; ours includes the navigation estimate's error, which RotorPy's true-state controller does
not have, so ours is also flown with ideal navigation: ``peers.ours_ideal_navigation_tracking_rms_m.bB``).
Skipped with one line when RotorPy is not installed (``pip install .[peers]``).
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

from wrp_eval.bench_record import BenchRecord
from wrp_eval.sim.bench import moderate_wind, warm_up_kernels
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.flight import FlightSimulator
from wrp_eval.sim.navigation import NavigationSection
from wrp_eval.sim.vehicle import GRAVITY_M_S2, PHANTOM4
from wrp_eval.wind.base import WindModel

log = logging.getLogger(__name__)

BATCHES = (1, 64, 1024)
SIM_S = 10.0
ROTORPY_DT_S = 0.01
HOVER_POINT = np.array([-250.0, 0.0, 30.0])   # 250 m upwind of the ship: free stream


def rotorpy_params(section: SimSection) -> dict[str, Any]:
    """RotorPy's parameter dictionary of our Phantom 4 (mass, inertia, X layout, parasitic drag, thrust)."""
    p = PHANTOM4
    a = p.arm_length_m / np.sqrt(2.0)
    omega_max = 1000.0                                              # rad/s; k_eta scales thrust to our maximum
    k_eta = p.max_thrust_per_motor_n / omega_max ** 2
    half_rho_cd = 0.5 * section.air_density_kg_m3 * section.drag_coefficient
    return {
        "mass": p.mass_kg, "Ixx": p.inertia_kg_m2[0], "Iyy": p.inertia_kg_m2[1], "Izz": p.inertia_kg_m2[2],
        "Ixy": 0.0, "Iyz": 0.0, "Ixz": 0.0, "num_rotors": 4, "rotor_radius": p.rotor_radius_m,
        "rotor_pos": {"r1": np.array([a, a, 0.0]), "r2": np.array([a, -a, 0.0]), "r3": np.array([-a, -a, 0.0]),
                      "r4": np.array([-a, a, 0.0])},
        "rotor_directions": np.array([1, -1, 1, -1]), "rI": np.zeros(3),
        "c_Dx": half_rho_cd * p.body_width_m * p.body_height_m,
        "c_Dy": half_rho_cd * p.body_length_m * p.body_height_m,
        "c_Dz": half_rho_cd * p.body_length_m * p.body_width_m,
        "k_eta": k_eta, "k_m": p.yaw_torque_per_newton_m * k_eta, "k_d": 0.0, "k_z": 0.0, "k_h": 0.0,
        "k_flap": 0.0, "tau_m": 0.005, "rotor_speed_min": 0.0, "rotor_speed_max": omega_max,
        "motor_noise_std": 0.0, "k_w": 1, "k_v": 10,     # attitude gains: RotorPy's defaults (per unit inertia)
    }


def wind_series(batch: int, dt_s: float, steps: int) -> np.ndarray:
    """(batch, steps, 3) m/s: the batch's wind at the hover point every dt_s (same seed and intensity as the field
    our flights get; the Dryden filter stepped at RotorPy's rate)."""
    field = moderate_wind(SimSection(), batch, 0, dt_s)
    at = np.repeat(HOVER_POINT[None], batch, axis=0)
    return np.stack([field.velocity(at, k * dt_s) for k in range(steps)], axis=1)


def rotorpy_hover(batch: int, series: np.ndarray, section: SimSection) -> tuple[float, float]:
    """(wall s, RMS tracking error m over the second half) of RotorPy holding the hover point."""
    import torch
    from rotorpy.controllers.quadrotor_control import BatchedSE3Control
    from rotorpy.vehicles.multirotor import BatchedMultirotor, BatchedMultirotorParams

    torch.set_num_threads(1)
    device = torch.device("cpu")
    quad = rotorpy_params(section)
    params = BatchedMultirotorParams([quad] * batch, batch, device)
    hover_speed = float(np.sqrt(PHANTOM4.mass_kg * GRAVITY_M_S2 / 4.0 / quad["k_eta"]))
    state = {"x": torch.tensor(np.repeat(HOVER_POINT[None], batch, 0), dtype=torch.double),
             "v": torch.zeros(batch, 3, dtype=torch.double),
             "q": torch.tensor([[0.0, 0.0, 0.0, 1.0]] * batch, dtype=torch.double),
             "w": torch.zeros(batch, 3, dtype=torch.double), "wind": torch.zeros(batch, 3, dtype=torch.double),
             "rotor_speeds": torch.full((batch, 4), hover_speed, dtype=torch.double)}
    vehicle = BatchedMultirotor(params, batch, state, device, integrator="rk4")
    controller = BatchedSE3Control(params, batch, device)
    zeros = torch.zeros(batch, 3, dtype=torch.double)
    flat = {"x": state["x"].clone(), "x_dot": zeros, "x_ddot": zeros, "x_dddot": zeros, "x_ddddot": zeros,
            "yaw": torch.zeros(batch, dtype=torch.double), "yaw_dot": torch.zeros(batch, dtype=torch.double)}
    wind = torch.tensor(series, dtype=torch.double)
    steps = series.shape[1]
    errors = []
    start = time.perf_counter()
    for k in range(steps):       # RotorPy's own loop: one controller update and one vehicle step per dt
        state["wind"] = wind[:, k]
        control = controller.update(k * ROTORPY_DT_S, state, flat)
        state = vehicle.step(state, control, ROTORPY_DT_S)
        if k >= steps // 2:
            errors.append(torch.linalg.norm(state["x"] - flat["x"], dim=1).numpy())
    wall = time.perf_counter() - start
    return wall, float(np.sqrt(np.mean(np.square(errors))))


def ours_hover(batch: int, field: WindModel, section: SimSection) -> tuple[float, float]:
    """(wall s, RMS tracking error m over the second half) of our flights holding the hover point."""
    with FlightSimulator(section) as sim:
        start = time.perf_counter()
        result = sim.hover(field, HOVER_POINT, 0.0, SIM_S, batch, flight_rngs=0)
        wall = time.perf_counter() - start
    tr = result.trajectory
    half = slice(len(tr.time) // 2, None)
    dist = np.linalg.norm(tr.position[:, half] - HOVER_POINT, axis=-1)
    return wall, float(np.sqrt(np.mean(dist ** 2)))


def run_bench() -> list[BenchRecord]:
    try:
        import rotorpy  # noqa: F401  # the optional [peers] extra
    except ImportError:
        log.info("peers: skipped (RotorPy is not installed: pip install '.[peers]')")
        return []
    section = SimSection()
    warm_up_kernels()       # ours: compiled kernels loaded (or compiled) before any timing
    steps = int(round(SIM_S / ROTORPY_DT_S))
    records = []
    for batch in BATCHES:
        series = wind_series(batch, ROTORPY_DT_S, steps)
        ours_wall, ours_err = ours_hover(batch, moderate_wind(section, batch, 0), section)
        peer_wall, peer_err = rotorpy_hover(batch, series, section)
        ours_rate, peer_rate = batch * SIM_S / ours_wall, batch * SIM_S / peer_wall
        note = (f"batch {batch}, {SIM_S:g} s hover in moderate Dryden turbulence (6 m/s mean), Phantom 4 mass and "
                f"drag; ours MuJoCo {section.timestep_s * 1e3:g} ms with every sim default on, RotorPy 3.0.0 "
                f"BatchedMultirotor rk4 {ROTORPY_DT_S * 1e3:g} ms + BatchedSE3Control, 1 torch thread")
        ideal = section.model_copy(update={"navigation": NavigationSection(preset="ideal")})
        _, ideal_err = ours_hover(batch, moderate_wind(section, batch, 0), ideal)
        target: tuple[str | None, float | None] = ("issue 19 target", 10.0) if batch == 1024 else (None, None)
        records += [
            BenchRecord(f"peers.ours_drone_s_per_s.b{batch}", ours_rate, "drone-s/s", None, None, note),
            BenchRecord(f"peers.rotorpy_drone_s_per_s.b{batch}", peer_rate, "drone-s/s", None, None, note),
            BenchRecord(f"peers.rotorpy_ratio.b{batch}", ours_rate / peer_rate, "ratio", *target, note),
            BenchRecord(f"peers.ours_tracking_rms_m.b{batch}", ours_err, "m", None, None,
                        "true position vs hover point, second half; includes the navigation estimate's error"),
            BenchRecord(f"peers.ours_ideal_navigation_tracking_rms_m.b{batch}", ideal_err, "m", None, None,
                        "the same flights with navigation estimate = truth (preset ideal): the controller's own "
                        "tracking, comparable with RotorPy's"),
            BenchRecord(f"peers.rotorpy_tracking_rms_m.b{batch}", peer_err, "m", None, None,
                        "true position vs hover point, second half; controller on the true state"),
        ]
    return records
