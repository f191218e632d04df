"""Transition viewpoints between proxy faces (paper Def. 3.4-3.5, Alg. 2).

For every tour segment joining views of two different faces: sample the segment uniformly at the mean of
the two faces' Poisson-disk radii, push samples out of the no-fly zone / up to the minimum altitude, and
orient them to the proxy. The paper says "towards the centre of the geometric proxy"; for an elongated hull
the centroid is far outside the image of a view near the bow, so we aim at the nearest point of the
proxy's centre line (x axis at mid-height, clamped to the hull length) - the centre for a cubic proxy.
Where the two faces' images share too little (e.g. a segment climbing over a corner), views aimed at the
centre line can jump from one face to the other; so every sampled position also offers a second
orientation, aimed at the point between the two end views' look-at points (linear in the position along
the segment). The chain below picks whichever satisfies OSMC.

Alg. 2 as written keeps or adds candidates pairwise; we pick the chain A -> c_i -> ... -> B with every
consecutive pair inside the OSMC interval t_min <= overlap <= t_max (Eq. 4) and as few added views as
possible (a shortest path over the candidates in segment order). Samples count in Eq. 4 with the area
they stand for (r_face^2, see ``transition_views``). When no chain satisfies OSMC, the one with the fewest
violating pairs is kept and the violations are counted in the plan metrics.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.planning.views import make_safe
from wrp_eval.planning.visibility import ProxyRaycaster, overlap_matrix, visibility
from wrp_eval.ship.proxy import Proxy

_VIOLATION_PENALTY = 1000.0


def proxy_axis_targets(proxy: Proxy, positions: np.ndarray) -> np.ndarray:
    """Nearest points (n, 3) of the proxy's centre line to ``positions``."""
    targets = np.zeros_like(positions)
    targets[:, 0] = np.clip(positions[:, 0], -proxy.length_m / 2, proxy.length_m / 2)
    targets[:, 2] = proxy.height_m / 2
    return targets


@dataclass(frozen=True)
class TransitionResult:
    """For each segment i (between tour positions i and i+1): the positions (k_i, 3), yaw, pitch of
    the views inserted, their visibility rows; plus the number of OSMC violations left."""

    positions: list[np.ndarray]
    yaw: list[np.ndarray]
    pitch: list[np.ndarray]
    obs: list[np.ndarray]
    violations: int
    checked_pairs: int


def best_chain(overlap: np.ndarray, t_min: float, t_max: float) -> tuple[list[int], int]:
    """Fewest-node chain 0 -> n-1 through an ordered candidate list; (interior nodes, violating pairs)."""
    n = len(overlap)
    ok = (overlap >= t_min) & (overlap <= t_max)
    # The direct pair of surface views needs no transition view when it already matches; its upper bound
    # does not apply (t_max only keeps transition views from being redundant, Alg. 2 lines 12-13).
    ok[0, n - 1] = overlap[0, n - 1] >= t_min
    edge = np.where(ok, 1.0, 1.0 + _VIOLATION_PENALTY)
    best = np.full(n, np.inf)
    prev = np.full(n, -1)
    best[0] = 0.0
    for j in range(1, n):  # DAG in segment order: a few dozen nodes
        cand = best[:j] + edge[:j, j]
        prev[j] = int(np.argmin(cand))
        best[j] = cand[prev[j]]
    chain, j = [], n - 1
    violations = 0
    while j > 0:
        i = prev[j]
        violations += int(not ok[i, j])
        if i > 0:
            chain.append(int(i))
        j = i
    return chain[::-1], violations


def keep_clear(positions: np.ndarray, proxy: Proxy, clearance_m: float) -> np.ndarray:
    """Move points (n, 3) closer than ``clearance_m`` to the proxy cuboid away from its nearest point."""
    if clearance_m <= 0:
        return positions
    lo, hi = proxy.bounds
    nearest = np.clip(positions, lo, hi)
    away = positions - nearest
    dist = np.linalg.norm(away, axis=1)
    inside = dist < 1e-9
    # points inside the cuboid leave through the top (always flyable)
    away[inside] = np.array([0.0, 0.0, 1.0])
    nearest[inside, 2] = hi[2]
    dist = np.where(inside, 1.0, dist)
    unit = away / dist[:, None]
    close = inside | (np.linalg.norm(positions - nearest, axis=1) < clearance_m)
    out = positions.copy()
    out[close] = nearest[close] + clearance_m * unit[close]
    return out


_REFINEMENTS = (1.0, 0.5, 0.25)  # spacing factors tried in turn on segments that still violate OSMC


