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

:class:`ScarceCoverage` answers a question about moves rather than the plan: how much scarce coverage one view
takes away from the set when it is flown at another pose (the surrogate's ``scarce`` input, issue 30).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import trimesh

from wrp_eval.camera import optical_axes
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.fusion import observe_samples
from wrp_eval.recon.oracle import GroundTruth, prepare_ground_truth
from wrp_eval.sim.captures import CaptureSet

PARTNER_SHARE = 0.1     # a partner sees at least 10 % of the view's weighted samples (a matchable overlap)
# the observation weight below which a sample's coverage counts as scarce: picked among 0.5 / 1 / 2 / 3 / 5 by
# the rank of the oracle's single-view changes on the inspection path (session 26, scripts/probes/
# scarce_coverage.py: Spearman 0.53 on the moves it was picked on, 0.58 on others; surrogate/README.md)
SCARCE_LEVEL = 2.0


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


def _sample_weights(capture_set: CaptureSet, gt, section) -> np.ndarray:
    """(samples,) each ground-truth sample's total observation weight from ``capture_set`` (every view
    registered, the oracle's per-sample cap of views applied)."""
    obs = observe_samples(capture_set, gt, np.ones(len(capture_set), dtype=bool), section,
                          1.0 / section.gt_density_per_m2)
    return np.bincount(obs.sample, weights=obs.weight, minlength=len(gt.samples))


@dataclass(frozen=True)
class ScarceCoverage:
    """The scarce coverage one view's move takes away from a planned capture set, the other views held.

    Per ground-truth sample s, W_s is the planned set's observation weight (the oracle's own model,
    :func:`wrp_eval.recon.fusion.observe_samples`, every view registered) and R_vs = W_s - a_vs without view v's
    own weight. View v flown at another pose, with weights w_s there, takes away
    lost = sum_s [min(W_s, c) - min(R_vs + w_s, c)] (negative: it adds scarce coverage), c = ``level``; 0 at
    the planned pose. Only samples with R_vs < c can change the sum, so each view keeps just those
    (``samples[v]`` indices, ``rest[v]`` their R) and its ``removal`` (n,) = sum_s [min(W_s, c) - min(R_vs, c)].
    The moved view is not subject to the oracle's per-sample cap of views. ``mesh`` and ``section`` (an
    OracleSection) give the prepared ground truth :attr:`gt`; a pickled copy (a training fold's process) leaves its
    ray-casting scenes behind and prepares them again, the same way the oracle does.
    """

    planned: CaptureSet
    mesh: trimesh.Trimesh
    section: OracleSection
    level: float
    removal: np.ndarray
    samples: tuple[np.ndarray, ...]
    rest: tuple[np.ndarray, ...]

    def __len__(self) -> int:
        return len(self.planned)

    @cached_property
    def gt(self) -> GroundTruth:
        return prepare_ground_truth(self.mesh, self.section.gt_density_per_m2, self.section.gt_seed)

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k != "gt"}      # open3d scenes do not pickle

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    def digest(self) -> str:
        """A content hash of what decides :meth:`lost` (the level, every view's scarce samples, their positions and
        rest weights, the planned poses): a checkpoint trained on one refuses another."""
        h = hashlib.blake2b(digest_size=16)
        h.update(np.float64(self.level).tobytes())
        h.update(np.round(np.asarray(self.planned.positions, float), 6).tobytes())
        h.update(np.round(np.asarray(self.planned.yaw, float), 9).tobytes())
        for idx, rest in zip(self.samples, self.rest, strict=True):
            h.update(np.round(self.gt.samples[idx], 6).tobytes())
            h.update(np.round(rest, 9).tobytes())
        return h.hexdigest()

    def lost(self, view: int, offsets: np.ndarray) -> np.ndarray:
        """(m,) the scarce coverage view ``view`` takes away when flown at planned + ``offsets`` (m, 4: dx, dy,
        dz m, dyaw rad)."""
        off = np.asarray(offsets, dtype=float).reshape(-1, 4)
        idx, rest = self.samples[view], self.rest[view]
        if idx.size == 0 or len(off) == 0:
            return np.full(len(off), self.removal[view])
        gt = replace(self.gt, samples=self.gt.samples[idx], sample_normals=self.gt.sample_normals[idx])
        base = self.planned.subset(np.array([view]))
        cands = replace(base.subset(np.zeros(len(off), dtype=int)), positions=base.positions + off[:, :3],
                        yaw=base.yaw + off[:, 3])
        # every candidate's own observations: no per-sample cap, the candidates are alternatives, not a set
        obs = observe_samples(cands, gt, np.ones(len(off), dtype=bool), self.section,
                              1.0 / self.section.gt_density_per_m2, max_views_per_sample=None)
        r = rest[obs.sample]
        gained = np.minimum(r + obs.weight, self.level) - np.minimum(r, self.level)
        regain: np.ndarray = np.bincount(obs.view, weights=gained, minlength=len(off))
        return self.removal[view] - regain

    def lost_views(self, offsets: np.ndarray, views: list[int] | slice = slice(None)) -> np.ndarray:
        """(..., k) :meth:`lost` of the viewpoints ``views`` (k of them; default every one) at offsets (..., k, 4),
        each view moved alone."""
        off = np.asarray(offsets, dtype=float)
        index = np.arange(len(self))[views]
        flat = off.reshape(-1, len(index), 4)
        out = np.stack([self.lost(int(v), flat[:, j]) for j, v in enumerate(index)], axis=1)
        return out.reshape(off.shape[:-1])


def scarce_coverage(planned: CaptureSet, mesh: trimesh.Trimesh, section: OracleSection, gt: GroundTruth,
                    level: float = SCARCE_LEVEL) -> ScarceCoverage:
    """The :class:`ScarceCoverage` of the ``planned`` capture set on the ship ``mesh`` with the oracle section
    ``section``; ``gt``: the mesh's prepared ground truth (the oracle's, :func:`prepare_ground_truth`)."""
    total = _sample_weights(planned, gt, section)
    kept = np.minimum(total, level)
    removal, samples, rest = np.zeros(len(planned)), [], []
    for v in range(len(planned)):
        own = _sample_weights(planned.subset(np.array([v])), gt, section)
        r = total - own
        removal[v] = float(np.sum(kept - np.minimum(r, level)))
        idx = np.flatnonzero(r < level)
        samples.append(idx)
        rest.append(r[idx])
    scarce = ScarceCoverage(planned, mesh, section, float(level), removal, tuple(samples), tuple(rest))
    scarce.__dict__["gt"] = gt          # the oracle's prepared one (cached_property's slot)
    return scarce
