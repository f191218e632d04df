"""``wrp-eval optimize``: the wind-resistance path (ISWRP / SWRP) of a path, from a trained surrogate.

    wrp-eval optimize CONFIG [--kind iswrp|swrp|robust] [--threshold T] [--out DIR] [--checkpoint FILE]
                             [--campaign DIR] [--e-original E] [--no-oracle] [--quiet]

Writes <out>/path.json (the WRP) and <out>/wrp_metrics.json (the paper's Table 3 columns: offset rate,
total position / rotation offset, time, and the WRP's error from the ORACLE; plus the surrogate's figures,
per-viewpoint offsets and where E_original and r_s came from). With the default acceptance (validated) the
oracle confirms every move; --no-oracle leaves the moves unconfirmed and wrp_metrics.json says so.
--kind robust (levers beyond moving a viewpoint, screened with the oracle on the campaign's stored flights
against placebos; no surrogate needed) writes <out>/path.json and <out>/levers.json instead.
"""

from __future__ import annotations

import argparse

from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.wrp.jobs import optimize_job


def _optimize(args: argparse.Namespace) -> int:
    if args.threshold is not None and args.threshold < 0:
        raise InputError("--threshold", f"must be >= 0, got {args.threshold}")
    optimize_job(ExperimentContext.load(args.config), kind=args.kind, threshold_m=args.threshold, out=args.out,
                 checkpoint=args.checkpoint, campaign=args.campaign, e_original=args.e_original,
                 use_oracle=not args.no_oracle)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("optimize", help="wind-resistance path (ISWRP/SWRP, paper Alg. 3/4, from a surrogate; "
                                        "or the robust kind's levers)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config", metavar="CONFIG")
    p.add_argument("--kind", choices=("iswrp", "swrp", "robust"), default=None, help="overrides wrp.kind")
    p.add_argument("--threshold", type=float, default=None, help="t in metres of error (overrides wrp.threshold_m)")
    p.add_argument("--out", default=None, help="output folder (default wrp.out_dir or logs/<run.name>/wrp-<kind>)")
    p.add_argument("--checkpoint", default=None, help="surrogate checkpoint (overrides wrp.checkpoint)")
    p.add_argument("--campaign", default=None, help="campaign folder for the path and r_s")
    p.add_argument("--e-original", type=float, default=None, help="E_original in m (default: the oracle)")
    p.add_argument("--no-oracle", action="store_true", help="do not score the WRP with the oracle")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=_optimize)
