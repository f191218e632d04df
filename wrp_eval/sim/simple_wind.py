"""A constant wind for hover checks against the analytic weight/drag balance.

It implements the :class:`wrp_eval.wind.base.WindModel` protocol ``velocity(points (n,3), t) -> (n,3)``,
row i being flight i. The real models (mesoscale field + Dryden turbulence) live in ``wrp_eval.wind``.
"""

from __future__ import annotations

import numpy as np


def mean_wind_vector(speed_m_s: float, direction_from_deg: float) -> np.ndarray:
    """(3,) wind velocity for a wind blowing FROM ``direction_from_deg`` (meteorological style, measured
    CCW from +x like every yaw in this project: 0 = wind from the bow, blowing towards -x)."""
    a = np.radians(direction_from_deg)
    return -speed_m_s * np.array([np.cos(a), np.sin(a), 0.0])


class ConstantWind:
    """The same wind vector everywhere, always."""

    def __init__(self, velocity_m_s):
        self.vector = np.asarray(velocity_m_s, dtype=float).reshape(3)

    def velocity(self, points: np.ndarray, t: float) -> np.ndarray:
        return np.broadcast_to(self.vector, (len(points), 3)).copy()
