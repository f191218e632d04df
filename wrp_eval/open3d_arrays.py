"""numpy arrays into open3d's tensor API (the ray casts of the planner and the oracle)."""

from __future__ import annotations

import numpy as np
import open3d as o3d
from numpy.typing import NDArray


def o3d_tensor(array: NDArray[np.generic]) -> o3d.core.Tensor:
    """``o3d.core.Tensor(array)``: a copy of ``array`` (its dtype) on the CPU."""
    tensor: o3d.core.Tensor = o3d.core.Tensor(array)  # type: ignore[call-overload]  # stubs omit dtype / device defaults
    return tensor
