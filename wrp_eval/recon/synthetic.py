"""Synthetic multi-view-stereo oracle: a campaign-speed stand-in for ContextCapture + CloudCompare.

For one capture set on the true ship mesh:

1. **Observe.** Every view casts a ``rays_x x rays_y`` grid of rays through its image (pixel centres of the
   grid cells), all views in one batched open3d ``RaycastingScene.cast_rays`` call against the ship plus a
   sea plane at z = 0 (the sea occludes the hull below it). A hit counts when it is on the ship, nearer than
   the range at which a pixel covers ``max_gsd_m`` (Smith et al. 2018 d_max) and seen at an incidence below
   ``incidence_max_deg`` (Smith et al. 2018 keep views within 85 deg of the normal; photo-consistency
   degrades with foreshortening, Furukawa & Hernandez 2015, "Multi-View Stereo: A Tutorial").
2. **Co-visibility.** Hits are hashed into surface cells (``cell_m``); the view x cell incidence matrix
   gives the cells each pair of views sees in common; each view keeps its ``max_partners`` best partners
   (bounded source views, as real MVS), and a hit's candidates are those of them that saw its cell.
3. **Match.** A hit p of view i is seen by a candidate view j when it projects inside j's image, in front
   of it, and j's own ray at that image cell hits the same surface (within a slope-scaled distance of p and
   on p's tangent plane: a shadow-map test, so occlusion comes from j's ray cast, not from extra rays).
   The pair is *matchable* when the change of viewing direction (parallax) alpha <= ``parallax_max_deg``
   (60 deg: SIFT matching breaks down beyond ~50-60 deg of viewpoint change, Lowe 2004; Morel & Yu 2009
   "ASIFT") and both incidences are within range; it *triangulates* when also alpha >=
   ``parallax_min_deg`` (5 deg: where Smith et al. 2018's w1, k1 = 32, alpha1 = pi/16, is ~0, i.e. the
   smallest angle that contributes any reconstructability). Between 45 and 60 deg (past Smith's w3
   midpoint pi/4) points still reconstruct, with the noise of step 5.
4. **Register.** ``registration: incremental`` (default) models an incremental SfM mapper (Schoenberger &
   Frahm 2016; COLMAP, which validates this oracle): a seed pair (most triangulating rays), then one view at
   a time with the most rays matching points already triangulated by two registered views (2D-3D
   correspondences), while that count reaches ``min_registration_rays``; see :func:`register_incremental`.
   ``registration: components`` links views i, j when their overlap (Hepp et al. 2018: shared observations
   over the mean of both views' observations, counted in matchable rays) reaches ``min_overlap`` and they
   share at least ``min_matched_rays`` matchable rays on average, and keeps the largest connected component
   (``scipy.sparse.csgraph.connected_components``). Fewer than 3 views, or fewer than half the views,
   registered = failed (ContextCapture / COLMAP leave unregistered images out; the paper's "Failed").
5. **Reconstruct and score** (:mod:`wrp_eval.recon.fusion`): on the fixed ground-truth samples, the registered
   views' observations (soft border, incidence, parallax; blur, GSD and texture from
   :mod:`wrp_eval.recon.image_effects`), each view's estimated pose (uncertainty from its correspondences, pulled
   towards its recorded position prior), the fused least-squares point per sample with the pose and pixel
   errors it inherits; ICP with scale as the paper aligns; error_m = accuracy part + hole part.
   Registration (step 4) counts a ray as the share of a keypoint its view keeps (blur).

Every random draw comes from ``numpy.random.default_rng(seed)``: same inputs and seed, same result.

Poses: what is seen is decided by the true camera poses, roll included (:meth:`CaptureSet.rotations`); what
is reconstructed carries each view's *estimated* pose (fusion.py), which a bundle adjustment with position
priors pulls towards the recorded (GNSS) positions (``CaptureSet.prior_positions``) where the images
constrain it weakly. The score is taken after a similarity ICP to the ground truth (the paper's alignment),
which removes the common part of any georeferencing offset.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree

from wrp_eval.camera import Camera, optical_axes, world_rays
from wrp_eval.compiled import contiguous, kernel
from wrp_eval.open3d_arrays import o3d_tensor
from wrp_eval.recon.config import OracleSection, SyntheticOracleSection
from wrp_eval.recon.fusion import FusedReconstruction, fuse
from wrp_eval.recon.image_effects import blur_keypoint_fraction
from wrp_eval.recon.oracle import GroundTruth, MeshOracle
from wrp_eval.sim.captures import CaptureSet

REGISTRATION_CALIBRATION_WIDTH_PX = 800  # the COLMAP renders min_registration_rays was calibrated on (README)


@dataclass(frozen=True)
class Observations:
    """Ray hits on the ship, flattened over views (h hits).

    view (h,) view index; ray (h,) ray index in the view's grid; points (h, 3) m; normals (h, 3) unit,
    turned to face the camera; dirs (h, 3) unit ray directions; dist (h,) m camera-to-hit;
    hit_map (n, r, 3) hit point per view and ray (NaN where none); normal_map (n, r, 3) likewise.
    """

    view: np.ndarray
    ray: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    dirs: np.ndarray
    dist: np.ndarray
    hit_map: np.ndarray
    normal_map: np.ndarray


def ray_grid(camera: Camera, rays_x: int, rays_y: int) -> tuple[np.ndarray, float]:
    """Camera-frame unit directions (r, 3) through the centres of a rays_x x rays_y grid (row-major),
    and the pixel spacing (px) between neighbouring rays."""
    u = (np.arange(rays_x) + 0.5) * camera.image_width_px / rays_x
    v = (np.arange(rays_y) + 0.5) * camera.image_height_px / rays_y
    uu, vv = np.meshgrid(u, v)
    f = camera.focal_px
    d = np.stack([(uu.ravel() - camera.image_width_px / 2) / f, (vv.ravel() - camera.image_height_px / 2) / f,
                  np.ones(uu.size)], axis=1)
    return d / np.linalg.norm(d, axis=1, keepdims=True), camera.image_width_px / rays_x


def observe(capture_set: CaptureSet, gt: GroundTruth, rays_x: int, rays_y: int, max_range_m: float,
            incidence_max: float) -> Observations:
    """Cast every view's ray grid in one batched call; keep usable hits on the ship."""
    n = len(capture_set)
    cam_dirs, _ = ray_grid(capture_set.camera, rays_x, rays_y)
    r = len(cam_dirs)
    rot = capture_set.rotations()  # roll included: a rolled view's ray grid turns about its optical axis
    dirs = world_rays(rot, cam_dirs)
    origins = np.broadcast_to(np.asarray(capture_set.positions, dtype=float)[:, None, :], (n, r, 3))
    rays = np.concatenate([origins, dirs], axis=2).astype(np.float32).reshape(-1, 6)
    ans = gt.occluder_scene.cast_rays(o3d_tensor(rays))
    # float32 from here on (what open3d casts in): metres to ~1e-5 at ship scale, far below the noise
    t_hit = ans["t_hit"].numpy()
    gid = ans["geometry_ids"].numpy()
    nrm = ans["primitive_normals"].numpy()
    flat_dirs = rays[:, 3:]
    flat_origins = rays[:, :3]
    cos_inc = -np.einsum("kj,kj->k", flat_dirs, nrm)
    # meshes with mixed triangle winding: the visible side is the one facing the camera
    nrm = nrm * np.where(cos_inc < 0, np.float32(-1), np.float32(1))[:, None]
    cos_inc = np.abs(cos_inc)
    good = (gid == gt.ship_geometry_id) & (t_hit <= max_range_m) & (cos_inc >= np.cos(incidence_max))
    idx = np.flatnonzero(good)
    points = flat_dirs[idx] * t_hit[idx, None] + flat_origins[idx]
    hit_map = np.full((n * r, 3), np.nan, dtype=np.float32)
    hit_map[idx] = points
    normal_map = np.full((n * r, 3), np.nan, dtype=np.float32)
    normal_map[idx] = nrm[idx]
    return Observations(idx // r, idx % r, points, nrm[idx], flat_dirs[idx], t_hit[idx],
                        hit_map.reshape(n, r, 3), normal_map.reshape(n, r, 3))


