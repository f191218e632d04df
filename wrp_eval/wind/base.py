"""The one interface every wind model implements (RotorPy-style plug-in family, batched from the start)."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray


@runtime_checkable
class WindModel(Protocol):
    """Anything with ``velocity(points, t)``.

    points (n, 3) in metres, world frame (x along the ship, z up); t in seconds.
    Returns (n, 3) wind velocity in m/s, world frame. Models with state (turbulence) are built for a batch
    of n flights, row i of ``points`` being flight i, and must be queried with non-decreasing t.
    """

    def velocity(self, points: NDArray[np.float64], t: float) -> NDArray[np.float64]: ...
