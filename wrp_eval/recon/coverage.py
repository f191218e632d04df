"""What each view of a capture set covers: the per-view facts a surrogate of the error needs.

From the oracle's own observation model (:func:`wrp_eval.recon.fusion.observe_samples`, every view taken as
registered), per view v with observation weights w_vs of the ground-truth samples s it sees:

* target (3,) m: the weighted centroid of the samples it sees (the patch of ship it photographs);
* normal (3,): their weighted mean surface normal (unit);
* unique_share: sum_s w_vs (w_vs / sum_v' w_v's) / sum_s w_vs, the share of the view's coverage that no
  other view provides (1: nothing else sees its samples; 1/k: k equal views share all of them);
* partners: how many other views see at least ``PARTNER_SHARE`` of its weighted samples (the co-visibility
  graph's degree).

A view that sees nothing gets its own position + its optical axis as the target, the axis reversed as the
normal, unique share 0 and no partners.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.camera import optical_axes
from wrp_eval.recon.fusion import observe_samples
from wrp_eval.sim.captures import CaptureSet

PARTNER_SHARE = 0.1     # a partner sees at least 10 % of the view's weighted samples (a matchable overlap)


@dataclass(frozen=True)
class ViewCoverage:
    """Per view (n,): target (n, 3) m, normal (n, 3), unique_share (n,), partners (n,) (module docstring)."""

    target: np.ndarray
    normal: np.ndarray
    unique_share: np.ndarray
    partners: np.ndarray


def view_coverage(capture_set: CaptureSet, gt, section) -> ViewCoverage:
    """The :class:`ViewCoverage` of ``capture_set`` on the prepared ground truth ``gt`` with the oracle section
    ``section`` (an :class:`wrp_eval.recon.config.OracleSection`)."""
    n = len(capture_set)
    obs = observe_samples(capture_set, gt, np.ones(n, dtype=bool), section, 1.0 / section.gt_density_per_m2)
    w = obs.weight
    n_samples = len(gt.samples)
    per_view = np.bincount(obs.view, weights=w, minlength=n)
    per_sample = np.bincount(obs.sample, weights=w, minlength=n_samples)
    own = np.bincount(obs.view, weights=w * w / np.maximum(per_sample[obs.sample], 1e-12), minlength=n)
    target = np.stack([np.bincount(obs.view, weights=w * gt.samples[obs.sample, k], minlength=n)
                       for k in range(3)], axis=1)
    normal = np.stack([np.bincount(obs.view, weights=w * gt.sample_normals[obs.sample, k], minlength=n)
                       for k in range(3)], axis=1)
    seen = per_view > 1e-12
    axes = optical_axes(capture_set.yaw, capture_set.pitch)
    target = np.where(seen[:, None], target / np.maximum(per_view, 1e-12)[:, None],
                      np.asarray(capture_set.positions, float) + axes)
    norm = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.where(seen[:, None] & (norm > 1e-9), normal / np.maximum(norm, 1e-12), -axes)
    shared = _shared_weight(obs.sample, obs.view, w, n)
    partners = ((shared >= PARTNER_SHARE * per_view[:, None]) & seen[:, None]).sum(axis=1) - seen
    return ViewCoverage(target, normal, np.where(seen, own / np.maximum(per_view, 1e-12), 0.0),
                        partners.astype(float))


def _shared_weight(sample: np.ndarray, view: np.ndarray, weight: np.ndarray, n_views: int) -> np.ndarray:
    """(n, n): entry (v, u) = sum of v's weights over the samples u also sees (observations sorted by sample)."""
    starts = np.flatnonzero(np.r_[True, sample[1:] != sample[:-1]])
    counts = np.diff(np.r_[starts, len(sample)])
    group = np.repeat(np.arange(len(starts)), counts)
    # every ordered pair of observations of one sample (<= MAX_VIEWS_PER_SAMPLE^2 per sample)
    first = np.repeat(np.arange(len(sample)), counts[group])
    offset = np.arange(len(first)) - np.repeat(np.cumsum(counts[group]) - counts[group], counts[group])
    second = starts[group[first]] + offset
    shared = np.zeros((n_views, n_views))
    np.add.at(shared, (view[first], view[second]), weight[first])
    return shared
