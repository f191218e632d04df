"""BLAS threads while the simulator's own threads run.

OpenBLAS (numpy's and scipy's) keeps the threads of a call it ran threaded busy-waiting for work for about 0.1 s
after the call returns. Measured on this 2-core machine: after ``scipy.linalg.solve_discrete_are`` of a small
system (the navigation filter's gain, solved when a flight starts) the process burnt 0.107 s of CPU during a
0.3 s sleep, and 0 s after a 3 x 3 product. During a flight that spin takes a core from ``mujoco.rollout``'s
threads: the batch-64 bench flight's rollout took 0.29-0.31 s inside the flight loop against 0.25-0.28 s for
the same calls replayed back to back, and 0.27-0.28 s inside the loop with BLAS on one thread
(wrp_eval/sim/README.md). A flight's linear algebra is a few small matrices, which BLAS threads cannot speed up.

threadpoolctl (a maintained library, scikit-learn's) sets the loaded BLAS libraries' thread counts and restores
them; the environment variables (OPENBLAS_NUM_THREADS) act only before the libraries load.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from functools import cache
from typing import Any, cast

from threadpoolctl import ThreadpoolController


@cache
def _controller() -> ThreadpoolController:
    """The BLAS libraries loaded when first asked (numpy's and scipy's: both are imported by then); looking them
    up costs ~0.7 ms, a limit on the kept controller ~20 us."""
    import scipy.linalg  # noqa: F401  (loads scipy's own OpenBLAS, so the controller sees it)
    return ThreadpoolController()


def single_threaded_blas() -> AbstractContextManager[Any]:
    """Context in which every loaded BLAS library runs on one thread (restored on exit)."""
    return cast(AbstractContextManager[Any], _controller().limit(limits=1, user_api="blas"))
