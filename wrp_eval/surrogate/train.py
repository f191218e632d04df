"""Training of the surrogate: split by trial, standardise, Adam with early stopping, held-out metrics, plot.

Seeding: the split comes from ``numpy.random.default_rng(SeedSequence(seed, spawn_key=(0,)))``; the initial
weights and the batch order from torch generators seeded with ``seed`` (the global torch RNG is forked, not
touched). Same data + same config + same seed -> the same weights (on this CPU build: torch CPU kernels are
deterministic for these layers).
"""

from __future__ import annotations

import copy
import logging
import multiprocessing
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch
from matplotlib.figure import Figure
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
)
from torch.nn import functional as F

from wrp_eval.atomic import atomic_path, write_json_atomic
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.logs import progress_shown
from wrp_eval.surrogate.config import SurrogateSection
from wrp_eval.surrogate.data import TrialData, load_campaign_trials, physical_variance_share, split_indices
from wrp_eval.surrogate.diagnostics import mean_offset_baseline, single_view_agreement
from wrp_eval.surrogate.features import (
    CONDITION_NAMES,
    COVERAGE_NAMES,
    conditions_or_reference,
    moving_features,
    moving_names,
)
from wrp_eval.surrogate.metrics import regression_metrics
from wrp_eval.surrogate.model import Surrogate, SurrogateMeta, ViewSequenceCNN

log = logging.getLogger(__name__)

CHECKPOINT_NAME = "surrogate.pt"
METRICS_NAME = "metrics.json"
PARITY_NAME = "parity.png"


@dataclass
class TrainResult:
    """surrogate: the trained model (best validation epoch); metrics: per split R^2, RMSE, MAE (m), counts (and
    ``val_targeted`` / ``test_targeted``: the same on the held-out flights commanded off the plan; ``test``
    ``registration``: the registration head's figures, when trained);
    history: per-epoch train and validation loss (standardised MSE); split: trial indices of each split;
    test_true / test_pred (m): the held-out test trials, for the parity plot; seconds: training wall time."""

    surrogate: Surrogate
    metrics: dict
    history: dict
    split: dict
    test_true: np.ndarray
    test_pred: np.ndarray
    seconds: float
    extra: dict = field(default_factory=dict)


