"""The ``wrp-eval`` command: one module per sub-command, each only parse -> call -> print.

Every module in :data:`COMMANDS` has ``register(subparsers)`` adding its sub-command with
``set_defaults(func=handler)``; ``handler(args) -> int`` returns the exit status. The work is done by the
stages' jobs (``wrp_eval/<stage>/...``, :mod:`wrp_eval.pipeline`); nothing outside this package imports it.
A bad input raises :class:`InputError`: one line on stderr, exit status 2.
"""

from __future__ import annotations

import argparse
import logging
import sys
from contextlib import nullcontext

from wrp_eval import __version__
from wrp_eval.campaign.backends import shared_process_pools
from wrp_eval.cli import (
    bench,
    campaign,
    envelope,
    evaluate,
    export,
    fly,
    optimize,
    plan,
    reconstruct,
    run,
    ship,
    train,
    validate_oracle,
    wind,
)
from wrp_eval.errors import InputError
from wrp_eval.logs import progress_log

COMMANDS = (run, ship, plan, wind, fly, reconstruct, validate_oracle, campaign, train, optimize, evaluate,
            envelope, export, bench)   # in pipeline order; `wrp-eval --help` lists them so


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="wrp-eval",
        description="Plan UAV photo flights around a ship and evaluate their robustness to wind "
                    "by Monte Carlo flights in MuJoCo.")
    parser.add_argument("--version", action="version", version=f"wrp-eval {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    # the jobs report through `logging` (wrp_eval.* loggers, wrp_eval/logs.py); the command line shows it on
    # stderr, the per-step lines and progress bars (wrp_eval.progress) unless --quiet (run: only with --progress)
    logging.basicConfig(level=logging.WARNING, format="%(message)s", stream=sys.stderr, force=True)
    logging.getLogger("wrp_eval").setLevel(logging.INFO)
    silent = getattr(args, "quiet", False) or getattr(args, "progress", True) is False
    progress_log.setLevel(logging.WARNING if silent else logging.NOTSET)
    try:
        # one process pool per size for the whole command: its campaigns reuse the workers (campaign/backends.py)
        with shared_process_pools() if getattr(args, "shared_pools", True) else nullcontext():
            return int(args.func(args) or 0)
    except InputError as err:
        print(f"wrp-eval: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("wrp-eval: interrupted", file=sys.stderr)
        return 130
