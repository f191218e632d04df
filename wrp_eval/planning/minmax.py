"""Min-Max view-set optimisation (Zhou et al. 2020, "Offsite aerial path planning", Sec. 5, as modified by
the paper Sec. 3.2: one reconstructability threshold per proxy face, scaled by that face's complexity).

Minimisation: starting from every candidate, remove views lowest-importance first, importance(v) =
max over the samples v sees of 1/h(s); a removal is rejected when it drops any sample below its threshold.
Because h only decreases as views go, importances only grow: a lazy heap (re-check the popped key) gives
the exact "lowest current importance first" order, and a rejected view never becomes removable later.
h is updated incrementally: removing v lowers h(s) by the sum of q(s, v, u) over the remaining u.

Maximisation (same count): for each kept view, worst-covered first, try every replacement candidate
generated from nearby samples of the same face (any tilt); accept the best swap that keeps every sample
above its threshold, does not lower H(S, U) and raises J = sum_s log(eps + h(s)) (a concave objective: gains
on the worst-covered samples count most).

Reported metrics (our definitions; the paper's Table 2 does not define them):
H(S, U) = mean over samples of h(s, U) (reconstructability of the set);
R(U) = mean over kept views of the fraction of the samples a view sees that would stay at or above their
threshold without it (view redundancy: 0 when every sample of every view depends on it).
"""

from __future__ import annotations

import heapq
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from wrp_eval.compiled import kernel
from wrp_eval.planning.reconstructability import SlotTable

_TOL = 1e-9
_LOG_EPS = 1e-3


@dataclass(frozen=True)
class MinResult:
    """active (n_v,) bool views kept; h (n_s,) after minimisation; threshold (n_s,) effective thresholds
    min(asked, h with every candidate) - a sample the candidates cannot lift to its threshold keeps all
    the reconstructability they give it."""

    active: np.ndarray
    h: np.ndarray
    threshold: np.ndarray


@kernel
def _largest_inverse(h: NDArray[np.float64], view_sample: NDArray[np.int64], start: int, stop: int) -> float:
    """max over ``view_sample[start:stop]`` of 1 / h (inf where h <= 0), 0 for an empty range: one compiled
    call instead of five numpy calls (the minimisation asks it ~30,000 times at 330 views)."""
    if stop <= start:
        return 0.0
    largest = -np.inf
    for i in range(start, stop):
        value = h[view_sample[i]]
        inverse = 1.0 / max(value, 1e-300) if value > 0 else np.inf
        if inverse > largest:
            largest = inverse
    return largest


def _importance(table: SlotTable, h: NDArray[np.float64], view: int | np.integer[Any]) -> float:
    """max over the samples ``view`` sees of 1 / h(s) (inf where h(s) is 0; 0 when it sees none)."""
    return float(_largest_inverse(h, table.view_sample, int(table.view_ptr[view]), int(table.view_ptr[view + 1])))


def minimise(table: SlotTable, initial: np.ndarray, thresholds: np.ndarray) -> MinResult:
    """Redundancy minimisation over the views flagged in ``initial`` (n_v,) with per-sample thresholds."""
    active = np.array(initial, dtype=bool, copy=True)
    act = table.active_slots(active)
    h = table.h(active)
    thr = np.minimum(np.asarray(thresholds, dtype=float), h)
    heap = [(_importance(table, h, v), v) for v in np.flatnonzero(active)]
    heapq.heapify(heap)
    while heap:
        key, v = heapq.heappop(heap)
        now = _importance(table, h, v)
        if now > key + _TOL and heap and now > heap[0][0]:
            heapq.heappush(heap, (now, v))  # its importance grew: not the least important any more
            continue
        samples, slots = table.entries(v)
        delta = table.q_sums(samples, slots, act[samples])
        if np.all(h[samples] - delta >= thr[samples] - _TOL):
            h[samples] -= delta
            act[samples, slots] = False
            active[v] = False
    return MinResult(active, np.maximum(h, 0.0), thr)


