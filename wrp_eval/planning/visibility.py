"""Which samples each view sees (paper Sec. 3.2; Smith et al. 2018 visibility conditions).

A view sees a sample when the sample projects inside the image, lies within ``d_max``, the angle theta
between the ray (sample -> view) and the sample normal is at most ``max_incidence`` (85 deg), and the ray
is not occluded by the proxy. The cheap tests run in one compiled pass over the view x sample pairs
(float32); the survivors go to open3d's Embree ray caster in ONE batched ``cast_rays`` call.
"""

from __future__ import annotations

import numpy as np
import open3d as o3d

from wrp_eval.camera import Camera, camera_rotations
from wrp_eval.compiled import kernel
from wrp_eval.open3d_arrays import o3d_tensor
from wrp_eval.ship.proxy import Proxy


class ProxyRaycaster:
    """The proxy's triangles in an Embree scene (built once per proxy)."""

    def __init__(self, proxy: Proxy):
        vertices, faces = proxy.triangles()
        self.scene = o3d.t.geometry.RaycastingScene()
        self.scene.add_triangles(o3d_tensor(vertices.astype(np.float32)),
                                 o3d_tensor(faces.astype(np.uint32)))

    def first_hit(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Distance (n,) to the first proxy hit along unit ``directions`` (inf when none)."""
        rays = np.concatenate([origins, directions], axis=1).astype(np.float32)
        return self.scene.cast_rays(o3d_tensor(rays))["t_hit"].numpy().astype(float)


@kernel
def _cheap_tests(pts: np.ndarray, nrm: np.ndarray, pos: np.ndarray, rot: np.ndarray, f: np.float32,
                 half_w: np.float32, half_h: np.float32, d_max: np.float32, cos_max: np.float32) -> np.ndarray:
    """(n_views, n_samples) bool: in the image, within ``d_max``, incidence within the limit (float32, as the
    ray caster). One pass over the pairs, no (views, samples, 3) temporaries."""
    n_views, n_samples = pos.shape[0], pts.shape[0]
    passed = np.zeros((n_views, n_samples), dtype=np.bool_)
    for c in range(n_views):
        for m in range(n_samples):
            r0 = pts[m, 0] - pos[c, 0]
            r1 = pts[m, 1] - pos[c, 1]
            r2 = pts[m, 2] - pos[c, 2]
            depth = rot[c, 0, 2] * r0 + rot[c, 1, 2] * r1 + rot[c, 2, 2] * r2
            if depth <= 0:
                continue
            x = rot[c, 0, 0] * r0 + rot[c, 1, 0] * r1 + rot[c, 2, 0] * r2
            y = rot[c, 0, 1] * r0 + rot[c, 1, 1] * r1 + rot[c, 2, 1] * r2
            if abs(x) * f > half_w * depth or abs(y) * f > half_h * depth:
                continue
            dist = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
            cos_theta = -(r0 * nrm[m, 0] + r1 * nrm[m, 1] + r2 * nrm[m, 2]) / max(dist, np.float32(1e-9))
            passed[c, m] = dist <= d_max and cos_theta >= cos_max
    return passed


def visibility(points: np.ndarray, normals: np.ndarray, positions: np.ndarray, yaw: np.ndarray,
               pitch: np.ndarray, camera: Camera, raycaster: ProxyRaycaster, d_max: float,
               max_incidence_rad: float) -> np.ndarray:
    """Boolean (n_views, n_samples): view i sees sample j under all four conditions."""
    passed = _cheap_tests(points.astype(np.float32), normals.astype(np.float32), positions.astype(np.float32),
                          camera_rotations(yaw, pitch).astype(np.float32), np.float32(camera.focal_px),
                          np.float32(camera.image_width_px / 2.0), np.float32(camera.image_height_px / 2.0),
                          np.float32(d_max), np.float32(np.cos(max_incidence_rad)))
    vi, si = np.nonzero(passed)
    if vi.size:
        rel = points[si] - positions[vi]
        dist = np.linalg.norm(rel, axis=1)
        t_hit = raycaster.first_hit(positions[vi], rel / dist[:, None])
        # The sample lies on the proxy: the ray must reach it before hitting anything else.
        occluded = t_hit < dist - (1e-3 + 1e-4 * dist)
        passed[vi[occluded], si[occluded]] = False
    return passed


def overlap_ratio(obs_a: np.ndarray, obs_b: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Sparse-matching overlap (Hepp et al. 2018; paper Eq. 4) of paired boolean rows (n, m) -> (n,).

    |obs(a) & obs(b)| / ((|obs(a)| + |obs(b)|) / 2); 0 when both see nothing. With ``weights`` (m,) each
    sample counts with its weight (the surface area it stands for) instead of 1.
    """
    w = np.ones(obs_a.shape[-1]) if weights is None else np.asarray(weights, dtype=float)
    inter = (obs_a & obs_b) @ w
    mean = 0.5 * (obs_a @ w + obs_b @ w)
    return np.where(mean > 0, inter / np.where(mean > 0, mean, 1.0), 0.0)


def overlap_matrix(obs: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """All-pairs overlap (n, n) of boolean rows (n, m) (Eq. 4, optionally weighted), by one matrix product."""
    w = np.ones(obs.shape[-1]) if weights is None else np.asarray(weights, dtype=float)
    o = obs.astype(float)
    inter = (o * w) @ o.T
    counts = o @ w
    mean = 0.5 * (counts[:, None] + counts[None, :])
    return np.where(mean > 0, inter / np.where(mean > 0, mean, 1.0), 0.0)