@dataclass(frozen=True)
class TransitionScene:
    """What transition views are placed and judged against: the proxy; the Poisson-disk samples (points,
    normals (n_s, 3), sample_faces (n_s,)) and the faces' radii (5,) m; the camera, the proxy raycaster, the
    view range d_max (m) and incidence limit (rad) of the visibility test; the lowest allowed height (m); the
    OSMC interval [t_min, t_max] of Eq. 4; clearance_m: how far from the proxy a transition view must be."""

    proxy: Proxy
    points: np.ndarray
    normals: np.ndarray
    sample_faces: np.ndarray
    radii: np.ndarray
    camera: Camera
    raycaster: ProxyRaycaster
    d_max: float
    max_incidence_rad: float
    min_altitude_m: float
    t_min: float
    t_max: float
    clearance_m: float


def transition_views(order_positions: np.ndarray, order_faces: np.ndarray, order_obs: np.ndarray,
                     order_targets: np.ndarray, scene: TransitionScene) -> TransitionResult:
    """Transition views for every face-changing segment of the ordered surface views (open sequence).

    order_positions (n, 3), order_faces (n,), order_obs (n, n_s) bool visibility rows and order_targets
    (n, 3) the points the surface views look at, all in flight order. Overlap (Eq. 4) counts every sample
    with weight r_face^2, the area it stands for: the faces are sampled at different radii, and a plain
    count would let the densely sampled face swamp the other (with equal radii this is Eq. 4 exactly).
    A segment whose best chain still violates OSMC is sampled again at half, then a quarter of the spacing
    (long segments of a poor tour need intermediate views closer together). Candidates nearer to the proxy
    than ``clearance_m`` move straight away from it to that distance (a view a few metres off the hull
    sees almost nothing to match)."""
    proxy, points, radii = scene.proxy, scene.points, scene.radii
    n = len(order_positions)
    seg = np.flatnonzero(order_faces[:-1] != order_faces[1:]) if n > 1 else np.zeros(0, dtype=int)
    empty = [np.zeros((0, 3)) for _ in range(max(n - 1, 0))]
    out_pos, out_yaw = list(empty), [np.zeros(0) for _ in empty]
    out_pitch, out_obs = list(out_yaw), [np.zeros((0, len(points)), dtype=bool) for _ in empty]
    sample_weights = radii[scene.sample_faces] ** 2
    bad_of: dict[int | np.integer[Any], int] = {}
    todo = seg
    for factor in _REFINEMENTS:
        if todo.size == 0:
            break
        a, b = order_positions[todo], order_positions[todo + 1]
        spacing = factor * 0.5 * (radii[order_faces[todo]] + radii[order_faces[todo + 1]])
        counts = np.maximum(np.ceil(np.linalg.norm(b - a, axis=1) / spacing).astype(int) - 1, 0)
        owner = np.repeat(np.arange(todo.size), counts)
        frac = (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + 1) / \
            np.repeat(counts + 1, counts)
        cand = a[owner] + frac[:, None] * (b[owner] - a[owner])
        cand = make_safe(keep_clear(cand, proxy, scene.clearance_m), proxy_axis_targets(proxy, cand), proxy,
                         scene.min_altitude_m)
        ta, tb = order_targets[todo][owner], order_targets[todo + 1][owner]
        # two orientations per position, interleaved (axis, look-at blend) so that segment order is kept
        cand = np.repeat(cand, 2, axis=0)
        targets = np.empty_like(cand)
        targets[0::2] = proxy_axis_targets(proxy, cand[0::2])
        targets[1::2] = ta + frac[:, None] * (tb - ta)
        counts = 2 * counts
        yaw, pitch = yaw_pitch_towards(cand, targets)
        obs = visibility(points, scene.normals, cand, yaw, pitch, scene.camera, scene.raycaster, scene.d_max,
                         scene.max_incidence_rad)
        starts = np.cumsum(counts) - counts
        for k, i in enumerate(todo):  # one small shortest-path problem per face change
            rows = slice(starts[k], starts[k] + counts[k])
            nodes_obs = np.concatenate([order_obs[i:i + 1], obs[rows], order_obs[i + 1:i + 2]])
            chain, bad = best_chain(overlap_matrix(nodes_obs, sample_weights), scene.t_min, scene.t_max)
            if i in bad_of and bad >= bad_of[i]:
                continue  # the coarser sampling was no worse
            pick = starts[k] + np.array(chain, dtype=int) - 1
            out_pos[i], out_yaw[i], out_pitch[i], out_obs[i] = cand[pick], yaw[pick], pitch[pick], obs[pick]
            bad_of[i] = bad
        todo = np.array([i for i in todo if bad_of[i] > 0], dtype=int)
    violations = int(sum(bad_of.values()))
    checked = int(sum(len(out_pos[i]) + 1 for i in seg))
    return TransitionResult(out_pos, out_yaw, out_pitch, out_obs, violations, checked)
