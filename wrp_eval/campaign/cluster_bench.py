"""``wrp-eval bench --only cluster``: a campaign on a two-node Ray cluster.

Runs ``scripts/ray_two_node.sh`` (``ray start --head`` + ``ray start --address`` on this machine, the same
campaign on the local backend and on the cluster, the worker node killed mid-campaign, a resume) and reads
its summary. Records: ``cluster.unique_trials`` (target: exactly N), ``cluster.same_records_as_local``
(1: the cluster's records equal the local backend's for the same seed, timings aside), ``cluster.killed_at``
(trials stored when the worker node was killed) and ``cluster.wall_s``. Needs the ``cluster`` extra (Ray) and
its CLI on the virtual environment's path.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from wrp_eval.bench_record import BenchRecord

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "ray_two_node.sh"
TRIALS = 96


def run_bench() -> list[BenchRecord]:
    with tempfile.TemporaryDirectory(prefix="wrp-cluster-") as tmp:
        start = time.perf_counter()
        env = {**os.environ, "BIN": str(Path(sys.executable).parent)}      # this environment's ray / wrp-eval
        run = subprocess.run(["bash", str(SCRIPT), tmp, str(TRIALS)], capture_output=True, text=True, env=env,
                             cwd=SCRIPT.parents[1], check=False)
        wall = time.perf_counter() - start
        summary_file = Path(tmp) / "summary.json"
        if not summary_file.is_file():
            tail = (run.stdout + run.stderr).strip().splitlines()[-5:]
            raise RuntimeError(f"{SCRIPT.name} ended with status {run.returncode} and no summary: {' | '.join(tail)}")
        doc = json.loads(summary_file.read_text())
    note = (f"{TRIALS} trials, 2 one-CPU nodes on this machine, worker node killed at "
            f"{doc['worker_node_killed_at_trials']} stored trials; workers {doc['ray_workers']}")
    return [
        BenchRecord("cluster.unique_trials", doc["unique_on_ray"], "trials", "issue 19 target (exactly N)",
                    TRIALS, note),
        BenchRecord("cluster.same_records_as_local", float(doc["same_records_as_local"]), "bool", None, None,
                    "records equal the local backend's for the same seed, timings aside"),
        BenchRecord("cluster.killed_at", doc["worker_node_killed_at_trials"], "trials", None, None, note),
        BenchRecord("cluster.wall_s", wall, "s", None, None, "local reference + cluster run + resume"),
    ]
