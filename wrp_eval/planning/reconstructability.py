"""Reconstructability of samples from view pairs (Smith et al. 2018, "Aerial path planning for urban scene
reconstruction", Sec. 4; set form as in Zhou et al. 2020, "Offsite aerial path planning").

q(s, v1, v2) = w1(alpha) w2(d_m) w3(alpha) cos(theta_m), with alpha the angle between the two viewing rays
at s, d_m the larger view distance, theta_m the larger angle between a ray and the normal n, and
w1 = 1/(1+exp(-k1 (alpha - alpha1))), w2 = 1 - min(d_m/d_max, 1), w3 = 1 - 1/(1+exp(-k3 (alpha - alpha3))).
h(s, V) = sum of q over all pairs of views in V that see s.

:class:`SlotTable` lays the visibility out per sample ("slots" = the views that see it, padded to the
largest count), so that q of one view against every other view of a sample is one vectorised row and
removing / adding / swapping a view updates h incrementally.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from wrp_eval.compiled import kernel

K1, ALPHA1 = 32.0, np.pi / 16.0   # Smith et al. 2018
K3, ALPHA3 = 8.0, np.pi / 4.0


def pair_reconstructability(cos_alpha: np.ndarray, d_max_pair: np.ndarray, cos_theta_max: np.ndarray,
                            d_max: float) -> np.ndarray:
    """q from the cosine of the triangulation angle, the larger distance (m) and the cosine of the larger
    incidence angle (all broadcastable arrays)."""
    alpha = np.arccos(np.clip(cos_alpha, -1.0, 1.0))
    w1 = 1.0 / (1.0 + np.exp(-K1 * (alpha - ALPHA1)))
    w2 = 1.0 - np.minimum(d_max_pair / d_max, 1.0)
    w3 = 1.0 - 1.0 / (1.0 + np.exp(-K3 * (alpha - ALPHA3)))
    return w1 * w2 * w3 * cos_theta_max


def pair_reconstructability_points(point: np.ndarray, normal: np.ndarray, view_a: np.ndarray,
                                   view_b: np.ndarray, d_max: float) -> np.ndarray:
    """q(s, v1, v2) straight from positions: point, normal (n, 3) and two view positions (n, 3) each."""
    ra, rb = view_a - point, view_b - point
    da, db = np.linalg.norm(ra, axis=-1), np.linalg.norm(rb, axis=-1)
    cos_alpha = np.einsum("...i,...i->...", ra, rb) / (da * db)
    cos_ta = np.einsum("...i,...i->...", ra, normal) / da
    cos_tb = np.einsum("...i,...i->...", rb, normal) / db
    return pair_reconstructability(cos_alpha, np.maximum(da, db), np.minimum(cos_ta, cos_tb), d_max)


def set_reconstructability(point: np.ndarray, normal: np.ndarray, views: np.ndarray, d_max: float) -> float:
    """h(s, V) for one sample and the views (k, 3) that see it (reference form, for tests and checks)."""
    ia, ib = np.triu_indices(len(views), k=1)
    q = pair_reconstructability_points(point[None], normal[None], views[ia], views[ib], d_max)
    return float(q.sum())


@kernel
def masked_first_columns(mask: NDArray[np.bool_], width: int) -> NDArray[np.int64]:
    """(T, width) column indices of ``mask`` (T, M) bool, per row the masked columns first, then the others,
    each in increasing order: ``np.argsort(~mask, axis=1, kind="stable")[:, :width]`` without the sort (one
    pass per row; the sort was 40 % of :meth:`SlotTable.q_sums`)."""
    rows, m = mask.shape
    cols = np.empty((rows, width), dtype=np.int64)
    for r in range(rows):
        k = 0
        for j in range(m):
            if mask[r, j]:
                if k < width:
                    cols[r, k] = j
                k += 1
        for j in range(m):
            if k >= width:
                break
            if not mask[r, j]:
                cols[r, k] = j
                k += 1
    return cols


@kernel
def _slot_layout(visible, points, normals, positions):
    """The arrays of :class:`SlotTable` from a visibility (n_v, n_s) bool, in one pass over it in memory order
    (view-major): a sample's slots hold its views in increasing order, and the view-major pass meets each view's
    (sample, slot) entries sorted by sample, which is the CSR from a view. Returns slot_view, ray, dist,
    cos_theta, view_ptr, view_sample, view_slot and the views per sample (n_s,)."""
    n_v, n_s = visible.shape
    counts = np.zeros(n_s, dtype=np.int64)
    view_ptr = np.zeros(n_v + 1, dtype=np.int64)
    for v in range(n_v):
        for s in range(n_s):
            if visible[v, s]:
                counts[s] += 1
                view_ptr[v + 1] += 1
    view_ptr = np.cumsum(view_ptr)
    width = max(counts.max() if n_s else 0, 1)
    slot_view = np.full((n_s, width), -1, dtype=np.int64)
    ray = np.zeros((n_s, width, 3))
    dist = np.full((n_s, width), np.inf)
    cos_theta = np.zeros((n_s, width))
    view_sample = np.empty(view_ptr[-1], dtype=np.int64)
    view_slot = np.empty(view_ptr[-1], dtype=np.int64)
    filled = np.zeros(n_s, dtype=np.int64)
    k = 0
    for v in range(n_v):
        for s in range(n_s):
            if not visible[v, s]:
                continue
            slot = filled[s]
            filled[s] += 1
            slot_view[s, slot] = v
            r0, r1, r2 = positions[v, 0] - points[s, 0], positions[v, 1] - points[s, 1], positions[v, 2] - points[s, 2]
            d = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
            dist[s, slot] = d
            ray[s, slot, 0], ray[s, slot, 1], ray[s, slot, 2] = r0 / d, r1 / d, r2 / d
            cos_theta[s, slot] = (ray[s, slot, 0] * normals[s, 0] + ray[s, slot, 1] * normals[s, 1]
                                  + ray[s, slot, 2] * normals[s, 2])
            view_sample[k], view_slot[k] = s, slot
            k += 1
    return slot_view, ray, dist, cos_theta, view_ptr, view_sample, view_slot, counts


@kernel
def _pair_cache(ray, dist, cos_theta, counts, d_max):
    """(n_s, M, M) float32: q of every pair of the occupied slots of each sample (slots 0..counts[s]-1), 0 for
    padding and on the diagonal. The formula of :func:`pair_reconstructability`, each pair computed once (q is
    symmetric: the same products and sums in either order)."""
    n_s, width = dist.shape
    out = np.zeros((n_s, width, width), dtype=np.float32)
    for s in range(n_s):
        for a in range(counts[s]):
            for b in range(a + 1, counts[s]):
                dot = ray[s, a, 0] * ray[s, b, 0] + ray[s, a, 1] * ray[s, b, 1] + ray[s, a, 2] * ray[s, b, 2]
                alpha = np.arccos(min(max(dot, -1.0), 1.0))
                w1 = 1.0 / (1.0 + np.exp(-K1 * (alpha - ALPHA1)))
                w2 = 1.0 - min(max(dist[s, a], dist[s, b]) / d_max, 1.0)
                w3 = 1.0 - 1.0 / (1.0 + np.exp(-K3 * (alpha - ALPHA3)))
                q = w1 * w2 * w3 * min(cos_theta[s, a], cos_theta[s, b])
                out[s, a, b] = q
                out[s, b, a] = q
    return out


@dataclass
class SlotTable:
    """Per-sample view slots of a visibility matrix.

    slot_view (n_s, M) int view index or -1; ray (n_s, M, 3) unit sample->view; dist (n_s, M) m;
    cos_theta (n_s, M); view_ptr (n_v + 1,), view_sample, view_slot (nnz,): CSR from a view to its
    (sample, slot) pairs; d_max m. ``cache`` (n_s, M, M) float32 holds all q when built with cache=True.
    """

    slot_view: np.ndarray
    ray: np.ndarray
    dist: np.ndarray
    cos_theta: np.ndarray
    view_ptr: np.ndarray
    view_sample: np.ndarray
    view_slot: np.ndarray
    d_max: float
    cache: np.ndarray | None = None

    @classmethod
    def build(cls, visible: np.ndarray, points: np.ndarray, normals: np.ndarray, positions: np.ndarray,
              d_max: float, cache: bool = False) -> "SlotTable":
        """From a boolean visibility (n_v, n_s) and the geometry."""
        slot_view, ray, dist, cos_theta, view_ptr, view_sample, view_slot, counts = _slot_layout(
            np.ascontiguousarray(visible, dtype=np.bool_), np.asarray(points, dtype=float),
            np.asarray(normals, dtype=float), np.asarray(positions, dtype=float))
        table = cls(slot_view, ray, dist, cos_theta, view_ptr, view_sample, view_slot, float(d_max))
        if cache:
            table.cache = _pair_cache(table.ray, table.dist, table.cos_theta, counts, float(d_max))
        return table

    @property
    def n_samples(self) -> int:
        return int(self.slot_view.shape[0])

    def entries(self, view: int | np.integer[Any]) -> tuple[np.ndarray, np.ndarray]:
        """(samples, slots) where ``view`` sits."""
        a, b = self.view_ptr[view], self.view_ptr[view + 1]
        return self.view_sample[a:b], self.view_slot[a:b]

    def q_sums(self, samples: np.ndarray, slots: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """sum over b of q(s_t, slot_t, b) * mask[t, b] (T,): the h contribution of one view against the
        masked (e.g. active) views of its sample. Only masked slots are evaluated: rows are compacted to
        the largest masked count, far below M when few views are active."""
        if samples.size == 0:
            return np.zeros(0)
        if self.cache is not None:
            return (self.cache[samples, slots] * mask).sum(axis=1)
        width = int(mask.sum(axis=1).max())
        if width == 0:
            return np.zeros(len(samples))
        cols = masked_first_columns(np.ascontiguousarray(mask, dtype=np.bool_), width)  # masked slots first
        valid = np.take_along_axis(mask, cols, axis=1)
        valid &= cols != slots[:, None]
        s2 = np.broadcast_to(samples[:, None], cols.shape)
        cos_alpha = np.einsum("ti,tki->tk", self.ray[samples, slots], self.ray[s2, cols])
        d_pair = np.maximum(self.dist[samples, slots][:, None], self.dist[s2, cols])
        cos_t = np.minimum(self.cos_theta[samples, slots][:, None], self.cos_theta[s2, cols])
        d_pair = np.where(valid, d_pair, self.d_max)
        q = pair_reconstructability(cos_alpha, d_pair, cos_t, self.d_max)
        return np.where(valid, q, 0.0).sum(axis=1)

    def active_slots(self, active_views: np.ndarray) -> np.ndarray:
        """Boolean (n_s, M): slot holds a view with ``active_views[view]`` True."""
        return (self.slot_view >= 0) & active_views[np.maximum(self.slot_view, 0)]

    def h(self, active_views: np.ndarray) -> np.ndarray:
        """h(s, U) (n_s,) for the views flagged in ``active_views`` (n_v,) bool."""
        act = self.active_slots(active_views)
        s, k = np.nonzero(act)
        if s.size == 0:
            return np.zeros(self.n_samples)
        contrib = self.q_sums(s, k, act[s])
        return 0.5 * np.bincount(s, weights=contrib, minlength=self.n_samples)
