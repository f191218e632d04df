"""What runs inside a worker (a pool process, a Ray worker or the calling process): one batch of trials.

The evaluator is built once per process (cached by the spec's key); an error while building it (bad input)
propagates and stops the campaign. A batch whose evaluation raises is retried trial by trial, each trial
alone up to ``max_attempts`` times; a trial that still raises is recorded as failed with its error, and the
rest of the batch goes on.
"""

from __future__ import annotations

import os
import socket
import sys
import time
import traceback
from collections.abc import Sequence

from wrp_eval.campaign.evaluators import TrialEvaluator, resolve_factory
from wrp_eval.campaign.records import make_record
from wrp_eval.campaign.sampling import TrialInputs, trial_inputs
from wrp_eval.errors import InputError

THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS")

_STATE: dict = {}


def thread_env(threads: int) -> dict[str, str]:
    """Environment that keeps numpy/BLAS/OpenMP (torch, open3d) to ``threads`` threads per worker."""
    return {name: str(threads) for name in THREAD_ENV}


def _limit_threads(threads: int) -> None:
    """Keep this process's numerical libraries to ``threads`` threads. torch is not imported for it (the flight
    and analytic evaluators never use torch, and importing it took a worker's imports from ~2.2 to ~4.0 s here):
    a torch imported later sizes its intra-op pool from OMP_NUM_THREADS, set here; one already imported (or
    imported by an evaluator's set-up, :func:`init_worker` calls this again) is told directly."""
    os.environ.update(thread_env(threads))
    torch = sys.modules.get("torch")
    if torch is None:
        return
    try:  # torch sizes its pools from its own setting, not only the environment
        torch.set_num_threads(threads)
        torch.set_num_interop_threads(threads)
    except RuntimeError:  # its interop pool already started
        pass


def init_worker(spec: dict) -> None:
    """Build this process's evaluator for ``spec`` (:func:`wrp_eval.campaign.runner.worker_spec`) unless already
    built."""
    if _STATE.get("key") == spec["key"]:
        return
    context = spec["context"]
    _limit_threads(context.threads)
    factory = resolve_factory(spec["evaluator"])
    _STATE.clear()
    evaluator: TrialEvaluator = factory(context, **spec["evaluator_options"])
    _limit_threads(context.threads)     # again: a plug-in evaluator may have imported torch in its set-up
    _STATE.update(key=spec["key"], evaluator=evaluator,
                  worker=f"{socket.gethostname()}:{os.getpid()}")


def _error_text(err: BaseException) -> str:
    last = traceback.extract_tb(err.__traceback__)[-1:] if err.__traceback__ else []
    where = f" (at {last[0].filename}:{last[0].lineno})" if last else ""
    return f"{type(err).__name__}: {err}{where}"


def trial_inputs_of(spec: dict, trials: Sequence) -> list[TrialInputs]:
    """The inputs of ``trials``: trial ids are drawn from the spec's campaign section; ready-made
    :class:`TrialInputs` (the envelope's cells, each with its own wind) are taken as they are."""
    ctx = spec["context"]
    return [t if isinstance(t, TrialInputs) else trial_inputs(ctx.trial.campaign, ctx.root_seed, t, len(ctx.path))
            for t in trials]


def run_batch(spec: dict, trials: Sequence) -> list[dict]:
    """Evaluate ``trials`` (trial ids or :class:`TrialInputs`) together; returns one record (dict of
    :data:`SCHEMA`) per trial, in their order. The evaluator is cached by ``spec["key"]``: specs that share a
    key must differ only in what reaches the evaluator through the trial inputs (the campaign's draws)."""
    try:
        init_worker(spec)
    except InputError:
        raise  # pickles across the process boundary; the runner stops the campaign with its one line
    except Exception as err:  # noqa: BLE001 - a bug, not an input: keep its text across the process boundary
        raise RuntimeError(f"campaign worker set-up failed: {_error_text(err)}") from None
    st = _STATE
    ctx = spec["context"]
    inputs = trial_inputs_of(spec, trials)
    max_attempts = int(spec["max_attempts"])

    def record(inp, outcome, attempts, seconds, error=None):
        return make_record(inp, outcome, root_seed=ctx.root_seed, path_digest=ctx.path_digest,
                           n_views=len(ctx.path), attempts=attempts, trial_s=seconds, worker=st["worker"],
                           finished_unix=time.time(), error=error)

    start = time.perf_counter()
    try:
        outcomes = st["evaluator"].evaluate(inputs)
        if len(outcomes) != len(inputs):
            raise RuntimeError(f"evaluator returned {len(outcomes)} outcomes for {len(inputs)} trials")
    except Exception:  # noqa: BLE001 - any failure of the batch: fall back to trial-by-trial retries
        outcomes = None
    if outcomes is not None:
        per_trial = (time.perf_counter() - start) / len(inputs)
        return [record(i, o, 1, per_trial) for i, o in zip(inputs, outcomes, strict=True)]
    records = []
    for inp in inputs:
        error = None
        for attempt in range(1, max_attempts + 1):
            t0 = time.perf_counter()
            try:
                (outcome,) = st["evaluator"].evaluate([inp])
                records.append(record(inp, outcome, attempt, time.perf_counter() - t0))
                break
            except Exception as err:  # noqa: BLE001 - recorded, the campaign goes on
                error = _error_text(err)
        else:
            records.append(record(inp, None, max_attempts, time.perf_counter() - t0, error=error))
    return records


def ray_run_batch(spec: dict, trials: Sequence) -> list[dict]:
    """The Ray task body (same as :func:`run_batch`; a separate name so Ray ships a plain function)."""
    return run_batch(spec, trials)
