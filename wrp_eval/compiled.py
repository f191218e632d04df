"""The one way wrp_eval compiles a kernel: :func:`kernel`, numba's ``njit`` with the project's settings.

Why compiled kernels at all (issue 19, measured in sim/README.md): between two ``mujoco.rollout`` chunks the
flight loop evaluates the wind, the position loop and the drag for the whole batch. At the campaign's
batch of 64 each numpy call costs ~1 us whatever its size, and those functions are dozens of calls each, so
the loop was bound by per-call overhead, not arithmetic. A kernel is one call with a plain loop over the
rows inside: each row is computed on its own, so a row's result never depends on the batch it is in.

Settings, in one place: ``cache=True`` (compiled once, later processes load it); ``nogil=True`` (a kernel
may run beside the rollout threads); ``error_model="numpy"``: a division by zero gives inf / nan as in numpy
instead of raising; no ``fastmath``: IEEE arithmetic, so a kernel's formulas give what the same formulas
give in numpy up to the rounding of library functions (exp, pow, ...), a few ulps.

Where the compiled code is kept: :func:`kernel_cache_dir`, not numba's default ``__pycache__`` beside each
file. numba invalidates a cached kernel only when the kernel's own file changes, while a kernel also freezes
what it takes from other files: another file's kernel (``_body_rows`` -> ``controller.quat_row_to_matrix``)
and constants (``vehicle.GRAVITY_M_S2``, the phase codes of ``flight_state``), so an edit there would leave
the cached kernel on the old code. The folder is named after the sources of the whole package: any edit
starts a fresh folder (the kernels compile again, ~10 s, once). An explicit ``NUMBA_CACHE_DIR`` in the
environment is left as it is.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import numba
import numpy as np
from numpy.typing import ArrayLike, DTypeLike, NDArray

from wrp_eval.resources import cache_dir

_PACKAGE = Path(__file__).resolve().parent


def kernel_sources_digest(package: Path = _PACKAGE) -> str:
    """16 hex digits of SHA-256 over every module of ``package`` (relative path and content, in path order)."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def kernel_cache_dir() -> Path:
    """numba's cache folder for these sources: ``cache_dir("numba", kernel_sources_digest())`` (folders of
    older sources are left behind: a few MB each, in the cache folder the user may empty)."""
    return cache_dir("numba", kernel_sources_digest())


if not os.environ.get("NUMBA_CACHE_DIR"):
    # the environment for processes started from this one (campaign workers compute the same folder), the
    # config for the kernels decorated from now on (numba reads it when a kernel is decorated)
    os.environ["NUMBA_CACHE_DIR"] = str(kernel_cache_dir())
    numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]  # type: ignore[attr-defined]  # numba sets it at run time


def as_rows(name: str, array: ArrayLike, shape: tuple[int, ...], dtype: DTypeLike = float) -> NDArray[Any]:
    """``array`` as ``dtype`` with ``shape`` (a number or another broadcastable shape is broadcast to it), or a
    ValueError naming ``name``. A kernel does not check its indices (numba: no bounds checks), so every array
    a kernel reads or writes row by row passes through here first: a wrong shape is an error, not a silent
    read or write past the end."""
    rows = np.asarray(array, dtype=dtype)
    if rows.shape == shape:
        return rows
    try:
        return np.broadcast_to(rows, shape)
    except ValueError:
        raise ValueError(f"{name} must have shape {shape}, got {rows.shape}") from None


def contiguous(array: ArrayLike, dtype: DTypeLike = float) -> NDArray[Any]:
    """``array`` as a C-contiguous, writeable ``dtype`` array of at least one dimension (a number becomes shape
    (1,)), copied only where it is not one already. numba compiles (or loads) a kernel once per argument layout
    and read-only flag: a caller that hands it a strided view or a read-only array costs a second compilation,
    ~1 s on a machine with an empty kernel cache."""
    out = np.ascontiguousarray(array, dtype=dtype)
    return out if out.flags.writeable else out.copy()


KernelFunction = TypeVar("KernelFunction", bound=Callable[..., Any])


def kernel(function: KernelFunction) -> KernelFunction:
    """``function`` compiled by numba (nopython mode) with the project's settings (module docstring). Typed as
    the function it compiles: numba ships no type information, and the dispatcher takes the same arguments."""
    return cast(KernelFunction, numba.njit(cache=True, nogil=True, error_model="numpy")(function))
