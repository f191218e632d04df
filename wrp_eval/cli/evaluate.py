"""``wrp-eval evaluate CONFIG``: robustness of the initial path, ISWRP and SWRP under the same winds.

    wrp-eval evaluate CONFIG [--trials N] [--out DIR] [--checkpoint FILE] [--campaign DIR] [--e-original E]

Optimises the ISWRP and the SWRP (as ``optimize``), then flies the three paths and ``wrp.evaluate.placebos``
placebo paths per WRP (as many viewpoints moved by the same magnitudes, chosen at random) as campaigns with the
same seed (common random numbers, viewpoints as planned) and writes <out>/evaluate.json (per path: mean, std,
95th percentile of the error, failure rate, P(meets spec), views not taken and expected sorties with bootstrap
CIs; paired differences against the initial path; each WRP's robustness gain against its placebos and the
recommended path) and <out>/boxplot.png. Re-running resumes the campaigns.
"""

from __future__ import annotations

import argparse

from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.wrp.jobs import evaluate_job


def _evaluate(args: argparse.Namespace) -> int:
    if args.trials is not None and args.trials < 2:
        raise InputError("--trials", f"need at least 2 trials, got {args.trials}")
    evaluate_job(ExperimentContext.load(args.config), args.out, n_trials=args.trials, checkpoint=args.checkpoint,
                 campaign=args.campaign, e_original=args.e_original, quiet=args.quiet)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser("evaluate", help="fly the initial path, ISWRP, SWRP and their placebo paths "
                                        "under the same winds; which path to fly", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("config", metavar="CONFIG")
    e.add_argument("--trials", type=int, default=None, help="trials per path (overrides wrp.evaluate.n_trials)")
    e.add_argument("--out", default=None, help="output folder (default wrp.evaluate.out_dir or "
                                               "logs/<run.name>/evaluate)")
    e.add_argument("--checkpoint", default=None)
    e.add_argument("--campaign", default=None, help="campaign folder for the initial path and r_s")
    e.add_argument("--e-original", type=float, default=None, help="E_original in m (default: the oracle)")
    e.add_argument("--quiet", action="store_true")
    e.set_defaults(func=_evaluate)
