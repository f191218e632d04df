"""``wrp-eval bench --only study``: every paper table's smallest setting (``wrp-eval run --smallest``), timed.

study.table<N>_smallest_s: wall seconds of experiments/paper/table<N>.yaml at its ``study.smallest`` setting, run
from scratch in a temporary folder (no stored campaign to resume). These are the runs the test suite made one by
one before issue 28 moved tables 3, 4 and 5 here (each trains its own surrogate on 12 flights: 19.0-42.9 s apiece,
81.7 s together, on the 2-core machine); the suite runs those three tables' base config once, as one study
holding a variant of each kind (tests/test_study.py, 25-34 s). Each table's rows are checked against its variants
(one row each, ``repetitions`` for the random offsets): a table whose rows differ, or whose run fails, raises and
the bench stops with its error. The first table's time includes the process's first imports and kernel loads
(~20 s here). No anchor: the paper gives no run times for these settings.
"""

from __future__ import annotations

import contextlib
import tempfile
import time

from wrp_eval.bench_record import BenchRecord
from wrp_eval.experiment import ExperimentContext
from wrp_eval.resources import source_experiments_dir
from wrp_eval.study.runner import run_study, variant_configs

PAPER = source_experiments_dir() / "paper"
TABLES = range(1, 9)


def smallest_record(table: int) -> BenchRecord:
    """Run table ``table``'s paper config at its smallest setting in a fresh temporary folder; its wall time."""
    ctx = ExperimentContext.load(PAPER / f"table{table}.yaml")
    with tempfile.TemporaryDirectory() as tmp, contextlib.chdir(tmp):    # the study writes logs/<run>/ here
        start = time.perf_counter()
        doc = run_study(ctx, smallest=True)
        wall = time.perf_counter() - start
    expected = [v.name for v, _ in variant_configs(ctx.config, ctx.source, smallest=True) for _ in range(v.repetitions)]
    if [r["variant"] for r in doc["rows"]] != expected:
        raise ValueError(f"table {table}: rows {[r['variant'] for r in doc['rows']]}, expected {expected}")
    note = (f"{len(doc['rows'])} rows of {len(set(expected))} variants, "
            f"{len(doc['shared_training'])} surrogate(s) trained")
    return BenchRecord(f"study.table{table}_smallest_s", wall, "s", note=note)


def run_bench() -> list[BenchRecord]:
    if not PAPER.is_dir():
        raise FileNotFoundError(f"{PAPER}: the paper configs ship with a source checkout, not with the package")
    return [smallest_record(table) for table in TABLES]
