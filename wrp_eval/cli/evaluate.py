"""``wrp-eval evaluate CONFIG``: robustness of the initial path, ISWRP and SWRP under the same winds.

    wrp-eval evaluate CONFIG [--trials N] [--out DIR] [--checkpoint FILE] [--campaign DIR] [--e-original E]

Optimises the ISWRP and the SWRP (as ``optimize``), then flies the three paths and ``wrp.evaluate.placebos``
placebo paths per WRP (as many viewpoints moved by the same magnitudes, chosen at random) as campaigns with the
same seed (common random numbers, viewpoints as planned) and writes <out>/evaluate.json (per path: mean, std,
95th percentile of the error, failure rate, P(meets spec), views not taken and expected sorties with bootstrap
CIs; paired differences against the initial path; each WRP's robustness gain against its placebos and the
recommended path; the recommended path in the forecast wind: P(meets spec) with its CI and GO / NO-GO) and
<out>/boxplot.png. Re-running resumes the campaigns. ``wrp.evaluate.robust: true`` adds the robust kind and its
placebos (wrp/robust.py); ``wrp.evaluate.direction: true`` the initial tour flown the other way round, its placebos
the initial tour with its flights' own errors drawn again (wrp/direction.py); ``wrp.evaluate.capture_stops`` /
``slow_legs: true`` (fly-through missions) the initial path stopping to shoot / slowing its legs where its held-out
campaign flights' photos blur, each with as many stops / slowed legs at random as placebos (wrp/capture_lever.py);
``wrp.evaluate.kinds: []`` leaves ISWRP and SWRP out (no surrogate needed).

    wrp-eval evaluate CONFIG --colmap-check [--winds N] [--out DIR]

On a finished evaluation: COLMAP re-scores N winds (default 10) of the initial path, ISWRP and SWRP and says
whether it agrees with the synthetic oracle on the sign of each WRP's change (<out>/colmap-check/
colmap_check.json; needs `pip install .[photogrammetry]`; ~1 min per capture set).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.wrp.colmap_check import colmap_sign_check
from wrp_eval.wrp.jobs import evaluate_job


def _colmap_check(args: argparse.Namespace) -> int:
    if args.winds < 1:
        raise InputError("--winds", f"must be >= 1, got {args.winds}")
    ctx = ExperimentContext.load(args.config)
    folder = Path(args.out) if args.out else ctx.folders.evaluate
    doc = colmap_sign_check(folder, ctx.config.oracle, ctx.ship.mesh, folder / "colmap-check", winds=args.winds,
                            seed=ctx.run_seed, config_dir=ctx.config_dir)
    print(json.dumps(doc["wrp"], indent=1))
    return 0


def _evaluate(args: argparse.Namespace) -> int:
    if args.colmap_check:
        return _colmap_check(args)
    if args.trials is not None and args.trials < 2:
        raise InputError("--trials", f"need at least 2 trials, got {args.trials}")
    evaluate_job(ExperimentContext.load(args.config), args.out, n_trials=args.trials, checkpoint=args.checkpoint,
                 campaign=args.campaign, e_original=args.e_original)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser("evaluate", help="fly the initial path, ISWRP, SWRP (and, as configured, the robust "
                                        "kind and the reversed tour) with their placebo paths under the same "
                                        "winds; which path to fly", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("config", metavar="CONFIG")
    e.add_argument("--trials", type=int, default=None, help="trials per path (overrides wrp.evaluate.n_trials)")
    e.add_argument("--out", default=None, help="output folder (default wrp.evaluate.out_dir or "
                                               "logs/<run.name>/evaluate)")
    e.add_argument("--checkpoint", default=None)
    e.add_argument("--campaign", default=None, help="campaign folder for the initial path and r_s")
    e.add_argument("--e-original", type=float, default=None, help="E_original in m (default: the oracle)")
    e.add_argument("--quiet", action="store_true")
    e.add_argument("--colmap-check", action="store_true", help="on a finished evaluation: COLMAP's sign of each "
                   "WRP's change against the synthetic oracle's, on --winds winds (slow; photogrammetry extra)")
    e.add_argument("--winds", type=int, default=10, help="winds re-scored by --colmap-check (default 10)")
    e.set_defaults(func=_evaluate)
