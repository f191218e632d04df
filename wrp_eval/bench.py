"""``wrp-eval bench``: speed and accuracy figures as JSON records, the paper's figure beside ours.

Each stage that is measured has ``wrp_eval/<stage>/bench.py`` with ``run_bench() -> list[BenchRecord]``;
the groups are listed in ``BENCH_GROUPS``. A record is ``{name, value, unit, anchor, anchor_value}``
(anchor: where the comparison figure comes from, e.g. "paper Table 7"), and every file carries the
machine and library versions. These machines are noisy: compare ratios taken within one run.
"""

from __future__ import annotations

import importlib
import inspect
import json
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from wrp_eval.atomic import write_text_atomic
from wrp_eval.bench_record import environment
from wrp_eval.errors import InputError

# group name -> module with run_bench()
BENCH_GROUPS: dict[str, str] = {
    "sim": "wrp_eval.sim.bench",
    "campaign": "wrp_eval.campaign.bench",
    "capture": "wrp_eval.campaign.capture_bench",
    "mission": "wrp_eval.wrp.mission_bench",
    "wind": "wrp_eval.wind.bench",
    "ship": "wrp_eval.ship.bench",
    "plan": "wrp_eval.planning.bench",
    "oracle": "wrp_eval.recon.bench",
    "colmap": "wrp_eval.recon.colmap_bench",
    "surrogate": "wrp_eval.surrogate.bench",
    "wrp": "wrp_eval.wrp.bench",
    "robustness": "wrp_eval.wrp.robustness_bench",
    "robust": "wrp_eval.wrp.robust_bench",
    "envelope": "wrp_eval.envelope.bench",
    "scaling": "wrp_eval.campaign.scaling_bench",
    "views": "wrp_eval.campaign.view_scaling",
    "cluster": "wrp_eval.campaign.cluster_bench",
    "peers": "wrp_eval.sim.peers_bench",
    "study": "wrp_eval.study.bench",
}


def run_groups(groups: list[str], out_dir: Path) -> list[dict]:
    out_dir.mkdir(parents=True, exist_ok=True)
    all_records: list[dict] = []
    for group in groups:
        start = time.perf_counter()
        run = importlib.import_module(BENCH_GROUPS[group]).run_bench
        # a group that draws figures takes the output folder
        records = run(out_dir) if "out_dir" in inspect.signature(run).parameters else run()
        doc: dict[str, Any] = {"group": group, "created_unix": time.time(), "wall_s": time.perf_counter() - start,
                               "environment": environment(), "records": [asdict(r) for r in records]}
        write_text_atomic(out_dir / f"{group}.json", json.dumps(doc, indent=1))
        all_records.extend(doc["records"])
    return all_records


def select_groups(only: str) -> list[str]:
    """The groups named in a comma-separated ``only`` (empty: all); an unknown name is an InputError."""
    groups = list(BENCH_GROUPS) if not only else [g.strip() for g in only.split(",") if g.strip()]
    unknown = [g for g in groups if g not in BENCH_GROUPS]
    if unknown:
        raise InputError("--only", f"unknown group(s) {unknown}; choose from {sorted(BENCH_GROUPS)}")
    return groups