class _Progress:
    """A rich progress bar on a terminal, plain lines (about 10 per run) otherwise."""

    def __init__(self, total: int, enabled: bool):
        self.total, self.enabled = total, enabled
        self.tty = enabled and sys.stderr.isatty()
        self.bar = None
        if self.tty:
            self.bar = Progress(TextColumn("train"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                TextColumn("{task.fields[info]}"), transient=False)
            self.bar.start()
            self.task = self.bar.add_task("train", total=total, info="")
        self.every = max(1, total // 10)

    def update(self, epoch: int, info: str) -> None:
        if self.bar is not None:
            self.bar.update(self.task, completed=epoch, info=info)
        elif self.enabled and (epoch % self.every == 0 or epoch == 1):
            log.info(f"train epoch {epoch}/{self.total} {info}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()


def _standardise(values: np.ndarray, axis) -> tuple[np.ndarray, np.ndarray]:
    mean = values.mean(axis=axis)
    std = values.std(axis=axis)
    return mean, np.where(std > 1e-12, std, 1.0)


def _conditions(data: TrialData, rows: np.ndarray) -> np.ndarray | None:
    """(len(rows), n, 5) the trials' conditions at the shutter, the forecast reference where not recorded."""
    if data.views is None:
        return None
    cond = None if data.conditions is None else np.asarray(data.conditions, float)[rows]
    return np.array(conditions_or_reference(cond, data.views.condition_reference, len(rows)))


def usable_rows(data: TrialData, section: SurrogateSection) -> tuple[np.ndarray, np.ndarray]:
    """(usable (n_trials,) bool: finite error and, unless ``use_failed_trials``, not failed; rows: the trial
    indices that take part in training -- every trial with ``predict_failure``, else the usable ones)."""
    error = np.asarray(data.error, float)
    usable = np.isfinite(error) & (section.use_failed_trials | ~np.asarray(data.failed, bool))
    if section.missing_views == "drop":
        usable &= data.complete()
    rows = np.arange(data.n_trials) if section.predict_failure else np.flatnonzero(usable)
    return usable, rows


def train_surrogate(data: TrialData, section: SurrogateSection = SurrogateSection(), seed: int = 0,
                    split: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> TrainResult:
    """Fit the surrogate on ``data`` (see :class:`SurrogateSection` for every knob).

    split: explicit (train, val, test) trial indices (as :func:`cross_validate` gives); none: the seeded
    random split of ``section``'s fractions.
    """
    start = time.perf_counter()
    torch.set_num_threads(section.threads)
    error = np.asarray(data.error, float)
    usable, rows = usable_rows(data, section)     # with predict_failure every trial teaches the failure output
    if rows.size < 10:
        raise InputError(data.source or "surrogate data", f"only {rows.size} usable trials; need at least 10")
    if split is None:
        split_rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(0,)))
        tr, va, te = (rows[i] for i in split_indices(rows.size, section.val_fraction, section.test_fraction,
                                                     split_rng))
    else:
        tr, va, te = (np.asarray(i, dtype=np.int64) for i in split)
    offsets = np.asarray(data.offsets, float)
    target = _target(data, section, error, usable)
    meta = _untrained_meta(data, section, offsets, target, usable, tr)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        net = ViewSequenceCNN(**meta.architecture)
    surrogate = Surrogate(net, meta, data.scarce)
    history, epoch, best_epoch, final_lr = _fit(net, surrogate, data, section, offsets, target, usable, tr, va,
                                                seed)

    metrics: dict[str, Any] = {}
    preds = {}
    for name, idx in (("train", tr), ("val", va), ("test", te)):
        keep = idx[usable[idx]]
        preds[name] = (error[keep], surrogate.predict(offsets[keep], _conditions(data, keep)))
        metrics[name] = regression_metrics(*preds[name])
    if section.predict_failure:
        p = surrogate.predict_failure(offsets[te], _conditions(data, te))
        f = np.asarray(data.failed, bool)[te]
        metrics["test"]["failure_brier"] = float(((p - f) ** 2).mean())
    targeted = data.targeted()
    for name, idx in (("val", va), ("test", te)):      # the held-out flights nearest the optimiser's one-view queries
        among = targeted[idx[usable[idx]]]
        if among.sum() > 1:
            metrics[f"{name}_targeted"] = regression_metrics(preds[name][0][among], preds[name][1][among])
    if section.registration_weight > 0:
        metrics["test"]["registration"] = registration_metrics(surrogate, data, te[usable[te]])
    seconds = time.perf_counter() - start
    metrics.update({"epochs_run": epoch, "best_epoch": best_epoch, "train_s": seconds, "seed": seed,
                    "final_lr": final_lr, "n_trials": int(data.n_trials), "n_used": int(rows.size),
                    "n_views": data.n_views, "data": data.source})
    final_meta = SurrogateMeta(**{**meta.__dict__, "metrics": metrics,
                                  "extra": {"seed": seed, "data": data.source}})
    surrogate = Surrogate(net, final_meta, data.scarce)
    return TrainResult(surrogate, metrics, history, {"train": tr.tolist(), "val": va.tolist(), "test": te.tolist()},
                       preds["test"][0], preds["test"][1], seconds)


def _target(data: TrialData, section: SurrogateSection, error: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """(N,) what the network learns per trial: the error (m) or its logarithm (NaN where not usable)."""
    if section.target != "log_error":
        return error
    if np.any(error[usable] <= 0):
        raise InputError(data.source or "surrogate data", "target log_error needs errors > 0; "
                                                          "use surrogate.target: error")
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(np.where(usable, error, np.nan))


def _untrained_meta(data: TrialData, section: SurrogateSection, offsets: np.ndarray, target: np.ndarray,
                    usable: np.ndarray, tr: np.ndarray) -> SurrogateMeta:
    """The checkpoint's meta before training: the architecture and every standardisation, from the training
    trials ``tr``."""
    off_mean, off_std = _standardise(offsets[tr].reshape(-1, 4), 0)
    err_train = target[tr][usable[tr]]
    if err_train.size < 2:
        raise InputError(data.source or "surrogate data", "too few training trials with a finite error")
    err_mean, err_std = float(err_train.mean()), float(max(err_train.std(), 1e-12))
    pose_mean = pose_std = planned = None
    if section.pose_channels:
        if data.planned_pose is None:
            raise InputError("surrogate.pose_channels", "the data has no planned poses; set pose_channels: false")
        pose = np.asarray(data.planned_pose, float)
        planned = pose.tolist()
        pose_mean, pose_std = (v.tolist() for v in _standardise(pose, 0))
    views = feat_mean = feat_std = scarce_digest = None
    if section.inputs != "offsets":
        if data.views is None:
            raise InputError(data.source or "surrogate data", "the data has no per-view context (ship coverage); "
                                                              "set surrogate.inputs: offsets")
        views = data.views.to_json_dict()
        scarce = data.scarce if section.inputs == "scarce" else None
        if section.inputs == "scarce" and scarce is None:
            raise InputError(data.source or "surrogate data", "the data has no scarce coverage of its path "
                                                              "(a campaign read without its ship)")
        scarce_digest = None if scarce is None else scarce.digest
        cond = cast(np.ndarray, _conditions(data, tr))
        moving = moving_features(data.views, scarce, offsets[tr], taken=cond[..., -1] >= 0.5)
        features = np.concatenate([moving, cond,
                                   np.broadcast_to(data.views.coverage(), (len(tr), data.n_views, 2))], axis=2)
        feat_mean, feat_std = (v.tolist() for v in _standardise(features.reshape(-1, features.shape[-1]), 0))
    n_features = 4 + (len(moving_names(section.inputs)) + len(CONDITION_NAMES) + len(COVERAGE_NAMES)
                      if section.inputs != "offsets" else 0)
    arch = {"in_channels": n_features + (7 if section.pose_channels else 0),
            "channels": section.channels,
            "kernel": section.kernel, "layers": section.layers, "hidden": section.hidden,
            "outputs": 2 if section.predict_failure else 1}
    if section.registration_weight > 0:
        arch["view_outputs"] = 1
    return SurrogateMeta(n_views=data.n_views, path_digest=data.path_digest, architecture=arch,
                         offset_mean=off_mean.tolist(), offset_std=off_std.tolist(), error_mean=err_mean,
                         error_std=err_std, pose_mean=pose_mean, pose_std=pose_std, planned_pose=planned,
                         offset_low=offsets[tr].reshape(-1, 4).min(0).tolist(),
                         offset_high=offsets[tr].reshape(-1, 4).max(0).tolist(), target=section.target,
                         inputs=section.inputs, views=views, feature_mean=feat_mean, feature_std=feat_std,
                         scarce_digest=scarce_digest)


def _fit(net, surrogate: Surrogate, data: TrialData, section: SurrogateSection, offsets: np.ndarray,
         target: np.ndarray, usable: np.ndarray, tr: np.ndarray, va: np.ndarray,
         seed: int) -> tuple[dict, int, int, float]:
    """Train ``net`` in place (Adam, seeded batches, early stopping on the validation loss -- of the error output
    alone when the registration head trains beside it, the auxiliary loss is a means, not the product; the best
    epoch's weights are kept): (loss history, epochs run, best epoch, final learning rate)."""
    loss_of = _loss_function(net, surrogate, data, section, offsets, target, usable)
    opt = torch.optim.Adam(net.parameters(), lr=section.lr, weight_decay=section.weight_decay)
    scheduler = None
    if section.lr_decay_patience > 0:
        scheduler = torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=section.lr_decay_factor,
                                                               patience=section.lr_decay_patience,
                                                               threshold=1e-7, threshold_mode="abs",
                                                               min_lr=section.lr * 1e-3)
    gen = torch.Generator().manual_seed(seed)
    tr_t, va_t = torch.as_tensor(tr), torch.as_tensor(va)
    best, best_state, best_epoch, stale = float("inf"), copy.deepcopy(net.state_dict()), 0, 0
    history: dict[str, list] = {"train_loss": [], "val_loss": []}
    bar = _Progress(section.epochs, progress_shown())
    epoch = 0
    try:
        for epoch in range(1, section.epochs + 1):
            history["train_loss"].append(_epoch(net, opt, loss_of, tr_t[torch.randperm(tr_t.numel(), generator=gen)],
                                                section.batch_size))
            net.eval()
            with torch.no_grad():      # with the registration head: early stopping on the error's loss alone
                val = float(loss_of(va_t, error_only=section.registration_weight > 0))
            history["val_loss"].append(val)
            if scheduler is not None:
                scheduler.step(val)
            if val < best - 1e-7:
                best, best_epoch, stale = val, epoch, 0
                best_state = copy.deepcopy(net.state_dict())
            else:
                stale += 1
            bar.update(epoch, f"train {history['train_loss'][-1]:.4f} val {val:.4f} best {best:.4f}@{best_epoch}")
            if stale >= section.patience:
                break
    finally:
        bar.close()
    net.load_state_dict(best_state)
    net.eval()
    return history, epoch, best_epoch, float(opt.param_groups[0]["lr"])


def _loss_function(net, surrogate: Surrogate, data: TrialData, section: SurrogateSection, offsets: np.ndarray,
                   target: np.ndarray, usable: np.ndarray):
    """loss_of(trial indices, error_only=False) -> the training loss of those trials: the standardised error's
    squared residual over the usable trials, [+ the failure logit's binary cross-entropy] [+ registration_weight
    x the per-view registration logits' binary cross-entropy over the views with a label, of usable trials];
    ``error_only``: the first term alone."""
    meta = surrogate.meta
    x_all = surrogate.input_tensor(offsets, data.conditions)                # (N, n, Cin)
    y_all = torch.as_tensor(np.nan_to_num((target - meta.error_mean) / meta.error_std), dtype=torch.float32)
    w_all = torch.as_tensor(usable, dtype=torch.float32)                     # error-loss mask
    f_all = torch.as_tensor(np.asarray(data.failed, bool), dtype=torch.float32)
    weight = section.registration_weight
    if weight > 0:
        labels = registration_labels(data, usable)
        r_all = torch.as_tensor(np.nan_to_num(labels), dtype=torch.float32)
        r_mask = torch.as_tensor(np.isfinite(labels), dtype=torch.float32)

    def loss_of(idx: torch.Tensor, error_only: bool = False) -> torch.Tensor:
        views = weight > 0 and not error_only
        out, logits = net.forward_with_views(x_all[idx]) if views else (net(x_all[idx]), None)
        w = w_all[idx]
        loss = ((out[:, 0] - y_all[idx]) ** 2 * w).sum() / w.sum().clamp(min=1.0)
        if error_only:
            return loss
        if section.predict_failure:
            loss = loss + F.binary_cross_entropy_with_logits(out[:, 1], f_all[idx])
        if logits is not None:
            m = r_mask[idx]
            bce = F.binary_cross_entropy_with_logits(logits[..., 0], r_all[idx], weight=m, reduction="sum")
            loss = loss + weight * bce / m.sum().clamp(min=1.0)
        return loss

    return loss_of


def registration_labels(data: TrialData, usable: np.ndarray) -> np.ndarray:
    """(n_trials, n_views) the registration labels the auxiliary loss learns: the campaign's view_registered (1 /
    0) on the ``usable`` trials, NaN elsewhere. A campaign without any label is an InputError."""
    labels = None if data.registered is None else np.where(usable[:, None], np.asarray(data.registered, float),
                                                            np.nan)
    if labels is None or not np.isfinite(labels).any():
        raise InputError("surrogate.registration_weight", f"{data.source or 'the training data'} records no "
                         "registered views (campaigns stored before view_registered); set it to 0 or fly the "
                         "campaign again")
    return labels


def registration_metrics(surrogate: Surrogate, data: TrialData, rows: np.ndarray) -> dict:
    """The registration head on trials ``rows`` (usable ones): log_loss (nats per labelled view), accuracy at
    p = 0.5, base_rate (the share registered) and n_views_labelled (only that, 0, when none has a label)."""
    labels = np.full((len(rows), data.n_views), np.nan) if data.registered is None else \
        np.asarray(data.registered, float)[rows]
    if not np.isfinite(labels).any():
        return {"n_views_labelled": 0}
    with torch.no_grad():
        _, logits = surrogate.net.forward_with_views(surrogate.input_tensor(np.asarray(data.offsets, float)[rows],
                                                                            _conditions(data, rows)))
    ok = np.isfinite(labels)
    z, y = logits[..., 0].double()[torch.as_tensor(ok)], torch.as_tensor(labels[ok])
    return {"log_loss": float(F.binary_cross_entropy_with_logits(z, y)),     # the training loss's own form
            "accuracy": float(((z > 0) == (y > 0.5)).double().mean()), "base_rate": float(y.mean()),
            "n_views_labelled": int(ok.sum())}


def _epoch(net, opt, loss_of, perm: torch.Tensor, batch_size: int) -> float:
    """One pass over the training trials ``perm`` in batches; returns the mean training loss."""
    net.train()
    total = 0.0
    for i in range(0, perm.numel(), batch_size):
        idx = perm[i:i + batch_size]
        opt.zero_grad(set_to_none=True)
        loss = loss_of(idx)
        loss.backward()
        opt.step()
        total += float(loss.detach()) * idx.numel()
    return total / perm.numel()


def fold_splits(data: TrialData, section: SurrogateSection, seed: int, folds: int) -> list[tuple]:
    """(train, val, test) trial indices of each of ``folds`` folds: fold k tests on the k-th of ``folds`` seeded
    parts of the training rows (:func:`usable_rows`); of the rest, ``val_fraction`` validates and the others
    train. Every training row is a test trial exactly once."""
    if folds < 2:
        raise InputError("surrogate cross-validation", f"folds must be >= 2, got {folds}")
    _, rows = usable_rows(data, section)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(1,)))
    parts = np.array_split(rng.permutation(rows), folds)
    n_val = max(1, int(round(section.val_fraction * rows.size)))
    splits = []
    for k in range(folds):
        rest = rng.permutation(np.concatenate([parts[j] for j in range(folds) if j != k]))
        splits.append((np.sort(rest[n_val:]), np.sort(rest[:n_val]), np.sort(parts[k])))
    return splits


