"""The scarce coverage one view's move takes away from a plan: the ``scarce`` input set's channel (issue 30).

By the synthetic oracle's own observation model (:func:`wrp_eval.recon.fusion.observe_samples`, every view
registered), per ground-truth sample s, W_s is the planned set's observation weight and R_vs = W_s - a_vs without
view v's own weight. View v flown at another pose, with weights w_s there, takes away

    lost = sum_s [min(W_s, c) - min(R_vs + w_s, c)]      (negative: it adds scarce coverage; 0 at the plan)

with c = :data:`SCARCE_LEVEL`. It ranks the oracle's single-view changes on the inspection path far better than the
surrogate without it (session 26's probe, scripts/probes/scarce_coverage.py; README). It lives in this stage, not
in ``recon``, so that its changes leave the campaigns' code digest (the flight and oracle code) alone.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import trimesh

from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.fusion import observe_samples
from wrp_eval.recon.oracle import GroundTruth, mesh_key, prepare_ground_truth
from wrp_eval.recon.scored_ship import ScoredShip
from wrp_eval.sim.captures import CaptureSet

# the observation weight below which a sample's coverage counts as scarce: picked among 0.5 / 1 / 2 / 3 / 5 by
# the rank of the oracle's single-view changes on the inspection path (session 26, scripts/probes/
# scarce_coverage.py: Spearman 0.53 on the moves it was picked on, 0.58 on others; README)
SCARCE_LEVEL = 2.0


def _sample_weights(capture_set: CaptureSet, gt: GroundTruth, section: OracleSection) -> np.ndarray:
    """(samples,) each ground-truth sample's total observation weight from ``capture_set`` (every view
    registered, the oracle's per-sample cap of views applied)."""
    obs = observe_samples(capture_set, gt, np.ones(len(capture_set), dtype=bool), section,
                          1.0 / section.gt_density_per_m2)
    return np.bincount(obs.sample, weights=obs.weight, minlength=len(gt.samples))


@dataclass(frozen=True, eq=False)
class ScarceCoverage:
    """The scarce coverage one view's move takes away from the ``planned`` capture set, the other views held
    (module docstring).

    Only samples with R_vs < c can change the sum, so each view keeps just those (``samples[v]`` indices,
    ``rest[v]`` their R) and its ``removal`` (n,) = sum_s [min(W_s, c) - min(R_vs, c)]. The moved view is not
    subject to the oracle's per-sample cap of views. ``mesh`` and ``section`` (an OracleSection) give the prepared
    ground truth :attr:`gt`; a pickled copy (a training fold's process) leaves its ray-casting scenes behind and
    prepares them again, the same way the oracle does.
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

    @cached_property
    def digest(self) -> str:
        """A content hash of what decides :meth:`lost`: the ship's mesh, the oracle section, the level and the
        planned views (poses, camera): a checkpoint trained on one refuses another."""
        h = hashlib.blake2b(digest_size=16)
        h.update(mesh_key(self.mesh).encode())
        h.update(json.dumps(self.section.model_dump(mode="json"), sort_keys=True).encode())
        h.update(np.float64(self.level).tobytes())
        p = self.planned
        for values in (p.positions, p.yaw, p.pitch, p.roll if p.roll is not None else np.zeros(len(p))):
            h.update(np.ascontiguousarray(values, dtype=np.float64).tobytes())
        h.update(repr(p.camera).encode())
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

    def lost_views(self, offsets: np.ndarray,
                   views: np.ndarray | list[int] | slice = slice(None)) -> np.ndarray:
        """(..., k) :meth:`lost` of the viewpoints ``views`` (k of them; default every one) at offsets (..., k, 4),
        each view moved alone."""
        off = np.asarray(offsets, dtype=float)
        index = np.arange(len(self))[views]
        if off.ndim < 2 or off.shape[-2:] != (len(index), 4):
            raise ValueError(f"offsets must be (..., {len(index)}, 4) for {len(index)} views, got {off.shape}")
        flat = off.reshape(-1, len(index), 4)
        out = np.stack([self.lost(int(v), flat[:, j]) for j, v in enumerate(index)], axis=1)
        return out.reshape(off.shape[:-1])


def scarce_coverage(planned: CaptureSet, mesh: trimesh.Trimesh, section: OracleSection, gt: GroundTruth,
                    level: float = SCARCE_LEVEL) -> ScarceCoverage:
    """The :class:`ScarceCoverage` of the ``planned`` capture set on the ship ``mesh`` with the oracle section
    ``section``; ``gt``: the mesh's prepared ground truth (the oracle's, :func:`prepare_ground_truth`)."""
    total = _sample_weights(planned, gt, section)
    # each view's own weights, every view at once: uncapped, a (sample, view) pair is one observation
    alone = observe_samples(planned, gt, np.ones(len(planned), dtype=bool), section, 1.0 / section.gt_density_per_m2,
                            max_views_per_sample=None)
    own = np.zeros((len(planned), len(gt.samples)))
    own[alone.view, alone.sample] = alone.weight
    r = total - own                                                   # (n, samples): R_vs
    removal = np.sum(np.minimum(total, level) - np.minimum(r, level), axis=1)
    samples = tuple(np.flatnonzero(row < level) for row in r)
    rest = tuple(row[idx] for row, idx in zip(r, samples, strict=True))
    scarce = ScarceCoverage(planned, mesh, section, float(level), removal, samples, rest)
    scarce.__dict__["gt"] = gt          # the oracle's prepared one (cached_property's slot)
    return scarce


def ship_scarce_coverage(ship: ScoredShip, planned: CaptureSet) -> ScarceCoverage:
    """:func:`scarce_coverage` of ``planned`` on a :class:`ScoredShip` (its mesh, oracle section and prepared
    ground truth)."""
    return scarce_coverage(planned, ship.mesh, ship.oracle.section, ship.oracle.ground_truth(ship.mesh))
