"""Where batches of trials run: in the calling process, a local process pool, or Ray tasks.

Each backend is a generator of completed batches (lists of records), in completion order, keeping a bounded
number of batches in flight (so that memory stays flat and a kill loses little work).
"""

from __future__ import annotations

import multiprocessing
import os
import socket
import time
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager

from wrp_eval.campaign.records import make_record
from wrp_eval.campaign.sampling import trial_inputs
from wrp_eval.campaign.worker import ray_run_batch, run_batch, thread_env
from wrp_eval.errors import InputError

IN_FLIGHT_PER_WORKER = 2


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def run_serial(spec: dict, batches: list[list[int]]) -> Iterator[list[dict]]:
    """Every batch in the calling process (``workers: 0``)."""
    for ids in batches:
        yield run_batch(spec, ids)


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


def _crash_records(spec: dict, ids: list[int], message: str) -> list[dict]:
    """Records for trials whose worker process died every time it tried them."""

    ctx = spec["context"]
    n_views = len(ctx.path)
    return [make_record(trial_inputs(ctx.trial.campaign, ctx.root_seed, k, n_views), None, root_seed=ctx.root_seed,
                        path_digest=ctx.path_digest, n_views=n_views, attempts=spec["max_attempts"],
                        trial_s=0.0, worker=socket.gethostname(), finished_unix=time.time(), error=message)
            for k in ids]


def run_local(spec: dict, batches: list[list[int]], workers: int) -> Iterator[list[dict]]:
    """A pool of ``workers`` spawned processes (spawn: no forked copies of MuJoCo/open3d/torch threads).

    A worker process that dies (segfault, OOM kill) breaks the pool: the pool is rebuilt and the batches in
    flight are tried again, up to ``max_attempts`` times, then recorded as failed."""
    ctx = multiprocessing.get_context("spawn")
    todo = list(enumerate(batches))[::-1]  # a stack: pop() takes the lowest batch first
    crashes: dict[int, int] = {}
    while todo:
        with _child_environment(spec["context"].threads):
            # no pool initializer: a worker's set-up error (bad ship mesh, netCDF, ...) then surfaces from
            # run_batch as that batch's exception and aborts the campaign with its message, instead of
            # breaking the pool like a crash
            pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx)
        running = {}
        try:
            while todo or running:
                while todo and len(running) < workers * IN_FLIGHT_PER_WORKER:
                    index, ids = todo.pop()
                    with _child_environment(spec["context"].threads):
                        running[pool.submit(run_batch, spec, ids)] = (index, ids)
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for fut in done:
                    index, ids = running.pop(fut)
                    yield fut.result()
        except BrokenProcessPool:
            for fut, (index, ids) in running.items():
                crashes[index] = crashes.get(index, 0) + 1
                if crashes[index] >= spec["max_attempts"]:
                    yield _crash_records(spec, ids, "worker process died (BrokenProcessPool)")
                else:
                    todo.append((index, ids))
            todo.sort(key=lambda item: -item[0])
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def run_ray(spec: dict, batches: list[list[int]], workers: int, address: str | None) -> Iterator[list[dict]]:
    """Ray tasks (``pip install .[cluster]``). Connects to ``address`` or starts a local instance with
    ``workers`` CPUs (reusing one already initialised in this process). Tasks are retried by Ray when a
    worker dies (``max_retries``); exceptions inside a trial are handled by the worker's own retries."""
    try:
        import ray  # lazily: Ray is the optional [cluster] extra, needed only by this backend
    except ImportError:
        raise InputError("campaign.backend", "the ray backend needs Ray: pip install '.[cluster]'") from None
    started_here = False
    if not ray.is_initialized():
        kwargs = dict(include_dashboard=False, log_to_driver=False, configure_logging=False)
        if address:
            ray.init(address=address, **kwargs)
        else:
            ray.init(num_cpus=workers, **kwargs)
        started_here = True
    try:
        task = ray.remote(num_cpus=1, max_retries=spec["max_attempts"], retry_exceptions=False)(ray_run_batch)
        spec_ref = ray.put(spec)
        limit = max(1, int(ray.cluster_resources().get("CPU", workers))) * IN_FLIGHT_PER_WORKER
        todo = list(batches)[::-1]
        running: dict = {}
        while todo or running:
            while todo and len(running) < limit:
                ids = todo.pop()
                running[task.remote(spec_ref, ids)] = ids
            ready, _ = ray.wait(list(running), num_returns=1)
            for ref in ready:
                ids = running.pop(ref)
                try:
                    records = ray.get(ref)
                except ray.exceptions.RayTaskError as err:  # set-up error in the task: abort with its message
                    raise (err.cause if isinstance(err.cause, Exception) else err) from None
                except ray.exceptions.RayError as err:  # the task's worker died max_retries + 1 times
                    records = _crash_records(spec, ids, f"ray task failed: {type(err).__name__}")
                yield records
    finally:
        if started_here:
            ray.shutdown()
