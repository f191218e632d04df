"""A constant wind for hover checks against the analytic weight/drag balance.

It implements the :class:`wrp_eval.wind.base.WindModel` protocol ``velocity(points (n,3), t) -> (n,3)``,
row i being flight i. The real models (mesoscale field + Dryden turbulence) live in ``wrp_eval.wind``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from wrp_eval.frames import wind_velocity


class ConstantWind:
    """The same wind vector (3,) m/s, ship frame, everywhere, always."""

    def __init__(self, velocity_m_s: ArrayLike) -> None:
        self.vector = np.asarray(velocity_m_s, dtype=float).reshape(3)

    @classmethod
    def blowing_from(cls, speed_m_s: float, direction_from_deg: float, ship_heading_deg: float) -> "ConstantWind":
        """A wind of ``speed_m_s`` blowing FROM the compass bearing ``direction_from_deg`` (degrees clockwise
        from true north, the project's one convention: :mod:`wrp_eval.frames`), in the frame of a ship with
        true heading ``ship_heading_deg``."""
        return cls(wind_velocity(speed_m_s, np.radians(direction_from_deg), np.radians(ship_heading_deg)))

    def velocity(self, points: np.ndarray, t: float) -> np.ndarray:
        return np.broadcast_to(self.vector, (len(points), 3)).copy()
