"""``wrp-eval bench --only wind``: Dryden spectral accuracy and wind-query speed.

No paper figure exists for these; the accuracy targets come from MIL-F-8785C's analytic spectra.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import NDArray
from scipy.signal import welch

from wrp_eval.bench_record import BenchRecord
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.dryden import DrydenTurbulence, dryden_parameters, dryden_psd
from wrp_eval.wind.field import build_wind_field

CASES = ((10.0, 5.0), (10.0, 12.0), (50.0, 5.0), (50.0, 12.0))   # (altitude m, W20 m/s); V = W20


def psd_check(altitude_m: float, w20_mps: float, n_flights: int = 64, n_steps: int = 20_000, dt_s: float = 0.05,
              seed: int = 0, nperseg: int = 4096) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(mean |dB error| per axis (3,), std error % per axis (3,)) of a batch of Dryden series against the
    analytic one-sided PSDs over 0.01 Hz .. fs/5 (Welch, averaged over the flights)."""
    turb = DrydenTurbulence(n_flights, dt_s, seed, w20_mps)
    series = turb.generate(n_steps, altitude_m, w20_mps)
    sigma, length = dryden_parameters(altitude_m, w20_mps)
    f, psd = welch(series, fs=1.0 / dt_s, nperseg=nperseg, axis=1)
    psd = psd.mean(axis=0)                                            # (n_freq, 3) per Hz
    band = (f >= 0.01) & (f <= 0.2 / dt_s)
    analytic = dryden_psd(2 * np.pi * f[band], sigma, length, w20_mps) * 2 * np.pi   # per rad/s -> per Hz
    db = np.abs(10 * np.log10(psd[band] / analytic)).mean(axis=0)
    std_err = 100 * np.abs(series.reshape(-1, 3).std(axis=0) / sigma - 1)
    return db, std_err


def points_per_s(n_points: int = 1024, n_steps: int = 200, dt_s: float = 0.01) -> float:
    """Velocity queries per second of the full default field (synthetic mean + Dryden), 1024 flights."""
    field = build_wind_field([WindSection()] * n_points, (0.0, 0.0, 0.0), 0, dt_s)
    rng = np.random.default_rng(1)
    points = np.c_[rng.uniform(-250, 250, (n_points, 2)), rng.uniform(5, 150, n_points)]
    field.velocity(points, 0.0)
    start = time.perf_counter()
    for k in range(1, n_steps + 1):   # one call per simulation step, as the simulator makes them
        field.velocity(points, k * dt_s)
    return n_points * n_steps / (time.perf_counter() - start)


def run_bench() -> list[BenchRecord]:
    worst_db, worst_std = 0.0, 0.0
    notes = []
    for altitude, w20 in CASES:
        db, std = psd_check(altitude, w20)
        worst_db, worst_std = max(worst_db, db.max()), max(worst_std, std.max())
        notes.append(f"h={altitude:g}m W20={w20:g}: dB u/v/w {np.round(db, 2).tolist()}, "
                     f"std% {np.round(std, 2).tolist()}")
    anchor = "MIL-F-8785C analytic Dryden PSD (target < 1 dB, < 5 %)"
    return [
        BenchRecord("wind.psd_err_db", float(worst_db), "dB", anchor, 1.0,
                    "worst axis and case of the mean |Welch - analytic| over 0.01 Hz..fs/5; 64 flights x 20k "
                    "steps, dt 0.05 s; " + "; ".join(notes)),
        BenchRecord("wind.sigma_err_pct", float(worst_std), "%", anchor, 5.0,
                    "worst axis and case of |std/sigma - 1|"),
        BenchRecord("wind.points_per_s", points_per_s(), "points/s", None, None,
                    "no paper figure: synthetic mean (IDW) + Dryden, 1024 flights, one call per step"),
    ]
