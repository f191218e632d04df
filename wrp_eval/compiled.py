"""The one way wrp_eval compiles a kernel: :func:`kernel`, numba's ``njit`` with the project's settings.

Why compiled kernels at all (issue 19, measured in sim/README.md): between two ``mujoco.rollout`` chunks the
flight loop evaluates the wind, the position loop and the drag for the whole batch. At the campaign's
batch of 64 each numpy call costs ~1 us whatever its size, and those functions are dozens of calls each, so
the loop was bound by per-call overhead, not arithmetic. A kernel is one call with a plain loop over the
rows inside: each row is computed on its own, so a row's result never depends on the batch it is in.

Settings, in one place: ``cache=True`` (compiled once per machine into ``__pycache__``, later processes load
it); ``nogil=True`` (a kernel may run beside the rollout threads); ``error_model="numpy"``: a division by zero
gives inf / nan as in numpy instead of raising; no ``fastmath``: IEEE arithmetic, so a
kernel's formulas give what the same formulas give in numpy up to the rounding of library functions (exp,
pow, ...), a few ulps.
"""

from __future__ import annotations

import numba


def kernel(function):
    """``function`` compiled by numba (nopython mode) with the project's settings (module docstring)."""
    return numba.njit(cache=True, nogil=True, error_model="numpy")(function)
