"""BLAS on one thread while a flight runs (wrp_eval/blas.py): OpenBLAS threads left spinning after a threaded call
take a core from the rollout's threads."""

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from wrp_eval.blas import single_threaded_blas
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.flight import FlightSimulator
from wrp_eval.sim.simple_wind import ConstantWind


def _blas_threads() -> list[int]:
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


@pytest.fixture(autouse=True)
def two_blas_threads():
    """Two BLAS threads around each test, whatever the machine's default, so that a missing limit shows."""
    with threadpool_limits(limits=2, user_api="blas"):
        yield


def test_blas_is_single_threaded_inside_the_context_and_restored_after():
    before = _blas_threads()
    assert before and all(threads == 2 for threads in before)
    with single_threaded_blas():
        assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before


class _SpyWind(ConstantWind):
    """A uniform wind that notes the BLAS thread counts whenever the simulator asks it for the wind."""

    seen: list[list[int]]

    def velocity(self, points, t):
        self.seen.append(_blas_threads())
        return super().velocity(points, t)


def test_a_flight_and_a_hover_run_with_blas_on_one_thread():
    wind = _SpyWind(np.array([3.0, 0.0, 0.0]))
    wind.seen = []
    before = _blas_threads()
    assert all(threads == 2 for threads in before)
    sec = SimSection().model_copy(update={"max_flight_time_s": 1.0})
    with FlightSimulator(sec) as sim:
        sim.hover(wind, [0.0, 0.0, 20.0], 0.0, 0.5, batch=2, flight_rngs=0)
    assert wind.seen and all(threads == [1] * len(before) for threads in wind.seen)
    assert _blas_threads() == before
