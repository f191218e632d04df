"""Compile (or load) wrp_eval's numba kernels once, in this one process: the processes started after it (the test
suite's workers and the pools they start) then load them from the cache (``wrp_eval.compiled.kernel_cache_dir``)
instead of each compiling them. `make test` runs it beside mypy before the suite: on a fresh clone the suite
compiles every kernel in several processes at once otherwise (measured in the Makefile's comment).

What it runs: the quickstart ship planned (planning kernels), its plan scored by the synthetic oracle (recon),
and a one-second flight of the simulator's bench path in each capture mode plus a hover (flight, wind, camera).
"""

from __future__ import annotations

import time

from wrp_eval.config import ExperimentConfig
from wrp_eval.experiment import ExperimentContext
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.sim.bench import bench_path, moderate_wind, ship_in_scene, warm_up_kernels
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.flight import FlightSimulator


def main() -> None:
    start = time.perf_counter()
    ctx = ExperimentContext(ExperimentConfig())
    path = ctx.planned.path
    ctx.scored_ship.score(captures_from_path(path), 0)
    warm_up_kernels()
    section = SimSection().model_copy(update={"max_flight_time_s": 1.0})
    section = section.model_copy(update={"capture": section.capture.model_copy(update={"mode": "fly-through"})})
    with FlightSimulator(section) as sim:
        sim.fly(bench_path(), moderate_wind(section, 1, 0), 1, ship=ship_in_scene(), flight_rngs=0)
    print(f"kernels compiled or loaded in {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