def candidate_pairs(obs: Observations, n_views: int, cell_m: float, max_partners: int,
                    axes: np.ndarray | None = None,
                    max_axis_angle: float = np.pi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate (hit, other view) pairs: among each view's ``max_partners`` best partner views (most
    surface cells seen in common) plus the maximum spanning tree of co-visibility, those that saw the
    hit's surface cell.

    Real MVS bounds the source images per reference image the same way (view selection, e.g. Goesele et
    al. 2007; Schoenberger et al. 2016), which keeps the cost linear in the number of views.
    ``axes`` (n, 3): optical axes; pairs whose axes differ by more than ``max_axis_angle`` are dropped (the
    rays to a common point differ from the axes by at most the half field of view each).
    Returns hit index (k,) sorted ascending, partner view (k,), and the shared-cell counts (n, n).
    """
    cells = np.floor(obs.points / cell_m).astype(np.int64)
    cells -= cells.min(axis=0)
    extent = cells.max(axis=0) + 1
    keys = (cells[:, 0] * extent[1] + cells[:, 1]) * extent[2] + cells[:, 2]
    _, cell_id = np.unique(keys, return_inverse=True)
    cell_id = cell_id.ravel()
    n_cells = int(cell_id.max()) + 1
    seen = np.zeros((n_views, n_cells), dtype=bool)  # view x cell incidence
    seen[obs.view, cell_id] = True
    incidence = sp.csr_matrix(seen, dtype=np.int32)
    shared = (incidence @ incidence.T).toarray()  # co-visibility: common cells per view pair
    np.fill_diagonal(shared, 0)
    if axes is not None:  # views looking in too different directions cannot match: not candidates
        shared = np.where(axes @ axes.T >= np.cos(max_axis_angle), shared, 0)
    k = min(max_partners, n_views - 1)
    order = np.argsort(-shared, axis=1, kind="stable")[:, :k]  # best partners first, ties by index
    allowed = np.zeros((n_views, n_views), dtype=bool)
    np.put_along_axis(allowed, order, True, axis=1)
    # plus the maximum spanning tree of co-visibility: the cap never cuts a chain of views that see
    # common surface (e.g. a ring whose best partners all lie on one side)
    weights = np.where(shared > 0, shared.max() + 1 - shared, 0)
    tree = minimum_spanning_tree(sp.csr_matrix(weights)).toarray() > 0
    allowed |= tree | tree.T
    allowed &= shared > 0
    partner_lists = sp.csr_matrix(allowed)  # row v: the candidate partners of view v (sorted)
    counts = np.diff(partner_lists.indptr)[obs.view]
    hit = np.repeat(np.arange(len(cell_id)), counts)
    offsets = np.arange(len(hit)) - np.repeat(np.cumsum(counts) - counts, counts)
    partner = partner_lists.indices[np.repeat(partner_lists.indptr[obs.view], counts) + offsets]
    ok = seen[partner, cell_id[hit]]
    return hit[ok], partner[ok], shared


def register_components(n_views: int, pair_view: np.ndarray, partner: np.ndarray, matchable: np.ndarray,
                        hits_per_view: np.ndarray, min_overlap: float,
                        min_matched_rays: int) -> tuple[np.ndarray, int]:
    """Registration as the largest connected component of the view-link graph.

    Views i, j are linked when their overlap (Hepp et al. 2018, Plan3D: |obs(i) & obs(j)| / mean(|obs(i)|,
    |obs(j)|), here counted in matchable rays of each view landing on surface the other sees) reaches
    ``min_overlap`` and they share >= ``min_matched_rays`` matchable rays on average.
    pair_view, partner, matchable (k,): view of the hit, other view, and matchability of each candidate
    pair; hits_per_view (n,). Returns the registered mask (n,) and the number of view groups.
    """
    n = n_views
    counts = np.bincount(pair_view[matchable] * n + partner[matchable], minlength=n * n).reshape(n, n)
    common = counts + counts.T
    with np.errstate(invalid="ignore", divide="ignore"):
        overlap = common / (hits_per_view[:, None] + hits_per_view[None, :])
    links = sp.csr_matrix((overlap >= min_overlap) & (common >= 2 * min_matched_rays))
    n_comp, labels = connected_components(links, directed=False)
    sizes = np.bincount(labels, minlength=n_comp)
    best_comp = int(np.argmax(sizes))  # ties -> the component with the lowest view index
    return labels == best_comp, int(n_comp)


def register_incremental(n_views: int, n_hits: int, hit_view: np.ndarray, hit: np.ndarray, partner: np.ndarray,
                         matchable: np.ndarray, triangulates: np.ndarray, grid_index: np.ndarray,
                         rays_per_view: int, min_rays: int, hit_ray: np.ndarray | None = None,
                         ray_weight: np.ndarray | None = None) -> tuple[np.ndarray, list[int]]:
    """Registration as an incremental SfM mapper does it (Schoenberger & Frahm 2016, "Structure-from-Motion
    Revisited", Sec. 4.2-4.3; COLMAP's IncrementalMapper).

    * **Seed:** the view pair with the most triangulating matchable rays (both directions counted), if that
      count reaches ``min_rays``.
    * **Points:** a hit (a ray sample = a feature of its view) is *triangulated* once its own view and a
      partner that triangulates it (parallax >= parallax_min) are both registered.
    * **Next view:** a view's 2D-3D correspondences are its rays (distinct image cells) that match a
      triangulated hit of another view (the pair is matchable and the shadow-map test put the hit on that
      ray). The unregistered view with the most of them is registered (absolute pose) when it has
      >= ``min_rays``; its pairs then triangulate new points. Stop when no view qualifies.

    Bookkeeping is incremental: per-hit "triangulated" and per-ray "has a 2D-3D correspondence" flags are
    updated only from the pairs of the newly registered view, so the whole run touches each pair O(1)
    times (one compiled pass per registration step, `_register_view`). Ties go to the lowest view index,
    so the result is deterministic.

    hit_view (h,) view of every hit; hit, partner, matchable, triangulates, grid_index (k,): candidate pairs
    sorted by hit, with the partner's flat ray index (partner * rays_per_view + ray) at the hit's image cell.
    ray_weight (n * rays_per_view,): the expected share of a keypoint behind each ray (blur;
    :mod:`wrp_eval.recon.image_effects`) with hit_ray (h,) each hit's own flat ray index: counts become sums
    of these weights (a seed pair's ray the smaller of its two: a feature coarse enough to survive the
    stronger blur survives both); None = every ray counts 1.
    Returns the registered mask (n,) and the registration order.
    """
    mi = np.flatnonzero(matchable)
    if len(mi) == 0:
        return np.zeros(n_views, dtype=bool), []
    if ray_weight is None:
        ray_weight = np.ones(n_views * rays_per_view)
        hit_ray = np.zeros(n_hits, dtype=np.int64)  # with unit weights any ray index gives weight 1
    elif hit_ray is None:
        raise ValueError("ray_weight needs hit_ray, each hit's own flat ray index")
    h, p, g, t = hit[mi], partner[mi], grid_index[mi], triangulates[mi]
    v_of = hit_view[h]
    seed = _seed_pair(n_views, p, t, v_of, np.minimum(ray_weight[hit_ray[h]], ray_weight[g]), min_rays)
    if seed is None:
        return np.zeros(n_views, dtype=bool), []
    # CSR views of the matchable pairs: by hit (sorted already), by the hit's view (sorted with the hits), by
    # partner (one stable sort; on 16-bit keys numpy's stable sort is a linear radix sort)
    by_partner = np.argsort(p.astype(np.int16) if n_views < 2**15 else p, kind="stable")
    registered, order = _register_loop(
        h, p, g, t, v_of, np.searchsorted(h, np.arange(n_hits + 1)), np.searchsorted(v_of, np.arange(n_views + 1)),
        by_partner, np.searchsorted(p[by_partner], np.arange(n_views + 1)), np.asarray(ray_weight, dtype=float),
        rays_per_view, seed[0], seed[1], float(min_rays))
    return registered, [int(v) for v in order]


def _seed_pair(n: int, p: np.ndarray, t: np.ndarray, v_of: np.ndarray, pair_weight: np.ndarray,
               min_rays: float) -> tuple[int, int] | None:
    """The view pair with the most triangulating rays over both directions (ties: lowest (i, j)), or None below
    ``min_rays``; over the matchable pairs (m,): p partner view, t triangulates, v_of the hit's view, pair_weight a
    pair's ray weighing the smaller of its two rays' weights."""
    tri = np.bincount(v_of[t] * n + p[t], weights=pair_weight[t], minlength=n * n).reshape(n, n)
    tri = np.triu(tri + tri.T, k=1)
    a, b = divmod(int(np.argmax(tri)), n)
    return None if tri[a, b] < min_rays or a == b else (a, b)        # a == b: no pair triangulates anything


@kernel
def _distinct(idx, stamp):
    """idx without repeats, each kept at its last occurrence, in order; ``stamp`` scratch as long as the ids."""
    for i in range(idx.shape[0]):
        stamp[idx[i]] = i
    keep = np.zeros(idx.shape[0], dtype=np.bool_)
    for i in range(idx.shape[0]):
        keep[i] = stamp[idx[i]] == i
    return idx[keep]


@kernel
def _register_view(v, h, p, g, t, v_of, hit_ptr, view_ptr, by_partner, partner_ptr, ray_weight, rays_per_view,
                   registered, tri_hit, corr_ray, corr_count, stamp_hit, stamp_ray):
    """Register view ``v`` (:func:`register_incremental`): its pairs with registered views triangulate new hits,
    whose matching rays in every view become 2D-3D correspondences (the state arrays are updated in place)."""
    registered[v] = True
    a, b = partner_ptr[v], partner_ptr[v + 1]
    new = np.empty(view_ptr[v + 1] - view_ptr[v] + b - a, dtype=np.int64)
    m = 0
    for i in range(view_ptr[v], view_ptr[v + 1]):            # v's hits x their registered partners
        if t[i] and registered[p[i]] and not tri_hit[h[i]]:
            new[m] = h[i]
            m += 1
    for j in by_partner[a:b]:                                # others' registered hits x partner v
        if t[j] and registered[v_of[j]] and not tri_hit[h[j]]:
            new[m] = h[j]
            m += 1
    new = _distinct(new[:m], stamp_hit)
    if new.shape[0] == 0:
        return
    total = 0
    for x in new:
        tri_hit[x] = True
        total += hit_ptr[x + 1] - hit_ptr[x]
    rays = np.empty(total, dtype=np.int64)                  # every view's ray that matches a newly triangulated hit
    m = 0
    for x in new:
        for k in range(hit_ptr[x], hit_ptr[x + 1]):
            if not corr_ray[g[k]]:
                rays[m] = g[k]
                m += 1
    rays = _distinct(rays[:m], stamp_ray)
    added = np.zeros(corr_count.shape[0])
    for r in rays:
        corr_ray[r] = True
        added[r // rays_per_view] += ray_weight[r]
    corr_count += added


@kernel
def _register_loop(h, p, g, t, v_of, hit_ptr, view_ptr, by_partner, partner_ptr, ray_weight, rays_per_view,
                   seed_a, seed_b, min_rays):
    """The mapper of :func:`register_incremental` from its seed pair on: register the unregistered view with the
    most correspondences (ties: lowest index) while that count reaches ``min_rays``. Returns the registered mask
    (n,) and the registration order."""
    n = view_ptr.shape[0] - 1
    n_hits = hit_ptr.shape[0] - 1
    registered = np.zeros(n, dtype=np.bool_)
    tri_hit = np.zeros(n_hits, dtype=np.bool_)                   # triangulated by two registered views
    corr_ray = np.zeros(n * rays_per_view, dtype=np.bool_)      # a view's ray matches a triangulated hit
    corr_count = np.zeros(n)
    stamp_hit = np.zeros(n_hits, dtype=np.int64)                # scratch for duplicate removal without sorting
    stamp_ray = np.zeros(n * rays_per_view, dtype=np.int64)
    order = np.empty(n, dtype=np.int64)
    count = 0
    v = seed_a
    while True:
        _register_view(v, h, p, g, t, v_of, hit_ptr, view_ptr, by_partner, partner_ptr, ray_weight, rays_per_view,
                       registered, tri_hit, corr_ray, corr_count, stamp_hit, stamp_ray)
        order[count] = v
        count += 1
        if count == 1:
            v = seed_b
            continue
        best, best_count = -1, -1.0
        for c in range(n):
            if not registered[c] and corr_count[c] > best_count:
                best, best_count = c, corr_count[c]
        if best < 0 or best_count < min_rays:
            break
        v = best
    return registered, order[:count]


DROPPED, CANDIDATE, MATCHABLE, TRIANGULATES = 0, 1, 2, 3   # _match_pairs' status codes, in increasing order


@kernel
def _match_pairs(points, normals, dirs, hit, partner, positions, rotations, hit_map, normal_map, focal_px,
                 width_px, height_px, rays_x, rays_y, px_spacing, max_range_m, cos_incidence_max,
                 cos_parallax_max, parallax_min_rad):
    """Step 3 for every candidate pair k (hit ``hit[k]`` of its view, other view ``partner[k]``): status (k,)
    int8 (DROPPED: out of j's range, incidence or parallax; CANDIDATE; MATCHABLE; TRIANGULATES) and the index
    (k,) of j's ray at the hit's image cell in the flattened (n x rays) maps (-1 where dropped).

    points, normals, dirs (h, 3): the hits; positions (n, 3) m and rotations (n, 3, 3) world-from-camera of
    the views; hit_map, normal_map (n * rays, 3): each view's ray hits (NaN where none). The shadow-map test:
    j's ray at p's image cell landed on p's surface patch (on its plane, within a slope-scaled distance)."""
    k_pairs = hit.shape[0]
    status = np.zeros(k_pairs, dtype=np.int8)
    grid = np.full(k_pairs, -1, dtype=np.int64)
    rays_per_view = rays_x * rays_y
    for k in range(k_pairs):
        h, j = hit[k], partner[k]
        rx = points[h, 0] - positions[j, 0]
        ry = points[h, 1] - positions[j, 1]
        rz = points[h, 2] - positions[j, 2]
        dist = np.sqrt(rx * rx + ry * ry + rz * rz)
        cos_j = abs(normals[h, 0] * rx + normals[h, 1] * ry + normals[h, 2] * rz) / max(dist, 1e-9)
        # parallax: angle at p between the two viewing rays (cos = (-d_i) . (-rel / |rel|))
        cos_alpha = (dirs[h, 0] * rx + dirs[h, 1] * ry + dirs[h, 2] * rz) / max(dist, 1e-9)
        if not (dist <= max_range_m and cos_j >= cos_incidence_max and cos_alpha >= cos_parallax_max):
            continue
        status[k] = CANDIDATE
        cx = rotations[j, 0, 0] * rx + rotations[j, 1, 0] * ry + rotations[j, 2, 0] * rz
        cy = rotations[j, 0, 1] * rx + rotations[j, 1, 1] * ry + rotations[j, 2, 1] * rz
        z = rotations[j, 0, 2] * rx + rotations[j, 1, 2] * ry + rotations[j, 2, 2] * rz
        zs = z if z > 1e-9 else 1e-9
        u = focal_px * cx / zs + width_px / 2
        v = focal_px * cy / zs + height_px / 2
        iu = min(max(int(u * rays_x / width_px), 0), rays_x - 1)
        iv = min(max(int(v * rays_y / height_px), 0), rays_y - 1)
        g = j * rays_per_view + iv * rays_x + iu
        grid[k] = g
        if not (z > 1e-9 and 0 <= u < width_px and 0 <= v < height_px):
            continue
        dx = points[h, 0] - hit_map[g, 0]
        dy = points[h, 1] - hit_map[g, 1]
        dz = points[h, 2] - hit_map[g, 2]
        spacing_j = dist * px_spacing / focal_px
        same_plane = abs(dx * normal_map[g, 0] + dy * normal_map[g, 1] + dz * normal_map[g, 2]) \
            <= 0.5 * spacing_j + 1e-3
        reach = 2.0 * spacing_j / max(cos_j, cos_incidence_max)
        if same_plane and dx * dx + dy * dy + dz * dz <= reach * reach:       # False where j's ray hit nothing
            alpha = np.arccos(min(max(cos_alpha, -1.0), 1.0))
            status[k] = TRIANGULATES if alpha >= parallax_min_rad else MATCHABLE
    return status, grid


@dataclass(frozen=True)
class MatchedPairs:
    """The candidate (hit, other view) pairs that pass step 3's range, incidence and parallax tests (k pairs):
    hit (k,) index into the observations, partner (k,) view, grid_index (k,) the partner's ray at the hit's
    image cell (flattened n x rays), matchable and triangulates (k,) bool."""

    hit: np.ndarray
    partner: np.ndarray
    grid_index: np.ndarray
    matchable: np.ndarray
    triangulates: np.ndarray


def match_pairs(obs: Observations, hit: np.ndarray, partner: np.ndarray, capture_set: CaptureSet,
                p: SyntheticOracleSection, max_range_m: float, incidence_max: float,
                px_spacing: float) -> MatchedPairs:
    """Step 3 on the candidate pairs (:func:`candidate_pairs`) in one compiled pass (:func:`_match_pairs`)."""
    cam = capture_set.camera
    status, grid_index = _match_pairs(
        obs.points, obs.normals, obs.dirs, hit, partner, contiguous(capture_set.positions),
        capture_set.rotations(),  # roll included: decides what lands in j's image
        obs.hit_map.reshape(-1, 3), obs.normal_map.reshape(-1, 3), cam.focal_px, float(cam.image_width_px),
        float(cam.image_height_px), p.rays_x, p.rays_y, px_spacing, float(max_range_m), float(np.cos(incidence_max)),
        float(np.cos(np.radians(p.parallax_max_deg))), float(np.radians(p.parallax_min_deg)))
    keep = np.flatnonzero(status > 0)
    status = status[keep]
    return MatchedPairs(hit[keep], partner[keep], grid_index[keep], status >= MATCHABLE, status == TRIANGULATES)


def register_views(obs: Observations, pairs: MatchedPairs, capture_set: CaptureSet,
                   p: SyntheticOracleSection) -> tuple[np.ndarray, str, dict]:
    """Step 4, which views join the reconstruction: (registered (n,) bool, what stopped it, diagnostics)."""
    n = len(capture_set)
    if p.registration == "components":
        registered, n_comp = register_components(n, obs.view[pairs.hit], pairs.partner, pairs.matchable,
                                                 np.bincount(obs.view, minlength=n), p.min_overlap,
                                                 p.min_matched_rays)
        return registered, f"{n_comp} disconnected view groups, largest kept", {"view_groups": int(n_comp)}
    # a blurred view has fewer keypoints behind its rays (image_effects.py); min_registration_rays is calibrated
    # against COLMAP on REGISTRATION_CALIBRATION_WIDTH_PX renders, so the blur is taken at that width (where the
    # texture law never binds: the GSD is coarse there)
    rays_per_view = p.rays_x * p.rays_y
    hit_weight = blur_keypoint_fraction(capture_set.blur()[obs.view] * REGISTRATION_CALIBRATION_WIDTH_PX
                                        / capture_set.camera.image_width_px)
    ray_weight = np.zeros(n * rays_per_view)
    hit_ray = obs.view * rays_per_view + obs.ray
    ray_weight[hit_ray] = hit_weight
    registered, order = register_incremental(n, len(obs.points), obs.view, pairs.hit, pairs.partner,
                                             pairs.matchable, pairs.triangulates, pairs.grid_index, rays_per_view,
                                             p.min_registration_rays, hit_ray, ray_weight)
    detail = f"incremental registration stopped: no other view sees >= {p.min_registration_rays} triangulated points"
    return registered, detail, {"registration_order": [int(v) for v in order]}


class SyntheticOracle(MeshOracle):
    """The default oracle. ``evaluate(capture_set, ship_mesh, seed)`` -> :class:`ReconResult`."""

    name = "synthetic"

    def __init__(self, section: OracleSection = OracleSection()):
        super().__init__(section)

    def reconstruct(self, capture_set: CaptureSet, gt: GroundTruth,
                    seed: int = 0) -> tuple[FusedReconstruction, np.ndarray | int, str, dict]:
        """The fused reconstruction from the registered views, which views registered ((n,) bool; 0 when none
        could), failure reason ("" if none) and diagnostics."""
        p = self.section.synthetic
        cam = capture_set.camera
        n = len(capture_set)
        empty = FusedReconstruction(gt.samples, np.zeros(len(gt.samples)), np.full(len(gt.samples), np.nan),
                                    np.zeros((n, 2)), np.zeros((n, 3)), np.zeros((n, 3)))
        if n == 0:
            return empty, 0, "no views captured", {}
        f = cam.focal_px
        max_range = cam.distance_for_gsd(p.max_gsd_m)
        inc_max = np.radians(p.incidence_max_deg)
        obs = observe(capture_set, gt, p.rays_x, p.rays_y, max_range, inc_max)
        _, px_spacing = ray_grid(cam, p.rays_x, p.rays_y)
        if len(obs.points) == 0:
            return empty, 0, "no view sees the ship", {"hits": 0}
        # Cells must be larger than the spacing of neighbouring rays on the surface, or a view's sparse
        # rays would miss cells it sees.
        spacing = obs.dist * px_spacing / f
        cell_m = max(p.cell_m, 1.5 * float(np.percentile(spacing, 95)))
        # roll turns a view about its optical axis: the axis, and the angle between it and any of the view's
        # rays, do not depend on it, so this pruning bound holds for rolled views too
        axes = optical_axes(capture_set.yaw, capture_set.pitch)
        hit, partner, _ = candidate_pairs(obs, n, cell_m, p.max_partners, axes,
                                          np.radians(p.parallax_max_deg) + max(cam.half_fov_x, cam.half_fov_y))

        pairs = match_pairs(obs, hit, partner, capture_set, p, max_range, inc_max, float(px_spacing))
        registered_mask, detail, reg_extra = register_views(obs, pairs, capture_set, p)
        n_registered = int(registered_mask.sum())
        reason = ""
        if n_registered < 3:
            reason = f"only {n_registered} view(s) registered (fewer than 3)"
        elif 2 * n_registered < n:
            reason = f"only {n_registered} of {n} views registered ({detail})"

        # --- reconstruct (fusion.py): estimated poses, triangulated and fused points on the visible truth ---
        fused = fuse(capture_set, gt, registered_mask, self.section, seed)
        registered_sigma = fused.pose_sigma[registered_mask & np.isfinite(fused.pose_sigma[:, 0])]
        extra = {"hits": int(len(obs.points)), "candidate_pairs": int(len(pairs.hit)), **reg_extra, "cell_m": cell_m,
                 "median_sigma_n_m": float(np.nanmedian(fused.sigma_n)) if np.any(fused.existence > 0) else None,
                 "mean_existence": float(fused.existence.mean()), "observations": fused.observations,
                 "median_pose_sigma_deg": float(np.degrees(np.median(registered_sigma[:, 0])))
                 if len(registered_sigma) else None,
                 "median_pose_sigma_m": float(np.median(registered_sigma[:, 1])) if len(registered_sigma) else None}
        return fused, registered_mask, reason, extra
