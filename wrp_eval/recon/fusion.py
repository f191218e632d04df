"""The synthetic oracle's reconstruction: estimated poses, triangulated and fused points on the visible truth.

Given which views registered (:mod:`wrp_eval.recon.synthetic`, the SfM part), this module models what the
photogrammetric pipeline then makes of each ground-truth sample (a patch of ``1 / gt_density_per_m2`` m^2 of
visible surface). Working on the fixed ground-truth samples, not on each view's rays, is what makes the
oracle's response smooth: a small pose change moves every weight a little instead of re-drawing which surface
the rays happen to hit, and every random draw is attached to a sample or a view (common random numbers).

1. **Observations.** Sample s is observed by registered view v when it projects into v's image in front of it,
   within range, and an occlusion ray from the sample to the camera (one batched open3d call on ship + sea)
   is free. Weight w_sv in 0..1 = image border ramp x incidence ramp x the probability that dense matching
   finds texture on the patch (its area in the image, thinned by the view's keypoint fraction: blur, GSD
   against the surface texture) (:mod:`wrp_eval.recon.image_effects`); pixel noise sigma_v from the view's
   blur. Blur thus costs a view keypoints (registration, pose) and precision at once, but a sharp-enough
   patch still reconstructs: dense matching uses every pixel, not only keypoints.
2. **Matching and triangulation.** Every pair of observations of a sample matches with probability
   w_sv w_sv' m(alpha) and triangulates with w_sv w_sv' t(alpha) (parallax ramps). The sample is reconstructed
   with probability e_s = 1 - prod(1 - triangulating pair probabilities) (at least one pair triangulates); an
   observation is matched with probability m_sv = 1 - prod over its partners (1 - matching probabilities).
3. **Pose estimation** (bundle adjustment per view, in the linear approximation). View v's 2D-3D
   correspondences are the keypoints on the samples it matched that were reconstructed: N_sv = (keypoints per
   px^2) x (patch area in px^2: a_s cos(incidence) / GSD^2) x m_sv x e_s. Its 6 x 6 Fisher information is
   sum N_sv J^T J / sigma_v^2, J the 2 x 6 Jacobian of the projection with respect to a small rotation and a
   shift of the camera centre (so count, image spread, depth and pixel noise all enter), plus the position
   prior (the recorded GNSS position, sigma ``prior_position_sigma_m``) where configured. The estimate =
   the prior's pull (covariance x prior information x (recorded - true position)) + a seeded Gaussian draw
   with the posterior covariance.
   Only the directions the images leave open are pulled: the rotation / translation trade-off of a narrow
   field of view is weakly constrained, and errors along it barely move the rays at the observed points.
   The linearisation holds the true structure fixed while it estimates each pose (per-view resection), so it
   does not model how a bundle adjustment would bend the structure with the cameras.
4. **Points.** The fused estimate of sample s is the weighted least-squares intersection of the matched rays
   (each weighted m_sv f^2 / (d^2 sigma_v^2) across its ray): its covariance C_s = (sum of those
   information matrices)^-1 gives the depth noise along the surface normal, sigma_n^2 = n^T C_s n, plus a
   model floor ``noise_floor_gsd`` x GSD in quadrature; each view's pose error moves its ray and so the
   point by C_s sum(info_sv (dc_v + phi_v x (p_s - c_v))). One seeded normal draw per sample scales sigma_n.

Scoring (:func:`score_fused`): the samples more likely reconstructed than not (e_s >= 0.5; a fixed subset of
``ICP_POINTS``) are aligned to the truth as the paper aligns (ICP with scale,
:func:`wrp_eval.recon.oracle.align_to_ground_truth`); then each visible ground-truth
sample contributes e_s |n_s . (aligned estimate - truth)| (the accuracy part: the distance to the fused
surface) + (1 - e_s) h_s (the hole part: the distance to the nearest reconstructed patch, each reconstructed
sample standing for a disc of the area it represents in its tangent plane, a partly reconstructed neighbour j
counting as HOLE_PENALTY_M x (1 - e_j) farther away), and ``error_m`` is their mean: CloudCompare's
cloud-to-reconstruction distance of the visible truth, resolved at the ground-truth spacing (0.71 m at the
default 2 samples / m^2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from wrp_eval.compiled import kernel
from wrp_eval.open3d_arrays import o3d_tensor
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.image_effects import (
    INCIDENCE_RAMP_DEG,
    PARALLAX_MAX_RAMP_DEG,
    PARALLAX_MIN_RAMP_DEG,
    border_weight,
    incidence_weight,
    keypoint_fraction,
    patch_match_probability,
    pixel_noise_px,
)
from wrp_eval.recon.oracle import GroundTruth, Scores, align_to_ground_truth
from wrp_eval.sim.captures import CaptureSet

OCCLUSION_OFFSET_M = 0.01    # occlusion rays start this far off the surface (no self-hits on shared edges)
MAX_POINT_SIGMA_M = 10.0     # weak-information cap: a sample seen along one ray only has this depth sigma
NO_PRIOR_POSITION_M = 100.0  # without priors, a weak regulariser of each camera centre (keeps the solve finite)
NO_PRIOR_ROTATION_RAD = 1.0
HOLE_PENALTY_M = 1.0         # a neighbour reconstructed with probability e counts (1 - e) x this farther away
HOLE_NEIGHBOURS = 16
MIN_EXISTENCE = 0.01         # samples less likely reconstructed than this are not part of the reconstruction
MAX_VIEWS_PER_SAMPLE = 24    # real MVS bounds the views per point (e.g. Goesele et al. 2007: ~10 neighbours per
                             # reference view); keeps the pair count linear in the views (46-view path: <= 19)
ICP_POINTS = 5000            # the ICP's source points: a fixed subset of the samples (stable under small changes)


@dataclass(frozen=True)
class SampleObservations:
    """Registered views that see ground-truth samples: k observations flattened, sorted by sample.

    sample (k,) index into the ground truth; view (k,) index into the capture set; rel (k, 3) m, sample minus
    camera centre; dist (k,) m; cam (k, 3) m, the sample in the camera frame; weight (k,) 0..1; sigma_px (k,);
    patch_px2 (k,) the sample's patch area in the image x keypoint fraction (keypoints = density x this).
    """

    sample: np.ndarray
    view: np.ndarray
    rel: np.ndarray
    dist: np.ndarray
    cam: np.ndarray
    weight: np.ndarray
    sigma_px: np.ndarray
    patch_px2: np.ndarray
    gsd_m: np.ndarray


@kernel
def _in_view(samples: np.ndarray, normals: np.ndarray, centres: np.ndarray, rot: np.ndarray, focal_px: float,
             width_px: float, height_px: float, max_dist_m: float, cos_incidence_min: float) -> np.ndarray:
    """(S, V) bool: sample s lies in front of view v, inside its image, within ``max_dist_m`` and at a
    matchable incidence (cosine above ``cos_incidence_min``). samples, normals (S, 3); centres (V, 3); rot
    (V, 3, 3) world-from-camera. One pass over the pairs with no (S, V, 3) temporaries: at close range most
    pairs fail the first tests."""
    n_s, n_v = samples.shape[0], centres.shape[0]
    out = np.zeros((n_s, n_v), dtype=np.bool_)
    for s in range(n_s):
        for v in range(n_v):
            rx = samples[s, 0] - centres[v, 0]
            ry = samples[s, 1] - centres[v, 1]
            rz = samples[s, 2] - centres[v, 2]
            z = rx * rot[v, 0, 2] + ry * rot[v, 1, 2] + rz * rot[v, 2, 2]
            if z <= 1e-9:
                continue
            u = focal_px * (rx * rot[v, 0, 0] + ry * rot[v, 1, 0] + rz * rot[v, 2, 0]) / z + width_px / 2
            w = focal_px * (rx * rot[v, 0, 1] + ry * rot[v, 1, 1] + rz * rot[v, 2, 1]) / z + height_px / 2
            if u <= 0 or u >= width_px or w <= 0 or w >= height_px:
                continue
            dist = np.sqrt(rx * rx + ry * ry + rz * rz)
            cos_inc = abs(rx * normals[s, 0] + ry * normals[s, 1] + rz * normals[s, 2]) / max(dist, 1e-9)
            out[s, v] = dist <= max_dist_m and cos_inc > cos_incidence_min
    return out


@kernel
def _view_candidates(samples, normals, centres, rot, focal_px, width_px, height_px, max_dist_m, cos_incidence_min,
                     offset_m):
    """The pairs :func:`_in_view` keeps, sample-major, with what step 1 needs of them: sample index (k,),
    view index (k,) into ``centres``, rel = sample - centre (k, 3) m, its length (k,) m, the camera-frame point
    R^T rel (k, 3) m, the incidence cosine |n . rel| / |rel| (k,), the image point (u, v) (k, 2) px and the
    occlusion ray (k, 6) float32: from ``offset_m`` off the sample towards the camera (origin, unit direction)."""
    keep = _in_view(samples, normals, centres, rot, focal_px, width_px, height_px, max_dist_m, cos_incidence_min)
    count = int(keep.sum())
    s_idx = np.empty(count, dtype=np.int64)
    v_idx = np.empty(count, dtype=np.int64)
    rel = np.empty((count, 3))
    dist = np.empty(count)
    cam = np.empty((count, 3))
    cos_inc = np.empty(count)
    pixel = np.empty((count, 2))
    rays = np.empty((count, 6), dtype=np.float32)
    k = 0
    for s in range(samples.shape[0]):
        for v in range(centres.shape[0]):
            if not keep[s, v]:
                continue
            rx = samples[s, 0] - centres[v, 0]
            ry = samples[s, 1] - centres[v, 1]
            rz = samples[s, 2] - centres[v, 2]
            s_idx[k], v_idx[k] = s, v
            rel[k, 0], rel[k, 1], rel[k, 2] = rx, ry, rz
            dist[k] = np.sqrt(rx * rx + ry * ry + rz * rz)
            for c in range(3):
                cam[k, c] = rx * rot[v, 0, c] + ry * rot[v, 1, c] + rz * rot[v, 2, c]
            cos_inc[k] = abs(rx * normals[s, 0] + ry * normals[s, 1] + rz * normals[s, 2]) / max(dist[k], 1e-9)
            pixel[k, 0] = focal_px * cam[k, 0] / cam[k, 2] + width_px / 2
            pixel[k, 1] = focal_px * cam[k, 1] / cam[k, 2] + height_px / 2
            for c in range(3):
                toward = -rel[k, c] / dist[k]
                rays[k, c] = samples[s, c] + offset_m * toward
                rays[k, 3 + c] = toward
            k += 1
    return s_idx, v_idx, rel, dist, cam, cos_inc, pixel, rays


@kernel
def _best_per_sample(sample, usable, weight, max_views):
    """Indices (m,) of the ``max_views`` usable observations of highest weight of each sample, sample-major and
    by decreasing weight (ties in index order: np.lexsort((-weight, sample)) restricted to ``usable``).
    ``sample`` (k,) sorted."""
    k = sample.shape[0]
    out = np.empty(k, dtype=np.int64)
    m = 0
    start = 0
    while start < k:
        end = start + 1
        while end < k and sample[end] == sample[start]:
            end += 1
        first = m
        for i in range(start, end):         # stable insertion by decreasing weight
            if not usable[i]:
                continue
            j = m
            while j > first and weight[out[j - 1]] < weight[i]:
                out[j] = out[j - 1]
                j -= 1
            out[j] = i
            m += 1
        m = min(m, first + max_views)
        start = end
    return out[:m]


def observe_samples(capture_set: CaptureSet, gt: GroundTruth, registered: np.ndarray, section: OracleSection,
                    sample_area_m2: float,
                    max_views_per_sample: int | None = MAX_VIEWS_PER_SAMPLE) -> SampleObservations:
    """The observations of step 1 (module docstring) of every ground-truth sample by the registered views: the
    ``max_views_per_sample`` best of each sample (None: every free one, sample-major, for callers that weigh views
    apart rather than reconstruct from them)."""
    p = section.synthetic
    cam_model = capture_set.camera
    f = cam_model.focal_px
    views = np.flatnonzero(registered)
    centres = np.asarray(capture_set.positions, dtype=float)[views]
    rot = np.ascontiguousarray(capture_set.rotations()[views])
    inc_max = np.radians(p.incidence_max_deg)
    s_idx, v_idx, rel_k, dist_k, cam_k, cos_k, pixel, rays = _view_candidates(
        gt.samples, gt.sample_normals, centres, rot, f, float(cam_model.image_width_px),
        float(cam_model.image_height_px), float(cam_model.distance_for_gsd(p.max_gsd_m)),
        float(np.cos(inc_max + np.radians(INCIDENCE_RAMP_DEG))), OCCLUSION_OFFSET_M)          # sample-major
    # occlusion: is the segment from the sample (just off the surface) to the camera free?
    t_hit = gt.occluder_scene.cast_rays(o3d_tensor(rays))["t_hit"].numpy()
    free = t_hit >= dist_k - 2 * OCCLUSION_OFFSET_M
    view = views[v_idx]
    blur = capture_set.blur()[view]
    gsd = np.asarray(cam_model.gsd_m(dist_k))
    keep_frac = keypoint_fraction(blur, gsd, p.texture_m)
    patch_px2 = sample_area_m2 * cos_k / gsd ** 2 * keep_frac
    weight = (border_weight(pixel[:, 0], pixel[:, 1], cam_model.image_width_px, cam_model.image_height_px)
              * incidence_weight(cos_k, inc_max) * patch_match_probability(patch_px2))
    # the best MAX_VIEWS_PER_SAMPLE free observations of each sample (by weight; still sorted by sample)
    keep = (np.flatnonzero(free) if max_views_per_sample is None
            else _best_per_sample(s_idx, free, weight, max_views_per_sample))
    return SampleObservations(s_idx[keep], view[keep], rel_k[keep], dist_k[keep], cam_k[keep], weight[keep],
                              pixel_noise_px(p.sigma_px, blur[keep]), patch_px2[keep], gsd[keep])


@kernel
def _cos_end(angle, beyond):
    """The cosine of a ramp's end ``angle`` rad; ``beyond`` (a cosine outside [-1, 1], never reached) for an end
    outside [0, pi], where alpha in [0, pi] is always on one side of it: the ramp's formula decides there."""
    return np.cos(angle) if 0.0 < angle < np.pi else beyond


