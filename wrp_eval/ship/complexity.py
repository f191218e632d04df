"""Model surface complexity per proxy face (paper Sec. 3.1, Definitions 3.1-3.3, eq. 1-3, Alg. 1).

Each mesh triangle is assigned to the proxy face (bottom excluded) whose outward normal is closest in angle
(eq. 1); it is counted for that face when the angle is <= 45 deg (eq. 2); the complexity of face i is
c_i = count_i / s_pi (eq. 3), the count divided by the face area. Alg. 1 line 10 as printed divides inside
the loop (M_c[k] <- (M_c[k] + 1) / S_k), which would not give eq. (3); we implement eq. (3).
Eq. (2) says "<= 45 deg" and Alg. 1 line 9 "< 45 deg"; we use eq. (2). Zero-area triangles have no normal
and are not counted. A triangle exactly between two faces goes to the first in ``FACE_NAMES`` order
(bow, stern, port, starboard, top). ``mesh_surface_complexity`` counts only triangles above the waterline
(centroid z > 0): the proxy, and every photograph, is above the sea; the submerged hull would otherwise
inflate the side faces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.ship.proxy import Proxy

MAX_ANGLE_DEG = 45.0


@dataclass(frozen=True)
class SurfaceComplexity:
    """Per proxy face, in ``Proxy.face_names`` order: counts (5,) triangles, areas (5,) m^2,
    complexity (5,) triangles per m^2 (eq. 3)."""

    face_names: tuple[str, ...]
    counts: np.ndarray
    areas: np.ndarray
    complexity: np.ndarray

    def as_dict(self) -> dict:
        return {name: {"triangles": int(n), "area_m2": float(a), "complexity_per_m2": float(c)}
                for name, n, a, c in zip(self.face_names, self.counts, self.areas, self.complexity, strict=True)}


def assign_triangles(normals: np.ndarray, proxy: Proxy, max_angle_deg: float = MAX_ANGLE_DEG) -> np.ndarray:
    """Face index (n,) of each triangle normal (n, 3) (closest proxy face by angle), -1 when not counted."""
    normals = np.asarray(normals, dtype=float)
    length = np.linalg.norm(normals, axis=1)
    valid = length > 1e-12
    unit = np.where(valid[:, None], normals / np.where(valid, length, 1.0)[:, None], 0.0)
    cosines = unit @ proxy.normals.T                          # (n, 5): cos of eq. (1)'s angle
    closest = np.argmax(cosines, axis=1)                      # smallest angle
    best = cosines[np.arange(len(unit)), closest]
    counted = valid & (best >= np.cos(np.radians(max_angle_deg)) - 1e-12)   # eq. (2), theta <= 45 deg
    return np.where(counted, closest, -1)


def surface_complexity(face_normals: np.ndarray, proxy: Proxy,
                       max_angle_deg: float = MAX_ANGLE_DEG) -> SurfaceComplexity:
    """Eq. (3) for the triangles with normals ``face_normals`` (n, 3) (e.g. ``trimesh.Trimesh.face_normals``)."""
    assigned = assign_triangles(face_normals, proxy, max_angle_deg)
    counts = np.bincount(assigned[assigned >= 0], minlength=len(proxy.face_names))
    areas = proxy.areas
    return SurfaceComplexity(tuple(proxy.face_names), counts, areas, counts / areas)


def mesh_surface_complexity(mesh, proxy: Proxy, waterline_z: float = 0.0,
                            max_angle_deg: float = MAX_ANGLE_DEG) -> SurfaceComplexity:
    """Eq. (3) for the triangles of a trimesh whose centroid is above ``waterline_z``."""
    above = np.asarray(mesh.triangles_center)[:, 2] > waterline_z
    return surface_complexity(np.asarray(mesh.face_normals)[above], proxy, max_angle_deg)
