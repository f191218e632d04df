"""The surrogate network, its checkpoint, and an exact incremental evaluator for one-viewpoint changes.

Architecture (paper Sec. 4.1 fits "a CNN regression model"; the layout here is ours): the viewpoint sequence
is a 1-D signal with one sample per viewpoint and standardised input channels, in this order: the 4 offsets
(dx, dy, dz, dyaw); with the ``per_view`` input set the 3 flown-geometry channels computed from them (with
``scarce`` also the scarce coverage lost) and the 5 conditions at the shutter (:mod:`wrp_eval.surrogate.features`);
the 7 planned-pose channels; with ``per_view`` / ``scarce`` the 2 coverage channels. The offsets and the channels
computed from them are what a candidate move changes;
``layers`` x (Conv1d 'same' zero padding + GELU) -> global MEAN
pooling over the viewpoints -> Linear-GELU-Linear head -> standardised error [+ failure logit]; optionally
(``view_outputs``) a linear per-viewpoint head on the last conv features, trained as an auxiliary task
(whether the oracle registered each view) and not used by the queries.

Why mean pooling: a change of ONE viewpoint's offsets then changes the conv features only within the receptive
field around it, and the pooled vector by a local sum. :class:`ViewQuery` uses that to score thousands of
candidate offsets of one viewpoint at a fraction of a full forward pass, exactly (up to float rounding).
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from wrp_eval.atomic import write_bytes_atomic
from wrp_eval.errors import InputError
from wrp_eval.surrogate.features import (
    CONDITION_NAMES,
    INPUT_SETS,
    ViewContext,
    conditions_or_reference,
    moving_features,
    moving_names,
)

if TYPE_CHECKING:
    from wrp_eval.surrogate.scarce import ScarceCoverage

CHECKPOINT_FORMAT = "wrp-eval-surrogate"
CHECKPOINT_VERSION = 2    # 2: input sets and per-view inputs; version 1 checkpoints are refused
VARIABLE_CHANNELS = {k: 4 + len(moving_names(k)) for k in INPUT_SETS}     # channels a candidate move changes


class ViewSequenceCNN(nn.Module):
    """1-D CNN over the viewpoint sequence: (batch, n_views, in_channels) -> (batch, outputs).

    The conv layers are ``nn.Conv1d`` parameters (weight (C, C_in, k)), evaluated as one matmul over the k
    shifted copies of the sequence (identical to Conv1d with 'same' zero padding; measured about 2x faster
    than ``F.conv1d`` for these small channel counts on this CPU). ``view_outputs`` > 0: a linear head per
    viewpoint on the last conv features (:meth:`forward_with_views`), besides the pooled one.
    """

    def __init__(self, in_channels: int, channels: int = 32, kernel: int = 5, layers: int = 2, hidden: int = 32,
                 outputs: int = 1, view_outputs: int = 0):
        super().__init__()
        if kernel % 2 == 0:
            raise ValueError("kernel must be odd")
        self.kernel = kernel
        self.convs = nn.ModuleList(
            nn.Conv1d(in_channels if i == 0 else channels, channels, kernel, padding=kernel // 2)
            for i in range(layers))
        self.head = nn.Sequential(nn.Linear(channels, hidden), nn.GELU(), nn.Linear(hidden, outputs))
        # per-viewpoint logits read linearly off the last features (the registration head; not used by queries):
        # being linear, their mean over the path is a linear function of the pooled vector the error head reads
        self.view_head = nn.Linear(channels, view_outputs) if view_outputs else None

    def conv_pre(self, layer: int, x: torch.Tensor) -> torch.Tensor:
        """Pre-activation of conv ``layer``: (batch, n, C_in) -> (batch, n, C), 'same' zero padding."""
        conv = cast(nn.Conv1d, self.convs[layer])
        h, n = self.kernel // 2, x.shape[1]
        xp = F.pad(x, (0, 0, h, h))
        cols = torch.cat([xp[:, j:j + n] for j in range(self.kernel)], dim=-1)      # (batch, n, k C_in)
        w = conv.weight.permute(0, 2, 1).reshape(conv.weight.shape[0], -1)          # (C, k C_in)
        bias = cast(torch.Tensor, conv.bias)                                        # created with bias=True
        return torch.addmm(bias, cols.reshape(-1, cols.shape[-1]), w.t()).view(x.shape[0], n, -1)

    def trunk(self, x: torch.Tensor) -> torch.Tensor:
        """(batch, n, in_channels) -> (batch, n, channels) features per viewpoint."""
        for layer in range(len(self.convs)):
            x = F.gelu(self.conv_pre(layer, x))
        return x

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.trunk(x).mean(dim=1))

    def forward_with_views(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(outputs (batch, outputs), per-view logits (batch, n, view_outputs)) from one pass of the trunk (a
        network built with ``view_outputs``)."""
        if self.view_head is None:
            raise ValueError("this network has no per-view head (view_outputs = 0)")
        features = self.trunk(x)
        return self.head(features.mean(dim=1)), self.view_head(features)


