"""Discrete "1 - cosine" gusts (MIL-F-8785C Sec. 3.7.4 shape), drawn per flight.

A gust starting at t0 with amplitude A, duration T and unit direction d adds
    A/2 (1 - cos(2 pi (t - t0) / T)) d      for t0 <= t <= t0 + T
(the full 1-cosine: it rises to A at mid-gust and falls back). Gust onsets form a Poisson process of rate
``rate_per_min``; directions are the flight's mean-wind azimuth plus a uniform spread, horizontal. Every draw
comes from each flight's own Generator, all at construction (a fixed horizon), so queries are pure functions
of t, and a flight's gusts do not depend on the other flights of its batch, bit for bit (each flight's sum
runs over its own gusts, as for a flight alone).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.streams import FlightRngs, flight_generators


class OneMinusCosineGusts:
    """Gusts for ``n_flights`` flights over ``horizon_s`` seconds; ``velocity(points, t)`` -> (n, 3) m/s.

    mean_azimuth_rad: scalar or (n_flights,): each flight's mean-wind azimuth (CCW from +x, radians).
    start_s, azimuth_rad (n_flights, g): onsets (s, ascending, padded with inf = never) and azimuths (rad).
    """

    def __init__(self, n_flights: int, rngs: FlightRngs, horizon_s: float, rate_per_min: float, amplitude_m_s: float,
                 duration_s: float, mean_azimuth_rad: ArrayLike = 0.0, direction_spread_deg: float = 30.0) -> None:
        rngs = flight_generators(rngs, n_flights)
        if duration_s <= 0 or horizon_s <= 0 or rate_per_min < 0:
            raise ValueError("gust duration and horizon must be > 0 and the rate >= 0")
        self.n_flights = n_flights
        self.amplitude_m_s = float(amplitude_m_s)
        self.duration_s = float(duration_s)
        mean_azimuth = np.broadcast_to(np.asarray(mean_azimuth_rad, dtype=float), (n_flights,))
        starts, azimuths = [], []
        spread = np.deg2rad(direction_spread_deg)
        for g, azimuth in zip(rngs, mean_azimuth, strict=True):  # once per flight at construction, never per step
            count = g.poisson(rate_per_min / 60.0 * horizon_s)
            starts.append(np.sort(g.uniform(0.0, horizon_s, count)))
            azimuths.append(azimuth + g.uniform(-spread, spread, count))
        width = max([len(s) for s in starts] + [1])
        self.start_s = np.full((n_flights, width), np.inf)      # padded with "never"
        self.azimuth_rad = np.zeros((n_flights, width))
        for i, (s, a) in enumerate(zip(starts, azimuths, strict=True)):
            self.start_s[i, :len(s)] = s
            self.azimuth_rad[i, :len(a)] = a

    def velocity(self, points: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        """Sum of the gusts active at time t, (n_flights, 3) m/s in the world frame."""
        phase = (t - self.start_s) / self.duration_s              # (n, g)
        active = (phase >= 0.0) & (phase <= 1.0)
        mag = np.where(active, 0.5 * self.amplitude_m_s * (1.0 - np.cos(2 * np.pi * np.where(active, phase, 0))), 0)
        # Each flight's sum runs over its own gusts only (the first ``count`` columns), in one call per distinct
        # count: numpy's pairwise summation groups a row's terms by the row's length, so a sum over the padded
        # row would make a flight's last bits depend on the other flights' gust counts (its batch).
        count = np.isfinite(self.start_s).sum(axis=1)
        out = np.zeros((self.n_flights, 3))
        for c in np.unique(count[count > 0]):                  # a few distinct counts per batch
            rows = np.flatnonzero(count == c)
            m = mag[rows, :c]
            out[rows, 0] = (m * np.cos(self.azimuth_rad[rows, :c])).sum(axis=1)
            out[rows, 1] = (m * np.sin(self.azimuth_rad[rows, :c])).sum(axis=1)
        return out