def train_in_parallel(data: TrialData, section: SurrogateSection, seed: int, splits: list,
                      workers: int = 1) -> list[TrainResult]:
    """:func:`train_surrogate` once per entry of ``splits`` (an explicit (train, val, test) split, or None for
    the seeded default split), ``workers`` at a time in spawned processes (each with ``section.threads`` torch
    threads). Each training is seeded the same way wherever it runs: the results equal the serial ones.
    Progress (:mod:`wrp_eval.logs`) shows for the trainings run in this process, not for pool processes."""
    if workers < 1:
        raise InputError("surrogate training", f"workers must be >= 1, got {workers}")
    if workers == 1 or len(splits) == 1:
        return [train_surrogate(data, section, seed=seed, split=split) for split in splits]
    # spawn, not fork: no forked copy of torch's thread pool; the data travel to each process once per job
    with ProcessPoolExecutor(max_workers=min(workers, len(splits)),
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        jobs = [pool.submit(train_surrogate, data, section, seed, split) for split in splits]
        return [job.result() for job in jobs]


def fold_summary(results: list[TrainResult], seed: int, seconds: float, workers: int) -> dict:
    """The cross-validation document of the fold trainings ``results`` (see :func:`cross_validate`)."""
    per_fold = [{**r.metrics["test"], "test_trials": list(r.split["test"])} for r in results]
    pooled = regression_metrics(np.concatenate([r.test_true for r in results]),
                                np.concatenate([r.test_pred for r in results]))
    summary = {"folds": len(results), "seed": seed, "per_fold": per_fold, "pooled": pooled,
               "seconds": seconds, "workers": int(workers)}
    for key in ("r2", "rmse", "mae"):
        values = np.array([m[key] for m in per_fold], float)
        summary[f"{key}_mean"], summary[f"{key}_min"], summary[f"{key}_max"] = (
            float(values.mean()), float(values.min()), float(values.max()))
    return summary


def cross_validate(data: TrialData, section: SurrogateSection = SurrogateSection(), seed: int = 0,
                   folds: int = 5, workers: int = 1) -> dict:
    """K-fold estimate of the held-out figures: every usable trial is a test trial exactly once.

    One R^2 from one random test split of a few hundred trials scatters widely when the error is heavy-tailed
    (measured on 1,500 flights of the surrogate bench: 0.85, 0.92 and 0.95 for split seeds 2, 1, 0), so the
    mean and range over folds are the figure to quote. Folds: :func:`fold_splits`; workers > 1 trains that
    many folds at once (:func:`train_in_parallel`, same figures). Returns per-fold R^2 / RMSE / MAE / n /
    test_trials, their mean, min and max, the pooled figures of all out-of-fold predictions, seconds, workers.
    """
    start = time.perf_counter()
    splits = fold_splits(data, section, seed, folds)
    results = train_in_parallel(data, section, seed, splits, workers)
    return fold_summary(results, seed, time.perf_counter() - start, min(workers, folds))


def train_with_folds(data: TrialData, section: SurrogateSection, seed: int, folds: int = 0,
                     workers: int = 1) -> tuple[TrainResult, dict | None]:
    """The model on the seeded default split and, with ``folds`` >= 2, ``folds``-fold cross-validation, all
    trained together ``workers`` at a time (:func:`train_in_parallel`). Returns (model, the
    :func:`cross_validate` document or None); ``seconds`` there is the wall time of every training."""
    start = time.perf_counter()
    splits = fold_splits(data, section, seed, folds) if folds else []
    results = train_in_parallel(data, section, seed, [None, *splits], workers)
    cv = (fold_summary(results[1:], seed, time.perf_counter() - start, min(workers, len(results)))
          if folds else None)
    return results[0], cv


def train_from_campaign(ctx: ExperimentContext, campaign_dir: str | Path | None = None,
                        out_dir: str | Path | None = None, folds: int = 0,
                        workers: int = 1) -> tuple[TrainResult, TrialData, dict | None]:
    """The training job of an experiment: its ``surrogate:`` section fitted on a campaign folder's trials
    (default ``surrogate.campaign_dir`` or the run's campaign; seed ``surrogate.seed``, else ``run.seed``),
    outputs written to ``out_dir`` (default ``surrogate.out_dir`` or the run's surrogate folder,
    :func:`write_outputs`), with ``folds``-fold cross-validation trained beside it when ``folds`` >= 2
    (:func:`train_with_folds`). Returns (result, the trials, the cross-validation document or None) -- what
    ``wrp-eval train``, ``wrp-eval run`` and the studies all do; the trials are returned so that the caller
    does not read the campaign again."""
    section = ctx.config.surrogate
    folder = campaign_dir if campaign_dir is not None else ctx.training_campaign_dir
    data = load_campaign_trials(folder, config_dir=ctx.config_dir, scarce=section.inputs == "scarce")
    result, cv = train_with_folds(data, section, section.seed_or(ctx.run_seed), folds, workers)
    result.metrics["physical_variance_share"] = physical_variance_share(data)
    result.metrics["baseline"] = mean_offset_baseline(data, result.split, usable_rows(data, section)[0])
    if section.validation_moves > 0 and data.views is not None:
        # the validated single-view error the optimiser's acceptance rule needs
        agreement = single_view_agreement(result.surrogate, folder, n_moves=section.validation_moves,
                                          jitters=section.validation_jitters, seed=section.seed_or(ctx.run_seed),
                                          config_dir=ctx.config_dir)
        validated = {k: v for k, v in agreement.items() if k != "oracle"}
        result.metrics["single_view"] = validated
        result.surrogate.meta.metrics["single_view"] = validated      # what the checkpoint carries
    write_outputs(result, out_dir if out_dir is not None else ctx.folders.surrogate)
    return result, data, cv


def parity_plot(result: TrainResult, file: str | Path, title: str = "surrogate: held-out test trials") -> None:
    """Predicted vs oracle error of the test split, with the y = x line (PNG, written atomically)."""
    file = Path(file)
    fig = Figure(figsize=(4.5, 4.5), dpi=120)
    ax = fig.subplots()
    t, p = result.test_true, result.test_pred
    ax.scatter(t, p, s=10, alpha=0.7)
    if t.size:
        lo, hi = float(min(t.min(), p.min())), float(max(t.max(), p.max()))
        ax.plot([lo, hi], [lo, hi], "k--", lw=1)
    m = result.metrics["test"]
    ax.set_xlabel("oracle error (m)")
    ax.set_ylabel("surrogate error (m)")
    ax.set_title(f"{title}\nR$^2$ {m['r2']:.3f}  RMSE {m['rmse']:.4f} m  n={m['n']}", fontsize=9)
    fig.tight_layout()
    with atomic_path(file) as tmp:
        fig.savefig(tmp, format="png")


def write_outputs(result: TrainResult, out_dir: str | Path) -> dict:
    """surrogate.pt, metrics.json (with the history and the split) and parity.png into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    result.surrogate.save(out / CHECKPOINT_NAME)
    write_json_atomic(out / METRICS_NAME, {**result.metrics, "history": result.history, "split": result.split,
                                           "architecture": result.surrogate.meta.architecture,
                                           "path_digest": result.surrogate.meta.path_digest})
    parity_plot(result, out / PARITY_NAME)
    return {"checkpoint": str(out / CHECKPOINT_NAME), "metrics": str(out / METRICS_NAME),
            "parity": str(out / PARITY_NAME)}