@dataclass(frozen=True)
class SurrogateMeta:
    """Everything a checkpoint needs besides the weights.

    n_views; path_digest: the campaign's hash of the path trained on (None: not tied to a stored path);
    architecture: ViewSequenceCNN keyword arguments; offset_mean/offset_std (4,), pose_mean/pose_std (7,):
    input standardisation; error_mean/error_std: target standardisation (of the error in m, or of its natural
    log when ``target`` is "log_error"); planned_pose (n_views, 7) or None;
    offset_low/offset_high (4,): range of the training offsets (the surrogate's domain); metrics: held-out
    figures; extra: free-form provenance (data source, seed, epochs run); inputs: the input set
    (:data:`wrp_eval.surrogate.features.INPUT_SETS`); views: the path's ViewContext (JSON) for ``per_view`` and
    ``scarce``; feature_mean/feature_std (10,) or (11,): standardisation of the moving (geometry [+ scarce]),
    condition and coverage channels; scarce_digest: :attr:`ScarceCoverage.digest` of the ship and plan the
    ``scarce`` channel was computed on.
    """

    n_views: int
    path_digest: str | None
    architecture: dict
    offset_mean: list
    offset_std: list
    error_mean: float
    error_std: float
    pose_mean: list | None = None
    pose_std: list | None = None
    planned_pose: list | None = None
    offset_low: list | None = None
    offset_high: list | None = None
    target: str = "error"
    metrics: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    inputs: str = "offsets"
    views: dict | None = None
    feature_mean: list | None = None
    feature_std: list | None = None
    scarce_digest: str | None = None


def _metadata(meta: SurrogateMeta) -> dict:
    """The checkpoint's metadata: ``meta`` as a dict, without a None ``scarce_digest`` (checkpoints of the other
    input sets stay readable by code from before that field)."""
    doc = asdict(meta)
    if doc["scarce_digest"] is None:
        del doc["scarce_digest"]
    return doc


