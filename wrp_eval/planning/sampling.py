"""Poisson-disk samples of the proxy faces (paper Sec. 3.1, "Candidate view set generation").

The most complex face gets the radius at which two neighbouring views (one per sample, at the planned
distance, looking along the face normal) overlap by ``overlap`` (0.85 in the paper); the other faces'
radii scale inversely with their complexity: r_i = r_0 * c_max / c_i, capped at ``max_factor * r_0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from wrp_eval.camera import Camera
from wrp_eval.ship.proxy import Proxy

# A complexity this small (relative to the largest) counts as zero: the cap decides that face's radius.
_MIN_RELATIVE_COMPLEXITY = 1e-9


@dataclass(frozen=True)
class Samples:
    """Sample set S = {s_i, n_i}: points (n, 3) m on the proxy, outward normals (n, 3), face (n,) int."""

    points: np.ndarray
    normals: np.ndarray
    face: np.ndarray

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def counts_per_face(self, n_faces: int = 5) -> np.ndarray:
        return np.bincount(self.face, minlength=n_faces)


def base_radius_m(camera: Camera, distance_m: float, overlap: float) -> float:
    """Radius r_0 (m): the spacing at which neighbouring fronto-parallel views overlap by ``overlap``.

    The footprint's short side limits the overlap, so r_0 = (1 - overlap) * min(footprint width, height).
    """
    width, height = camera.footprint_m(distance_m)
    return float((1.0 - overlap) * min(width, height))


def face_radii_m(complexity: np.ndarray, base_radius: float, max_factor: float) -> np.ndarray:
    """Per-face Poisson-disk radii (5,) m: r_0 on the most complex face, r_0 c_max / c_i elsewhere (capped)."""
    c = np.asarray(complexity, dtype=float)
    if c.shape != (5,) or not np.all(np.isfinite(c)) or np.any(c < 0) or c.max() <= 0:
        raise ValueError(f"complexity must be 5 finite non-negative values, not all zero; got {c}")
    rel = np.maximum(c / c.max(), _MIN_RELATIVE_COMPLEXITY)
    return np.minimum(base_radius / rel, base_radius * max_factor)


def poisson_samples(proxy: Proxy, radii: np.ndarray, rng: np.random.Generator) -> Samples:
    """Fill every face with a Poisson-disk set of its radius (scipy's Bridson sampler on the face rectangle)."""
    points, normals, faces = [], [], []
    for face in range(len(proxy.face_names)):  # five faces: one sampler call each
        hu, hv = proxy.half_extents[face]
        radius = float(radii[face])
        if radius >= 2.0 * max(hu, hv):  # the whole face fits in one disk: its centre is the sample
            uv = np.zeros((1, 2))
        else:
            engine = qmc.PoissonDisk(2, radius=radius, l_bounds=[-hu, -hv], u_bounds=[hu, hv],
                                     ncandidates=20, rng=rng)
            uv = engine.fill_space()
        points.append(proxy.face_points(face, uv))
        normals.append(np.broadcast_to(proxy.normals[face], (len(uv), 3)))
        faces.append(np.full(len(uv), face, dtype=int))
    return Samples(np.concatenate(points), np.ascontiguousarray(np.concatenate(normals)),
                   np.concatenate(faces))
