"""``wrp-eval bench``: speed and accuracy figures as JSON records, the paper's figure beside ours.

Each stage that is measured has ``wrp_eval/<stage>/bench.py`` with ``run_bench() -> list[BenchRecord]``;
the groups are listed in ``BENCH_GROUPS``. A record is ``{name, value, unit, anchor, anchor_value}``
(anchor: where the comparison figure comes from, e.g. "paper Table 7"), and every file carries the
machine and library versions. These machines are noisy: compare ratios taken within one run.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from wrp_eval.errors import InputError

# group name -> module with run_bench()
BENCH_GROUPS: dict[str, str] = {
    "sim": "wrp_eval.sim.bench",
    "campaign": "wrp_eval.campaign.bench",
    "wind": "wrp_eval.wind.bench",
    "ship": "wrp_eval.ship.bench",
    "plan": "wrp_eval.planning.bench",
    "oracle": "wrp_eval.recon.bench",
    "surrogate": "wrp_eval.surrogate.bench",
    "wrp": "wrp_eval.wrp.bench",
}


@dataclass(frozen=True)
class BenchRecord:
    name: str
    value: float
    unit: str
    anchor: str | None = None
    anchor_value: float | None = None
    note: str = ""


def environment() -> dict:
    """Machine and library versions, stored with every bench file."""
    import numpy
    versions = {"python": platform.python_version(), "numpy": numpy.__version__}
    for mod in ("scipy", "mujoco", "open3d", "torch", "trimesh", "rerun"):
        try:
            versions[mod] = importlib.import_module(mod).__version__
        except Exception:  # a missing optional library is simply not reported
            pass
    return {"machine": platform.machine(), "processor": platform.processor(), "cpus": os.cpu_count(),
            "system": platform.platform(), "versions": versions}


def run_groups(groups: list[str], out_dir: Path) -> list[dict]:
    out_dir.mkdir(parents=True, exist_ok=True)
    all_records = []
    for group in groups:
        start = time.perf_counter()
        records = importlib.import_module(BENCH_GROUPS[group]).run_bench()
        doc = {"group": group, "created_unix": time.time(), "wall_s": time.perf_counter() - start,
               "environment": environment(), "records": [asdict(r) for r in records]}
        target = out_dir / f"{group}.json"
        tmp = target.with_name(target.name + ".tmp")
        tmp.write_text(json.dumps(doc, indent=1))
        tmp.replace(target)
        for r in records:
            anchor = f"  (anchor {r.anchor}: {r.anchor_value})" if r.anchor is not None else ""
            print(f"{r.name:34s} {r.value:14.6g} {r.unit}{anchor}")
        all_records.extend(doc["records"])
    return all_records


def _cmd_bench(args: argparse.Namespace) -> int:
    if not BENCH_GROUPS:
        raise InputError("bench", "no benchmark groups are available")
    groups = list(BENCH_GROUPS) if not args.only else [g.strip() for g in args.only.split(",") if g.strip()]
    unknown = [g for g in groups if g not in BENCH_GROUPS]
    if unknown:
        raise InputError("--only", f"unknown group(s) {unknown}; choose from {sorted(BENCH_GROUPS)}")
    run_groups(groups, Path(args.out))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="run the benchmarks and write JSON records",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--only", default="", help="comma-separated groups (default: all): "
                   + ", ".join(BENCH_GROUPS) if BENCH_GROUPS else "comma-separated groups")
    p.add_argument("--out", default="logs/bench/", help="output folder (default logs/bench/)")
    p.set_defaults(func=_cmd_bench)