class Surrogate:
    """A trained network with its standardisation: offsets (batch, n_views, 4) -> predicted error (batch,) m.

    ``scarce``: the :class:`ScarceCoverage` of the path on the ship, which the ``scarce`` input set computes its
    channel with (required there, its digest checked; ignored by the other input sets)."""

    def __init__(self, net: ViewSequenceCNN, meta: SurrogateMeta, scarce: ScarceCoverage | None = None):
        self.net = net.eval()
        self.meta = meta
        self._off_mean = torch.tensor(meta.offset_mean, dtype=torch.float32)
        self._off_std = torch.tensor(meta.offset_std, dtype=torch.float32)
        self._pose = None
        if meta.planned_pose is not None:
            pose = (np.asarray(meta.planned_pose, float) - np.asarray(meta.pose_mean)) / np.asarray(meta.pose_std)
            self._pose = torch.tensor(pose, dtype=torch.float32).unsqueeze(0)     # (1, n, 7)
        self.views = ViewContext.from_json_dict(meta.views) if meta.views is not None else None
        self.variable_channels = VARIABLE_CHANNELS[meta.inputs]
        self.n_moving = self.variable_channels - 4            # channels computed from the offsets
        self.scarce = scarce if meta.inputs == "scarce" else None
        if meta.inputs == "scarce" and (scarce is None or scarce.digest != meta.scarce_digest):
            raise ValueError("the scarce input set needs the ScarceCoverage it was trained on"
                             + (" (another ship, oracle or plan)" if scarce is not None else ""))
        if self.views is not None and meta.inputs != "offsets":
            self._feat_mean = np.asarray(meta.feature_mean, float)
            self._feat_std = np.asarray(meta.feature_std, float)
            n_varying = self.n_moving + len(CONDITION_NAMES)
            cover = (self.views.coverage() - self._feat_mean[n_varying:]) / self._feat_std[n_varying:]
            self._cover = torch.tensor(cover, dtype=torch.float32).unsqueeze(0)   # (1, n, 2)

    @property
    def n_views(self) -> int:
        return self.meta.n_views

    @property
    def variable_scale(self) -> np.ndarray:
        """(variable_channels,) the standard deviations of the channels a candidate move changes."""
        scale = np.asarray(self.meta.offset_std, float)
        return np.concatenate([scale, self._feat_std[:self.n_moving]]) if self.n_moving else scale

    def moving_features(self, offsets: np.ndarray, views: list[int] | slice = slice(None),
                        taken: np.ndarray | None = None) -> np.ndarray:
        """(..., k, n_moving) the channels computed from offsets (..., k, 4) of the viewpoints ``views``: the flown
        geometry [+ the scarce coverage lost; a view not ``taken`` loses its whole share], unstandardised."""
        return moving_features(cast(ViewContext, self.views), self.scarce, offsets, views, taken)

    def input_tensor(self, offsets: np.ndarray | torch.Tensor, conditions: np.ndarray | None = None) -> torch.Tensor:
        """(batch, n_views, 4) offsets [+ (batch, n_views, 5) conditions at the shutter, default the forecast
        reference] -> (batch, n_views, in_channels) standardised network input."""
        off_np = np.asarray(offsets, dtype=float)
        x = (torch.as_tensor(off_np, dtype=torch.float32) - self._off_mean) / self._off_std
        parts = [x]
        if self.n_moving:
            views = cast(ViewContext, self.views)
            cond = conditions_or_reference(conditions, views.condition_reference, x.shape[0])
            feat = np.concatenate([self.moving_features(off_np, taken=cond[..., -1] >= 0.5), cond], axis=2)
            n_varying = feat.shape[2]
            parts.append(torch.as_tensor((feat - self._feat_mean[:n_varying]) / self._feat_std[:n_varying],
                                         dtype=torch.float32))
        if self._pose is not None:
            parts.append(self._pose.expand(x.shape[0], -1, -1))
        if self.n_moving:
            parts.append(self._cover.expand(x.shape[0], -1, -1))
        return torch.cat(parts, dim=2) if len(parts) > 1 else x

    @torch.no_grad()
    def predict(self, offsets: np.ndarray, conditions: np.ndarray | None = None, batch: int = 8192) -> np.ndarray:
        """(batch, n_views, 4) offsets [+ conditions (batch, n_views, 5), default the forecast reference] ->
        (batch,) predicted error (m)."""
        offsets = np.asarray(offsets, dtype=np.float32)
        if offsets.ndim != 3 or offsets.shape[1:] != (self.n_views, 4):
            raise ValueError(f"offsets must be (batch, {self.n_views}, 4), got {offsets.shape}")
        cond = None if conditions is None else np.asarray(conditions, float)
        out = [self.net(self.input_tensor(offsets[i:i + batch], None if cond is None else cond[i:i + batch]))[:, 0]
               for i in range(0, len(offsets), batch)]
        y = torch.cat(out).double().numpy() if out else np.zeros(0)
        return self.to_error(y)

    def to_error(self, standardised: np.ndarray) -> np.ndarray:
        """The network's standardised output -> reconstruction error (m)."""
        y = np.asarray(standardised, float) * self.meta.error_std + self.meta.error_mean
        return np.exp(y) if self.meta.target == "log_error" else y

    @torch.no_grad()
    def predict_failure(self, offsets: np.ndarray, conditions: np.ndarray | None = None) -> np.ndarray:
        """(batch,) probability of failure (needs a model trained with ``predict_failure``)."""
        if self.meta.architecture.get("outputs", 1) < 2:
            raise InputError("surrogate", "this checkpoint was trained without a failure output")
        logit = self.net(self.input_tensor(np.asarray(offsets, np.float32), conditions))[:, 1]
        return torch.sigmoid(logit).double().numpy()

    # -- checkpoint ---------------------------------------------------------------------------------------
    def save(self, file: str | Path) -> None:
        """state_dict + metadata (as a JSON string: plain data for ``torch.load(weights_only=True)``), written
        atomically."""
        doc = {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION,
               "metadata_json": json.dumps(_metadata(self.meta)),
               "state_dict": {k: v.detach().clone() for k, v in self.net.state_dict().items()}}
        buf = io.BytesIO()
        torch.save(doc, buf)
        write_bytes_atomic(file, buf.getvalue())

    @classmethod
    def load(cls, file: str | Path, *, n_views: int | None = None, path_digest: str | set[str] | None = None,
             inputs: str | None = None,
             scarce: ScarceCoverage | Callable[[], ScarceCoverage] | None = None) -> "Surrogate":
        """Load a checkpoint (``torch.load(weights_only=True)``). A corrupt file, another format or version, one
        trained for another path (``n_views``, ``path_digest`` when both sides know it), on another input set
        than ``inputs`` (when given) or, for the ``scarce`` input set, on another ship, oracle or plan than
        ``scarce`` (the path's :class:`ScarceCoverage`, or a function that builds it: called only for a ``scarce``
        checkpoint) is an :class:`InputError`."""
        file = Path(file)
        if not file.is_file():
            raise InputError(file, "no such surrogate checkpoint")
        try:
            doc = torch.load(file, map_location="cpu", weights_only=True)
        except Exception as err:  # torch raises many types for a damaged or foreign file
            raise InputError(file, f"not a readable surrogate checkpoint ({type(err).__name__}: "
                                   f"{str(err).splitlines()[0] if str(err) else ''})") from None
        if not isinstance(doc, dict) or doc.get("format") != CHECKPOINT_FORMAT:
            raise InputError(file, "not a wrp-eval surrogate checkpoint")
        if doc.get("version") != CHECKPOINT_VERSION:
            raise InputError(file, f"checkpoint version {doc.get('version')!r} is not {CHECKPOINT_VERSION}; "
                                   "retrain with `wrp-eval train`")
        try:
            meta = SurrogateMeta(**json.loads(doc["metadata_json"]))
            net = ViewSequenceCNN(**meta.architecture)
            net.load_state_dict(doc["state_dict"])
        except Exception as err:
            raise InputError(file, f"damaged surrogate checkpoint: {type(err).__name__}: "
                                   f"{str(err).splitlines()[0] if str(err) else ''}") from None
        if meta.inputs not in INPUT_SETS or (meta.inputs != "offsets" and meta.views is None):
            raise InputError(file, f"damaged surrogate checkpoint: input set {meta.inputs!r} without its views")
        if inputs is not None and meta.inputs != inputs:
            raise InputError(file, f"checkpoint was trained on the input set {meta.inputs!r}, the config asks for "
                                   f"{inputs!r} (surrogate.inputs); retrain with `wrp-eval train`")
        check_path(meta, n_views, path_digest, source=file)
        cover = None
        if meta.inputs == "scarce":
            cover = scarce() if callable(scarce) else scarce
            if cover is None or cover.digest != meta.scarce_digest:
                raise InputError(file, "checkpoint's scarce-coverage channel (surrogate.inputs: scarce) was computed "
                                       "on " + ("another ship, oracle or plan than this config's" if cover is not None
                                                else "a ship and oracle not given to the loader"))
        try:
            surrogate = cls(net, meta, cover)
        except Exception as err:
            raise InputError(file, f"damaged surrogate checkpoint: {type(err).__name__} in its metadata") from None
        return surrogate

    def check_path(self, n_views: int | None, path_digest: str | set[str] | None,
                   source: str | Path = "surrogate") -> None:
        """Refuse use on a path the checkpoint was not trained for (:func:`check_path`)."""
        check_path(self.meta, n_views, path_digest, source)


