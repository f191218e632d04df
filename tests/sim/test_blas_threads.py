"""A batch flies with BLAS on one thread (sim/flight.py ``_BLAS_LIMIT``): OpenBLAS threads left spinning after a
threaded call take a core from the rollout's threads."""

from threadpoolctl import threadpool_info, threadpool_limits

from tests.sim.conftest import make_path
from wrp_eval.sim.simple_wind import ConstantWind


def _blas_threads() -> list[int]:
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


class _SpyWind(ConstantWind):
    """A constant wind that notes the BLAS thread counts whenever the simulator asks it for the wind."""

    def __init__(self, velocity_m_s):
        super().__init__(velocity_m_s)
        self.seen: list[list[int]] = []

    def velocity(self, points, t):
        self.seen.append(_blas_threads())
        return super().velocity(points, t)


def test_a_flight_and_a_hover_run_with_blas_on_one_thread_and_restore_it(simulator):
    hovering, flying = _SpyWind([3.0, 0.0, 0.0]), _SpyWind([3.0, 0.0, 0.0])
    with threadpool_limits(limits=2, user_api="blas"):      # whatever the machine's default: a missing limit shows
        before = _blas_threads()
        assert before and all(threads == 2 for threads in before)
        simulator.hover(hovering, [0.0, 0.0, 20.0], 0.0, 0.5, batch=2, flight_rngs=0)
        assert _blas_threads() == before
        simulator.fly(make_path(2), flying, 2, flight_rngs=0)
        assert _blas_threads() == before
    for seen in (hovering.seen, flying.seen):
        assert seen and all(threads == [1] * len(before) for threads in seen)