@kernel
def _parallax_row(cos_alpha, min_lo, min_hi, max_lo, max_hi, cos_min_lo, cos_min_hi, cos_max_lo, cos_max_hi):
    """(matchable, triangulates) of one pair from the cosine of its parallax angle: image_effects.parallax_weights,
    with the arccos taken only inside a ramp (outside a ramp its value is 0 or 1: the cosine decides)."""
    alpha = -1.0
    if cos_alpha >= cos_max_lo:
        matchable = 1.0
    elif cos_alpha <= cos_max_hi:
        return 0.0, 0.0
    else:
        alpha = np.arccos(min(max(cos_alpha, -1.0), 1.0))
        matchable = 1.0 - min(max((alpha - max_lo) / (max_hi - max_lo), 0.0), 1.0)
    if cos_alpha >= cos_min_lo:
        return matchable, 0.0
    if cos_alpha <= cos_min_hi:
        return matchable, matchable
    if alpha < 0.0:
        alpha = np.arccos(min(max(cos_alpha, -1.0), 1.0))
    return matchable, matchable * min(max((alpha - min_lo) / (min_hi - min_lo), 0.0), 1.0)


@kernel
def _pair_evidence(sample, rel, dist, weight, parallax_min, parallax_max, min_ramp, max_ramp, n_samples):
    """Steps 2-3 over every unordered pair (a, b), a < b, of observations of the same sample (``sample`` sorted,
    (k,)): alpha = the angle between their rays, matchable m = 1 - ramp(alpha; parallax_max -+ max_ramp),
    triangulates t = m ramp(alpha; parallax_min -+ min_ramp) (image_effects.parallax_weights), both = w_a w_b.
    Returns (S,) sum of log(1 - both t) per sample and (k,) sum of log(1 - both m) per observation over the pairs
    it is in (1 - exp of either: the probability that at least one pair triangulates / matches, the pairs taken
    as independent). Sums run in pair order (a, then b), every pair's matching term first at its a, then at its
    b; zero terms are skipped (adding 0 changes no sum). A NaN weight or ray counts as no evidence (a zero term;
    the numpy formulas this replaced carried it into the sums): the weights are clipped ramps of finite
    quantities and the rays have a length, so none arises from a capture set."""
    k = sample.shape[0]
    max_lo, max_hi = parallax_max - max_ramp, parallax_max + max_ramp      # the ramps' ends as ramp() has them
    min_lo, min_hi = parallax_min - min_ramp, parallax_min + min_ramp
    cosines = (_cos_end(min_lo, 2.0), _cos_end(min_hi, -2.0), _cos_end(max_lo, 2.0), _cos_end(max_hi, -2.0))
    cap = 1.0 - 1e-12
    log_untriangulated = np.zeros(n_samples)
    log_unmatched = np.zeros(k)
    terms = np.zeros(0)
    start = 0
    while start < k:
        end = start + 1
        while end < k and sample[end] == sample[start]:
            end += 1
        n = end - start
        if terms.shape[0] < n * (n - 1) // 2:
            terms = np.zeros(n * (n - 1) // 2)
        j = 0
        for a in range(start, end):
            for b in range(a + 1, end):
                both = weight[a] * weight[b]
                terms[j] = 0.0
                if both > 0.0:
                    dot = rel[a, 0] * rel[b, 0] + rel[a, 1] * rel[b, 1] + rel[a, 2] * rel[b, 2]
                    m, t = _parallax_row(dot / (dist[a] * dist[b]), min_lo, min_hi, max_lo, max_hi, *cosines)
                    if m > 0.0:
                        terms[j] = np.log1p(-min(both * m, cap))
                        log_unmatched[a] += terms[j]
                    if t > 0.0:
                        log_untriangulated[sample[a]] += np.log1p(-min(both * t, cap))
                j += 1
        j = 0
        for a in range(start, end):
            for b in range(a + 1, end):
                if terms[j] != 0.0:
                    log_unmatched[b] += terms[j]
                j += 1
        start = end
    return log_untriangulated, log_unmatched


@kernel
def _pose_information(view, cam, rel, rotations, weight, focal_px, n_views):
    """(n_views, 6, 6): sum over observations k of ``weight[k]`` J_k^T J_k by ``view[k]``, J_k (2, 6) the
    Jacobian of the projection of the camera-frame point ``cam[k]`` = R^T rel[k] (R = rotations[view[k]],
    world-from-camera; rel = point - centre) with respect to a small world-frame rotation phi and a shift of
    the camera centre: dX/dphi = R^T [rel]x, dX/dc = -R^T."""
    info = np.zeros((n_views, 6, 6))
    jac = np.empty((2, 6))
    for k in range(view.shape[0]):
        v = view[k]
        x, y, z = cam[k, 0], cam[k, 1], cam[k, 2]
        a = focal_px / z
        qx, qy, qz = rel[k, 0], rel[k, 1], rel[k, 2]
        for r in range(2):
            d0, d1, d2 = (a, 0.0, -a * x / z) if r == 0 else (0.0, a, -a * y / z)
            # row r of d_proj R^T: entry c = d . R[c, :]
            p0 = d0 * rotations[v, 0, 0] + d1 * rotations[v, 0, 1] + d2 * rotations[v, 0, 2]
            p1 = d0 * rotations[v, 1, 0] + d1 * rotations[v, 1, 1] + d2 * rotations[v, 1, 2]
            p2 = d0 * rotations[v, 2, 0] + d1 * rotations[v, 2, 1] + d2 * rotations[v, 2, 2]
            jac[r, 0] = p1 * qz - p2 * qy          # (p^T [q]x)
            jac[r, 1] = p2 * qx - p0 * qz
            jac[r, 2] = p0 * qy - p1 * qx
            jac[r, 3], jac[r, 4], jac[r, 5] = -p0, -p1, -p2
        w = weight[k]
        for i in range(6):
            for j in range(i, 6):
                info[v, i, j] += w * (jac[0, i] * jac[0, j] + jac[1, i] * jac[1, j])
    for v in range(n_views):
        for i in range(6):
            for j in range(i):
                info[v, i, j] = info[v, j, i]
    return info


@kernel
def _fused_points(sample, view, rel, dist, coef, dc, phi, normals, prior_info):
    """Step 4 per sample s: the information C_s^-1 = sum coef_k (I - r_k r_k^T) + prior_info I over its
    observations k (r_k = rel_k / dist_k, the unit ray), the point shift C_s sum coef_k (I - r_k r_k^T) shift_k
    (shift_k = dc[view_k] + phi[view_k] x rel_k: the view's pose error moving its ray at the sample) and the
    variance along the normal n_s^T C_s n_s. Returns (S, 3) m and (S,) m^2; S = len(normals)."""
    n_samples = normals.shape[0]
    info = np.zeros((n_samples, 6))       # symmetric 3 x 3: xx, yy, zz, xy, xz, yz
    moved = np.zeros((n_samples, 3))
    for k in range(sample.shape[0]):
        s, v, c = sample[k], view[k], coef[k]
        qx, qy, qz = rel[k, 0], rel[k, 1], rel[k, 2]
        rx, ry, rz = qx / dist[k], qy / dist[k], qz / dist[k]
        info[s, 0] += c * (1.0 - rx * rx)
        info[s, 1] += c * (1.0 - ry * ry)
        info[s, 2] += c * (1.0 - rz * rz)
        info[s, 3] -= c * rx * ry
        info[s, 4] -= c * rx * rz
        info[s, 5] -= c * ry * rz
        sx = dc[v, 0] + phi[v, 1] * qz - phi[v, 2] * qy
        sy = dc[v, 1] + phi[v, 2] * qx - phi[v, 0] * qz
        sz = dc[v, 2] + phi[v, 0] * qy - phi[v, 1] * qx
        along = rx * sx + ry * sy + rz * sz
        moved[s, 0] += c * (sx - rx * along)
        moved[s, 1] += c * (sy - ry * along)
        moved[s, 2] += c * (sz - rz * along)
    shift = np.empty((n_samples, 3))
    sigma2 = np.empty(n_samples)
    for s in range(n_samples):
        a, b, d = info[s, 0] + prior_info, info[s, 1] + prior_info, info[s, 2] + prior_info
        e, f, g = info[s, 3], info[s, 4], info[s, 5]           # [[a, e, f], [e, b, g], [f, g, d]]
        c00, c11, c22 = b * d - g * g, a * d - f * f, a * b - e * e   # cofactors (the matrix is symmetric)
        c01, c02, c12 = f * g - e * d, e * g - f * b, e * f - a * g
        det = a * c00 + e * c01 + f * c02
        m = moved[s]
        shift[s, 0] = (c00 * m[0] + c01 * m[1] + c02 * m[2]) / det
        shift[s, 1] = (c01 * m[0] + c11 * m[1] + c12 * m[2]) / det
        shift[s, 2] = (c02 * m[0] + c12 * m[1] + c22 * m[2]) / det
        nx, ny, nz = normals[s, 0], normals[s, 1], normals[s, 2]
        sigma2[s] = (c00 * nx * nx + c11 * ny * ny + c22 * nz * nz
                     + 2.0 * (c01 * nx * ny + c02 * nx * nz + c12 * ny * nz)) / det
    return shift, sigma2


def pose_errors(obs: SampleObservations, matched: np.ndarray, existence: np.ndarray, capture_set: CaptureSet,
                section: OracleSection, rng_views: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 3: each view's estimated-pose error. Returns rotation errors phi (n, 3) rad (world frame: the
    estimated camera is exp([phi]x) R), centre errors dc (n, 3) m and their standard deviations (n, 2): the
    RMS rotation (rad) and position (m) sigma per axis. ``rng_views`` (n, 6): the views' standard normals."""
    p = section.synthetic
    n = len(capture_set)
    f = capture_set.camera.focal_px
    keypoints = p.keypoints_per_mpx * 1e-6 * obs.patch_px2 * matched * existence[obs.sample]
    info = _pose_information(obs.view, obs.cam, obs.rel, capture_set.rotations(), keypoints / obs.sigma_px ** 2,
                             float(f), n)
    true_c = np.asarray(capture_set.positions, dtype=float)
    pull = np.zeros((n, 6))
    if p.prior_position_sigma_m is None:
        prior = np.r_[np.full(3, NO_PRIOR_ROTATION_RAD ** -2), np.full(3, NO_PRIOR_POSITION_M ** -2)]
    else:
        prior = np.r_[np.full(3, NO_PRIOR_ROTATION_RAD ** -2), np.full(3, p.prior_position_sigma_m ** -2)]
        pull[:, 3:] = (capture_set.position_priors() - true_c) * p.prior_position_sigma_m ** -2
    info = info + np.diag(prior)[None]
    cov = np.linalg.inv(info)
    cov = 0.5 * (cov + np.transpose(cov, (0, 2, 1)))
    mean = np.einsum("nij,nj->ni", cov, pull)
    # scale by the diagonal before the Cholesky factor: rotations (~1e-6 rad) and positions (~1e-3 m) differ
    scale = np.sqrt(np.einsum("nii->ni", cov))
    corr = cov / (scale[:, :, None] * scale[:, None, :]) + 1e-12 * np.eye(6)
    draw = mean + scale * np.einsum("nij,nj->ni", np.linalg.cholesky(corr), rng_views)
    sigmas = np.stack([np.sqrt((scale[:, :3] ** 2).mean(1)), np.sqrt((scale[:, 3:] ** 2).mean(1))], 1)
    return draw[:, :3], draw[:, 3:], sigmas


@dataclass(frozen=True)
class FusedReconstruction:
    """The reconstructed visible truth. estimates (S, 3) m: each ground-truth sample's fused estimate (its
    truth where not reconstructed); existence (S,) 0..1: the probability it is reconstructed; sigma_n (S,) m:
    its depth noise along the normal; pose_sigma (n, 2): per view the rotation (rad) and position (m) sigma;
    camera_position_error (n, 3) m and camera_rotation_error (n, 3) rad (world-frame rotation vector): each
    view's estimated pose minus its true pose (0 for views not registered); observations: how many (sample,
    registered view) observations it was made from."""

    estimates: np.ndarray
    existence: np.ndarray
    sigma_n: np.ndarray
    pose_sigma: np.ndarray
    camera_position_error: np.ndarray
    camera_rotation_error: np.ndarray
    observations: int = 0

    def __len__(self) -> int:
        return int(round(float(self.existence.sum())))

    def score(self, gt: GroundTruth, section: OracleSection, seed: int = 0) -> Scores:
        return score_fused(self, gt, section, seed)


def fuse(capture_set: CaptureSet, gt: GroundTruth, registered: np.ndarray, section: OracleSection,
         seed: int = 0) -> FusedReconstruction:
    """Steps 1-4 of the module docstring on the registered views of ``capture_set``. Seeded: one standard
    normal per ground-truth sample, then six per viewpoint of the plan (``capture_set.view_ids()``; common random
    numbers: a pose change, a missing view or the tour flown in another order leaves every other draw where it
    was)."""
    p = section.synthetic
    n_samples = len(gt.samples)
    rng = np.random.default_rng(seed)
    z_samples = rng.standard_normal(n_samples)
    planned = capture_set.view_ids()
    z_views = rng.standard_normal((int(planned.max(initial=-1)) + 1, 6))[planned]
    # each sample stands for the patch 1 / density of the surface it was drawn on
    obs = observe_samples(capture_set, gt, registered, section, 1.0 / section.gt_density_per_m2)
    f = capture_set.camera.focal_px
    log_untriangulated, log_unmatched = _pair_evidence(
        obs.sample, obs.rel, obs.dist, obs.weight, np.radians(p.parallax_min_deg), np.radians(p.parallax_max_deg),
        np.radians(PARALLAX_MIN_RAMP_DEG), np.radians(PARALLAX_MAX_RAMP_DEG), n_samples)
    existence = 1.0 - np.exp(log_untriangulated)
    matched = 1.0 - np.exp(log_unmatched)
    phi, dc, pose_sigma = pose_errors(obs, matched, existence, capture_set, section, z_views)

    # step 4: weighted least-squares intersection of the matched rays
    coef = matched * (f / (obs.dist * obs.sigma_px)) ** 2
    normals = gt.sample_normals
    point_shift, sigma_geo2 = _fused_points(obs.sample, obs.view, obs.rel, obs.dist, coef, dc, phi, normals,
                                            MAX_POINT_SIGMA_M ** -2)
    weight_sum = np.bincount(obs.sample, weights=matched, minlength=n_samples)
    gsd = np.bincount(obs.sample, weights=matched * obs.gsd_m, minlength=n_samples) / np.maximum(weight_sum, 1e-12)
    sigma_n = np.sqrt(sigma_geo2 + (p.noise_floor_gsd * gsd) ** 2)
    estimates = gt.samples + point_shift + (sigma_n * z_samples)[:, None] * normals
    estimates = np.where((existence > 0)[:, None], estimates, gt.samples)
    # a registered view that observes no sample has only its prior: no estimated pose to speak of
    posed = (np.asarray(registered, dtype=bool) & (np.bincount(obs.view, minlength=len(capture_set)) > 0))
    pose_sigma = np.where(posed[:, None], pose_sigma, np.nan)
    return FusedReconstruction(estimates, existence, np.where(existence > 0, sigma_n, np.nan), pose_sigma,
                               np.where(posed[:, None], dc, 0.0), np.where(posed[:, None], phi, 0.0),
                               int(len(obs.sample)))


def score_fused(recon: FusedReconstruction, gt: GroundTruth, section: OracleSection, seed: int = 0) -> Scores:
    """ICP with scale on the reconstructed samples, then error_m = accuracy part + hole part (module
    docstring), accuracy_m / precision over the reconstruction weighted by existence, completeness at tau."""
    e = recon.existence
    present = np.flatnonzero(e > MIN_EXISTENCE)
    if len(present) == 0:
        return Scores(float("nan"), float("nan"), 0.0, 0.0, 0.0, 1.0)
    core = np.flatnonzero(e >= 0.5) if np.count_nonzero(e >= 0.5) >= 3 else present
    # a subset chosen by a fixed key per sample (not a draw over however many there are): one sample more or
    # less changes the subset by one sample, so the alignment moves smoothly with the capture set
    keys = np.random.default_rng(seed).random(len(e))
    core = core[np.argsort(keys[core], kind="stable")[:ICP_POINTS]]
    transform = align_to_ground_truth(recon.estimates[np.sort(core)], gt, section.icp_max_correspondence_m,
                                      section.icp_max_iterations, max_source_points=ICP_POINTS, seed=seed)
    aligned = recon.estimates @ transform[:3, :3].T + transform[:3, 3]
    scale = float(np.cbrt(np.linalg.det(transform[:3, :3])))
    along = np.abs(np.einsum("sj,sj->s", aligned - gt.samples, gt.sample_normals))
    hole = np.zeros(len(e))
    missing = np.flatnonzero(e < 1.0)   # a certainly reconstructed sample has no hole term
    if len(missing):
        cloud = aligned[present]
        tree = cKDTree(cloud, balanced_tree=False, compact_nodes=False)
        k = min(HOLE_NEIGHBOURS, len(present))
        dist, idx = tree.query(gt.samples[missing], k=k)
        dist, idx = dist.reshape(len(missing), k), idx.reshape(len(missing), k)
        # point-to-disc distance to each neighbour's patch (radius sqrt(a / pi), in its tangent plane), as
        # base.surfel_distances measures a point cloud's surfels
        radius = np.sqrt(1.0 / (np.pi * section.gt_density_per_m2))
        rel = gt.samples[missing][:, None, :] - cloud[idx]
        dn = np.einsum("skj,skj->sk", rel, gt.sample_normals[present][idx])
        dt = np.sqrt(np.maximum(dist * dist - dn * dn, 0.0))
        cost = np.sqrt(dn * dn + np.maximum(dt - radius, 0.0) ** 2) + HOLE_PENALTY_M * (1.0 - e[present][idx])
        cost[present[idx] == missing[:, None]] = np.inf  # a sample's own estimate is its accuracy part
        nearest = cost.min(axis=1)
        hole[missing] = np.where(np.isfinite(nearest), nearest, dist.max(axis=1) + HOLE_PENALTY_M)
    accuracy_part = float(np.mean(e * along))
    hole_part = float(np.mean((1.0 - e) * hole))
    tau = section.tau_m
    completeness = float(np.mean(e * (along <= tau) + (1.0 - e) * (hole <= tau)))
    to_mesh = gt.ship_scene.compute_distance(
        o3d_tensor(aligned[present].astype(np.float32))).numpy().astype(np.float64)
    w = e[present]
    precision = float(np.sum(w * (to_mesh <= tau)) / np.sum(w))
    fscore = 0.0 if completeness + precision == 0 else 2 * completeness * precision / (completeness + precision)
    return Scores(accuracy_part + hole_part, float(np.sum(w * to_mesh) / np.sum(w)), completeness, precision,
                  fscore, scale, hole_part, accuracy_part)
