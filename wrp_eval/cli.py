"""The ``wrp-eval`` command: one entry point, one sub-command family per stage.

Each stage module listed in ``COMMAND_MODULES`` has ``register(subparsers)`` adding its sub-commands,
each with ``set_defaults(func=handler)``; ``handler(args) -> int`` returns the exit status.
A bad input raises :class:`InputError`: one line on stderr, exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from wrp_eval import __version__
from wrp_eval.errors import InputError

COMMAND_MODULES = (   # in pipeline order; `wrp-eval --help` lists them so
    "wrp_eval.pipeline",
    "wrp_eval.ship.commands",
    "wrp_eval.planning.commands",
    "wrp_eval.wind.commands",
    "wrp_eval.sim.commands",
    "wrp_eval.recon.commands",
    "wrp_eval.campaign.commands",
    "wrp_eval.surrogate.commands",
    "wrp_eval.wrp.commands",
    "wrp_eval.export.commands",
    "wrp_eval.bench",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="wrp-eval",
        description="Plan UAV photo flights around a ship and evaluate their robustness to wind "
                    "by Monte Carlo flights in MuJoCo.")
    parser.add_argument("--version", action="version", version=f"wrp-eval {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except InputError as err:
        print(f"wrp-eval: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("wrp-eval: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
