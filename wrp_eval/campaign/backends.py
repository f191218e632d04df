"""Where batches of trials run: in the calling process, a local process pool, or Ray tasks.

:class:`TrialPool` is the one interface: ``with TrialPool(kind, workers) as pool: for index, records in
pool.run(tasks)``. A task is ``(spec, trials)``: a worker spec (:func:`wrp_eval.campaign.worker.run_batch`) and
the trial ids (or ready-made :class:`~wrp_eval.campaign.sampling.TrialInputs`) to evaluate together. Batches come
back in completion order, a bounded number in flight (memory stays flat and a kill loses little work). The pool
lives across calls of ``run``, so a caller that decides its next tasks from the last results (the envelope's
sequential cells) starts the worker processes, and builds their evaluators, once.
"""

from __future__ import annotations

import multiprocessing
import os
import socket
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from typing import Any

import numpy as np

from wrp_eval.campaign.records import make_record
from wrp_eval.campaign.worker import ray_run_batch, run_batch, thread_env, trial_inputs_of
from wrp_eval.errors import InputError

IN_FLIGHT_PER_WORKER = 2

# the local process pools shared inside :func:`shared_process_pools`, by (workers, threads); None: not shared
_SHARED_POOLS: dict[tuple[int, int], ProcessPoolExecutor] | None = None