def removal_deltas(table: SlotTable, act: np.ndarray, view: int | np.integer[Any]) -> tuple[np.ndarray, np.ndarray]:
    """(samples, drop of h) when ``view`` leaves the set whose slots are ``act``."""
    samples, slots = table.entries(view)
    return samples, table.q_sums(samples, slots, act[samples])


def maximise(table: SlotTable, active: np.ndarray, thresholds: np.ndarray,
             replacements: Callable[[int], np.ndarray], rounds: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Reconstructability maximisation by replacement. ``replacements(view) -> candidate view indices``.

    Returns (active (n_v,) bool, h (n_s,), number of swaps). The number of active views never changes.
    """
    active = np.array(active, dtype=bool, copy=True)
    act = table.active_slots(active)
    h = table.h(active)
    thr = np.asarray(thresholds, dtype=float)
    slot_of = np.full(table.n_samples, -1, dtype=np.int64)
    swaps = 0
    for _ in range(rounds):
        kept = np.flatnonzero(active)
        worst = np.array([h[table.entries(v)[0]].min(initial=np.inf) for v in kept])
        changed = False
        for v in kept[np.argsort(worst, kind="stable")]:
            cands = np.asarray(replacements(v), dtype=np.int64)
            cands = cands[~active[cands]]
            if cands.size == 0:
                continue
            s_v, rem = removal_deltas(table, act, v)
            ptr = table.view_ptr
            lengths = ptr[cands + 1] - ptr[cands]
            flat = np.concatenate([np.arange(ptr[c], ptr[c + 1]) for c in cands]) if lengths.sum() else \
                np.zeros(0, dtype=np.int64)
            s_c, k_c = table.view_sample[flat], table.view_slot[flat]
            owner = np.repeat(np.arange(cands.size), lengths)
            # active slots without v, for the samples the candidates see
            slot_of[s_v] = table.entries(v)[1]
            a = act[s_c].copy()
            has_v = slot_of[s_c] >= 0
            a[np.flatnonzero(has_v), slot_of[s_c][has_v]] = False
            slot_of[s_v] = -1
            add = table.q_sums(s_c, k_c, a)
            local = np.unique(np.concatenate([s_v, s_c]))
            pos_v = np.searchsorted(local, s_v)
            base = h[local].copy()
            base[pos_v] -= rem
            h_new = np.broadcast_to(base, (cands.size, local.size)).copy()
            np.add.at(h_new, (owner, np.searchsorted(local, s_c)), add)
            feasible = np.all(h_new >= thr[local] - _TOL, axis=1) & \
                (h_new.sum(axis=1) >= h[local].sum() - _TOL)
            gain = np.log(_LOG_EPS + np.maximum(h_new, 0)).sum(axis=1) - np.log(_LOG_EPS + h[local]).sum()
            gain = np.where(feasible, gain, -np.inf)
            best = int(np.argmax(gain))
            if gain[best] <= 1e-9:
                continue
            c = int(cands[best])
            act[s_v, table.entries(v)[1]] = False
            s_new, k_new = table.entries(c)
            act[s_new, k_new] = True
            h[local] = h_new[best]
            active[v], active[c] = False, True
            swaps += 1
            changed = True
        if not changed:
            break
    return active, np.maximum(h, 0.0), swaps


def set_metrics(table: SlotTable, active: np.ndarray, thresholds: np.ndarray) -> tuple[float, float]:
    """(H(S, U), R(U)) as defined in the module docstring."""
    act = table.active_slots(active)
    h = table.h(active)
    fractions = []
    for v in np.flatnonzero(active):  # one vectorised row block per kept view (tens of views)
        samples, drop = removal_deltas(table, act, v)
        fractions.append(1.0 if samples.size == 0 else
                         float(np.mean(h[samples] - drop >= thresholds[samples] - _TOL)))
    return float(h.mean()) if h.size else 0.0, float(np.mean(fractions)) if fractions else 0.0
