"""``wrp-eval train CONFIG``: fit the surrogate on a campaign's trials (the ``surrogate:`` section).

    wrp-eval train CONFIG [--campaign DIR] [--out DIR] [--cv K [--workers W]] [--quiet]

Writes <out>/surrogate.pt (state_dict + metadata, loaded with torch.load(weights_only=True)),
<out>/metrics.json (R^2, RMSE, MAE of the held-out test trials; train/val too; the mean-offset baseline on the
same split; the single-view validation against the jitter-averaged oracle, surrogate.validation_moves, whose
RMSE the optimiser's acceptance uses) and <out>/parity.png.
With --cv K also K-fold cross-validation (K more trainings; every trial tested once) into <out>/cv.json:
one test split's R^2 scatters widely on heavy-tailed errors, the fold mean and range do not. The folds train
with the model itself, W at a time in separate processes (default: one per CPU core); the figures do not depend
on W.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wrp_eval.atomic import write_json_atomic
from wrp_eval.campaign.backends import default_workers
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.surrogate.train import CHECKPOINT_NAME, train_from_campaign


def _train(args: argparse.Namespace) -> int:
    workers = args.workers if args.workers is not None else default_workers()
    if workers < 1:                     # refused before an hour of training, not after
        raise InputError("--workers", f"must be >= 1, got {workers}")
    if args.cv == 1 or args.cv < 0:
        raise InputError("--cv", f"needs K >= 2 folds (or 0: none), got {args.cv}")
    ctx = ExperimentContext.load(args.config)
    out = Path(args.out) if args.out else ctx.folders.surrogate
    if args.cv and not args.quiet:
        print(f"training the surrogate and {args.cv} cross-validation folds, {min(workers, args.cv + 1)} at a "
              f"time ...", flush=True)
    result, data, cv = train_from_campaign(ctx, args.campaign, out, folds=args.cv,
                                           workers=workers)
    m = result.metrics["test"]
    print(f"surrogate {out / CHECKPOINT_NAME}: test R^2 {m['r2']:.4f}, RMSE {m['rmse']:.4g} m, MAE {m['mae']:.4g} m "
          f"on {m['n']} held-out trials ({result.metrics['n_used']} used of {data.n_trials}; "
          f"{result.metrics['epochs_run']} epochs, {result.seconds:.1f} s)")
    if args.cv:
        if cv is None:
            raise RuntimeError(f"{args.cv} cross-validation folds asked for, none came back")
        write_json_atomic(out / "cv.json", cv)
        print(f"cross-validation {out / 'cv.json'}: {args.cv} folds, test R^2 mean {cv['r2_mean']:.4f} "
              f"(min {cv['r2_min']:.4f}, max {cv['r2_max']:.4f}), pooled {cv['pooled']['r2']:.4f}, "
              f"RMSE mean {cv['rmse_mean']:.4g} m ({cv['seconds']:.0f} s, {cv['workers']} processes)")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("train", help="train the surrogate (offsets -> reconstruction error) on a campaign",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("config", metavar="CONFIG")
    p.add_argument("--campaign", default=None, help="campaign folder (default surrogate.campaign_dir or the "
                                                    "campaign's default folder)")
    p.add_argument("--out", default=None, help="output folder (default surrogate.out_dir or "
                                               "logs/<run.name>/surrogate)")
    p.add_argument("--cv", type=int, default=0, metavar="K",
                   help="also K-fold cross-validation (K >= 2) into <out>/cv.json")
    p.add_argument("--workers", type=int, default=None, metavar="W",
                   help="with --cv: folds trained at once in separate processes (default: CPU cores)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_train)