def check_path(meta: SurrogateMeta, n_views: int | None, path_digest: str | set[str] | None,
               source: str | Path = "surrogate") -> None:
    """Refuse a checkpoint's ``meta`` on a path it was not trained for. ``path_digest``: the path's digest, or a set
    of digests that all identify it (the file's own JSON and its re-serialisation, which can differ in the last
    bits of the degree <-> radian round trip)."""
    if n_views is not None and int(n_views) != meta.n_views:
        raise InputError(source, f"checkpoint was trained for a path of {meta.n_views} viewpoints, "
                                 f"this path has {n_views}")
    digests = {path_digest} if isinstance(path_digest, str) else set(path_digest or ())
    if digests and meta.path_digest is not None and meta.path_digest not in digests:
        raise InputError(source, f"checkpoint was trained for path {meta.path_digest}, "
                                 f"not this path ({', '.join(sorted(digests))})")


class ViewQuery:
    """Predicted error of a path when ONE viewpoint's offsets are replaced, the others held at ``base``.

    Exact local evaluation by delta propagation: the first conv is linear in the input, so a change of
    viewpoint i's offsets changes layer 1's pre-activation only at i +- h (h = kernel // 2) by W1 * delta;
    layer l's pre-activation changes by a 'full' convolution of the previous layer's activation change, over
    i +- l h. Activations outside the path are zeroed after every layer (what the 'same' zero padding of the
    full network sees), and the cached pooled sum is updated by the local change. Per query this costs
    about (2 l h + 1) C^2 k multiply-adds for layer l instead of n_views (C^2 k + ...) for a full pass.
    ``forward_calls`` counts batched evaluations (one per :meth:`errors` call), ``queries`` the candidates.
    """

    def __init__(self, surrogate: Surrogate, base_offsets: np.ndarray):
        self.s = surrogate
        net = surrogate.net
        self.h = net.kernel // 2
        self.P = len(net.convs) * self.h
        self.n = surrogate.n_views
        self.forward_calls = 0
        self.queries = 0
        # every layer's taps as (k, C_in, C): tap j maps a change at position i to position i + h - j; the first
        # layer's only on the channels a move changes (offsets [+ flown geometry]), unstandardised
        m = surrogate.variable_channels
        scale = torch.as_tensor(surrogate.variable_scale, dtype=torch.float32).view(1, m, 1)
        w1 = cast(nn.Conv1d, net.convs[0]).weight[:, :m, :].detach() / scale                # (C, m, k)
        self._taps = [w1.permute(2, 1, 0).contiguous()] + [
            c.weight.detach().permute(2, 1, 0).contiguous() for c in cast("Iterable[nn.Conv1d]", net.convs[1:])]
        self.set_base(base_offsets)

    @torch.no_grad()
    def set_base(self, base_offsets: np.ndarray) -> None:
        """Cache every layer's pre-activation and activation for the base offsets (n_views, 4)."""
        base = np.asarray(base_offsets, dtype=np.float32).reshape(1, self.n, 4)
        self.base = base[0].copy()
        x = self.s.input_tensor(base)                                      # (1, n, Cin)
        P = self.P
        self.pre, self.act = [], []
        for layer in range(len(self.s.net.convs)):
            pre = self.s.net.conv_pre(layer, x)
            x = F.gelu(pre)
            self.pre.append(F.pad(pre[0], (0, 0, P, P)))                   # (n + 2P, C) path at [P, P + n)
            self.act.append(F.pad(x[0], (0, 0, P, P)))                     # zeros outside the path
        self.pooled_sum = x[0].sum(dim=0)                                  # (C,)
        inside = torch.zeros(self.n + 2 * P)
        inside[P:P + self.n] = 1.0
        self._inside = inside.view(-1, 1, 1)

    def _variables(self, index: int, candidates: np.ndarray) -> torch.Tensor:
        """(q, m) change of the move-dependent channels (offsets [+ moving features], unstandardised) of viewpoint
        ``index`` from the base to each candidate (q, 4)."""
        base = self.base[index].astype(float)
        delta = candidates - base
        if self.s.n_moving:
            moving = self.s.moving_features(np.concatenate([candidates, base[None]])[:, None, :], views=[index])[:, 0]
            delta = np.concatenate([delta, moving[:-1] - moving[-1]], axis=1)
        return torch.as_tensor(delta, dtype=torch.float32)

    def update_view(self, index: int, offset: np.ndarray) -> None:
        """Set viewpoint ``index``'s base offset (4,) and refresh the cache."""
        base = self.base.copy()
        base[index] = offset
        self.set_base(base)

    @torch.no_grad()
    def errors(self, index: int, candidates: np.ndarray) -> np.ndarray:
        """(q, 4) candidate offsets of viewpoint ``index`` -> (q,) predicted path error (m)."""
        candidates = np.asarray(candidates, dtype=float)
        q = candidates.shape[0]
        self.forward_calls += 1
        self.queries += q
        h, n, k = self.h, self.n, self.s.net.kernel
        c = index + self.P                                                 # padded coordinate of the view
        delta_in = self._variables(index, candidates)                      # (q, m)
        # position-major (w, q, C): every tap adds into a contiguous block of positions. Each layer's change is the
        # 'full' convolution of the previous one's (at first the input's, at the view alone): lo-h .. hi+h-1
        lo, hi = c, c + 1
        change = delta_in                                                  # (width q, m): width 1, the view
        for layer, taps in enumerate(self._taps):
            width = hi - lo
            lo, hi = lo - h, hi + h
            pre = self.pre[layer][lo:hi, None, :].repeat(1, q, 1)
            for j in range(k):
                pre[2 * h - j:2 * h - j + width].view(width * q, -1).addmm_(change, taps[j])
            delta_act = self._activation_change(layer, pre, lo, hi)
            change = delta_act.reshape((hi - lo) * q, -1)
        pooled = (self.pooled_sum + delta_act.sum(dim=0)) / n             # (q, C)
        return self.s.to_error(self.s.net.head(pooled)[:, 0].double().numpy())

    def _activation_change(self, layer: int, pre: torch.Tensor, lo: int, hi: int) -> torch.Tensor:
        """(w, q, C) change of conv ``layer``'s activation at padded positions [lo, hi) from the candidates'
        pre-activations ``pre`` (w, q, C); zero outside the path, as the full network's 'same' padding sees it."""
        new = F.gelu(pre)
        if lo < self.P or hi > self.P + self.n:                            # at the path's ends
            new = new * self._inside[lo:hi]
        return new - self.act[layer][lo:hi, None, :]