Task = tuple[dict, Sequence]     # (worker spec, trial ids or TrialInputs)


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def split_batches(count: int, batch_size: int, workers: int) -> list[np.ndarray]:
    """Indices 0..count-1 in consecutive batches of at most ``batch_size``, and at least one per worker while
    there are enough: a campaign smaller than ``workers x batch_size`` keeps every worker busy instead of
    handing one worker the whole batch. Sizes differ by at most one."""
    parts = max(1, workers, -(-count // max(1, batch_size)))
    return [chunk for chunk in np.array_split(np.arange(count), parts) if chunk.size]


@contextmanager
def shared_process_pools() -> Iterator[None]:
    """Within this block the local process pools of the same size and thread count are one: a command that flies
    several campaigns one after another (an evaluation's paths and placebos, a study's variants, the pipeline's
    stages) spawns its worker processes, and imports the package in them (~6 s each here), once. Each worker
    still builds the evaluator of every campaign it is given (:func:`wrp_eval.campaign.worker.run_batch` caches
    one by the spec's key). The pools are shut down when the block ends; a pool whose run was aborted or whose
    worker died is shut down at once and the next run starts a fresh one."""
    global _SHARED_POOLS
    if _SHARED_POOLS is not None:       # nested: the outer block owns the pools
        yield
        return
    _SHARED_POOLS = {}
    try:
        yield
    finally:
        pools, _SHARED_POOLS = _SHARED_POOLS, None
        for pool in pools.values():
            pool.shutdown(wait=True, cancel_futures=True)


@contextmanager
def _child_environment(threads: int):
    """Thread limits in the environment while pool processes start (they inherit it at spawn time)."""
    saved = {k: os.environ.get(k) for k in thread_env(threads)}
    os.environ.update(thread_env(threads))
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _crash_records(spec: dict, trials: Sequence, message: str) -> list[dict]:
    """Records for trials whose worker process died every time it tried them."""
    ctx = spec["context"]
    n_views = len(ctx.path)
    return [make_record(inp, None, root_seed=ctx.root_seed, path_digest=ctx.path_digest, n_views=n_views,
                        attempts=spec["max_attempts"], trial_s=0.0, worker=socket.gethostname(),
                        finished_unix=time.time(), error=message)
            for inp in trial_inputs_of(spec, trials)]


class TrialPool:
    """Runs tasks in the calling process (``kind`` local with ``workers`` 0), a pool of ``workers`` spawned
    processes (spawn: no forked copies of MuJoCo/open3d/torch threads) or Ray (``kind`` ray: connects to
    ``address`` or starts a local instance with ``workers`` CPUs, reusing one already initialised in this
    process). ``threads``: CPU threads per worker.

    A local worker process that dies (segfault, OOM kill) breaks the pool: the pool is rebuilt and the batches
    in flight are tried again, up to their spec's ``max_attempts``, then recorded as failed. Ray retries a
    task whose worker died (``max_retries``); exceptions inside a trial are the worker's own retries."""

    def __init__(self, kind: str, workers: int, address: str | None = None, threads: int = 1):
        self.kind, self.workers, self.address, self.threads = kind, workers, address, threads
        self._pool: ProcessPoolExecutor | None = None
        self._ray_started = False
        self._open_runs = 0         # run() generators started and not yet finished or closed

    def __enter__(self) -> "TrialPool":
        if self.kind == "ray":
            self._start_ray()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Shut the pool's processes down and leave Ray if this pool started it. A shared pool stays up for the
        next run when every run of this one has finished (all its batches came back); with a run still open (its
        caller stopped reading it) batches may still be in the pool, so it is shut down and unshared."""
        if self._pool is not None:
            if self._shared(self._pool) and not self._open_runs:
                self._pool = None
            else:
                self._discard(self._pool)
        if self._ray_started:
            import ray
            ray.shutdown()
            self._ray_started = False

    def run(self, tasks: Sequence[Task]) -> Iterator[tuple[int, list[dict]]]:
        """(task index, its records) for every task, in completion order."""
        self._open_runs += 1
        try:
            if self.kind == "ray":
                yield from self._run_ray(tasks)
            elif self.workers == 0:
                for index, (spec, trials) in enumerate(tasks):
                    yield index, run_batch(spec, trials)
            else:
                yield from self._run_local(tasks)
        finally:
            self._open_runs -= 1

    def _shared(self, pool: ProcessPoolExecutor) -> bool:
        return _SHARED_POOLS is not None and _SHARED_POOLS.get((self.workers, self.threads)) is pool

    def _discard(self, pool: ProcessPoolExecutor) -> None:
        """Shut ``pool`` down now, shared or not (a worker died, or the run was aborted with batches running)."""
        if self._shared(pool) and _SHARED_POOLS is not None:
            del _SHARED_POOLS[(self.workers, self.threads)]
        pool.shutdown(wait=True, cancel_futures=True)
        self._pool = None

    def _local_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            key = (self.workers, self.threads)
            if _SHARED_POOLS is not None and key in _SHARED_POOLS:
                self._pool = _SHARED_POOLS[key]
                return self._pool
            with _child_environment(self.threads):
                # no pool initializer: a worker's set-up error (bad ship mesh, netCDF, ...) then surfaces from
                # run_batch as that batch's exception and aborts the run with its message, instead of
                # breaking the pool like a crash
                self._pool = ProcessPoolExecutor(max_workers=self.workers,
                                                 mp_context=multiprocessing.get_context("spawn"))
            if _SHARED_POOLS is not None:
                _SHARED_POOLS[key] = self._pool
        return self._pool

    def _run_local(self, tasks: Sequence[Task]) -> Iterator[tuple[int, list[dict]]]:
        todo = list(range(len(tasks)))[::-1]     # a stack: pop() takes the lowest task first
        crashes: dict[int, int] = {}
        while todo:
            pool = self._local_pool()
            running: dict[Future[list[dict]], int] = {}
            try:
                while todo or running:
                    while todo and len(running) < self.workers * IN_FLIGHT_PER_WORKER:
                        index = todo[-1]
                        with _child_environment(self.threads):
                            # a pool broken while idle (a shared worker died between runs) raises here: the
                            # batch stays in `todo` and goes to the fresh pool
                            future = pool.submit(run_batch, *tasks[index])
                        running[future] = todo.pop()
                    done, _ = wait(running, return_when=FIRST_COMPLETED)
                    for fut in done:
                        records = fut.result()   # a crashed worker raises here, its batch still in `running`
                        yield running.pop(fut), records
            except BrokenProcessPool:
                for index in running.values():
                    crashes[index] = crashes.get(index, 0) + 1
                    spec, trials = tasks[index]
                    if crashes[index] >= spec["max_attempts"]:
                        yield index, _crash_records(spec, trials, "worker process died (BrokenProcessPool)")
                    else:
                        todo.append(index)
                todo.sort(reverse=True)
                self._discard(pool)
            except BaseException:
                # an aborted run (an input error, a kill, the caller closing the generator): no batch of it may
                # still be running when the caller goes on
                self._discard(pool)
                self.close()
                raise

    def _start_ray(self) -> None:
        try:
            import ray  # lazily: Ray is the optional [cluster] extra, needed only by this backend
        except ImportError:
            raise InputError("campaign.backend", "the ray backend needs Ray: pip install '.[cluster]'") from None
        if not ray.is_initialized():
            kwargs: dict[str, Any] = dict(include_dashboard=False, log_to_driver=False, configure_logging=False)
            if self.address:
                ray.init(address=self.address, **kwargs)
            else:
                ray.init(num_cpus=max(1, self.workers), **kwargs)
            self._ray_started = True

    def _run_ray(self, tasks: Sequence[Task]) -> Iterator[tuple[int, list[dict]]]:
        import ray
        refs: dict[int, ray.ObjectRef[dict]] = {}              # one object-store copy per distinct spec
        remote = {}
        limit = max(1, int(ray.cluster_resources().get("CPU", self.workers))) * IN_FLIGHT_PER_WORKER
        todo = list(range(len(tasks)))[::-1]
        running: dict = {}
        while todo or running:
            while todo and len(running) < limit:
                index = todo.pop()
                spec, trials = tasks[index]
                attempts = spec["max_attempts"]
                if attempts not in remote:
                    remote[attempts] = ray.remote(num_cpus=1, max_retries=attempts,
                                                  retry_exceptions=False)(ray_run_batch)
                if id(spec) not in refs:
                    refs[id(spec)] = ray.put(spec)
                running[remote[attempts].remote(refs[id(spec)], trials)] = index
            ready, _ = ray.wait(list(running), num_returns=1)
            for ref in ready:
                index = running.pop(ref)
                try:
                    records = ray.get(ref)
                except ray.exceptions.RayTaskError as err:  # set-up error in the task: abort with its message
                    raise (err.cause if isinstance(err.cause, Exception) else err) from None
                except ray.exceptions.RayError as err:  # the task's worker died max_retries + 1 times
                    records = _crash_records(tasks[index][0], tasks[index][1],
                                             f"ray task failed: {type(err).__name__}")
                yield index, records
