"""``wrp-eval bench [--only GROUPS] [--out DIR]``: speed and accuracy figures as JSON records."""

from __future__ import annotations

import argparse
from pathlib import Path

from wrp_eval.bench import BENCH_GROUPS, run_groups, select_groups
from wrp_eval.bench import __doc__ as BENCH_DOC


def _bench(args: argparse.Namespace) -> int:
    for group in select_groups(args.only):      # a group at a time: its records show as soon as it ends
        for r in run_groups([group], Path(args.out)):
            anchor = f"  (anchor {r['anchor']}: {r['anchor_value']})" if r["anchor"] is not None else ""
            print(f"{r['name']:34s} {r['value']:14.6g} {r['unit']}{anchor}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="run the benchmarks and write JSON records",
                       description=BENCH_DOC, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--only", default="", help="comma-separated groups (default: all): " + ", ".join(BENCH_GROUPS))
    p.add_argument("--out", default="logs/bench/", help="output folder (default logs/bench/)")
    # the bench's campaign timings include the workers' start-up: no pool shared across its groups
    p.set_defaults(func=_bench, shared_pools=False)
