"""``wrp-eval campaign``: run or resume a Monte Carlo campaign, or report on one.

    wrp-eval campaign CONFIG [--trials N] [--out DIR] [--backend local|ray] [--workers K] [--no-rerun]
    wrp-eval campaign run CONFIG ...        (the same, explicit)
    wrp-eval campaign status DIR [--json]

Re-running the same command on the same DIR resumes: stored trials are skipped. The first word after
``campaign`` picks the action: ``status`` or ``run``; anything else is the CONFIG file (a config file
literally named ``status`` or ``run`` can be given as ``./status``).
"""

from __future__ import annotations

import argparse
import json

from wrp_eval.campaign.jobs import campaign_job
from wrp_eval.campaign.runner import campaign_status
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext


def _run(args: argparse.Namespace, config_file: str) -> int:
    summary = campaign_job(ExperimentContext.load(config_file), out_dir=args.out, n_trials=args.trials,
                           backend=args.backend, workers=args.workers, rerun=False if args.no_rerun else None)
    print(f"campaign {summary.out_dir}: {summary.done}/{summary.n_trials} trials stored "
          f"({summary.ran} run now in {summary.wall_s:.1f} s, {summary.trials_per_min:.1f} trials/min), "
          f"{summary.failed} failed of which {summary.errors} raised")
    return 0


def _status(args: argparse.Namespace, out_dir: str) -> int:
    status = campaign_status(out_dir)
    if args.json:
        print(json.dumps(status, indent=1))
        return 0
    rate = status["trials_per_min"]
    print(f"{status['out_dir']}: {status['done']}/{status['n_trials']} done, {status['failed']} failed "
          f"({status['errors']} raised), {status['remaining']} remaining, "
          + (f"{rate:.1f} trials/min" if rate is not None else "rate unknown"))
    return 0


def _dispatch(args: argparse.Namespace) -> int:
    words = list(args.words)
    action = words[0] if words[0] in ("run", "status") else "run"
    if words[0] in ("run", "status"):
        words = words[1:]
    if len(words) != 1:
        want = "DIR" if action == "status" else "CONFIG"
        raise InputError("campaign", f"'{action}' takes exactly one {want}, got {len(words)} argument(s)")
    return _status(args, words[0]) if action == "status" else _run(args, words[0])


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("campaign", help="run/resume a Monte Carlo campaign, or show its status",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("words", nargs="+", metavar="CONFIG | run CONFIG | status DIR")
    p.add_argument("--trials", type=int, default=None, help="number of trials (overrides campaign.n_trials)")
    p.add_argument("--out", default=None, help="campaign folder (default campaign.outputs.dir or "
                                               "logs/<run.name>/campaign)")
    p.add_argument("--backend", choices=("local", "ray"), default=None, help="overrides campaign.backend.kind")
    p.add_argument("--workers", type=int, default=None, help="worker processes / Ray CPUs (0: in-process)")
    p.add_argument("--no-rerun", action="store_true", help="do not write campaign.rrd")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--json", action="store_true", help="status: print JSON")
    p.set_defaults(func=_dispatch)
