"""What every reconstruction oracle shares: the result type, the interface, the ground truth and the scoring.

Scoring follows the paper (Sec. 4.1): the reconstruction is aligned to the ground truth by ICP allowing a
scale change (CloudCompare there, open3d here), then the mean distance between the two is the
reconstruction error. We measure it from the *visible* ground truth (surface above the waterline, keel and
enclosed faces excluded) to the reconstruction, so that missing surface counts, as the paper's remark on the
never-reconstructed bottom implies; accuracy (reconstruction -> ground truth), completeness, precision and
F-score at tau follow the Tanks-and-Temples convention (Knapitsch et al. 2017).

The reconstruction is a set of surfels: points with a normal and a radius (the footprint of the image sample
that produced it). Distances to it are point-to-disc distances, so that the score does not depend on how
densely the image was sampled, only on what was reconstructed and how noisily.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import open3d as o3d
import trimesh
from scipy.spatial import cKDTree

from wrp_eval.errors import InputError
from wrp_eval.open3d_arrays import o3d_tensor
from wrp_eval.sim.captures import CaptureSet

SEA_HALF_EXTENT_M = 1.0e5  # the sea plane occluder spans +-100 km around the origin
_ENCLOSURE_DIRECTIONS = 48  # rays per ground-truth sample for the "can anything outside see it" test


@dataclass(frozen=True)
class ReconResult:
    """The verdict of an oracle on one capture set.

    error_m: mean distance (m) from the visible ground-truth surface samples to the aligned reconstruction
    (NaN when nothing was reconstructed); accuracy_m: mean distance (m) from the aligned reconstruction to the
    ground-truth mesh; completeness, precision, fscore: fractions in [0, 1] at ``tau_m``;
    registered_views / total_views: views in the reconstruction; failed with ``reason`` ("" when not failed);
    time_s: wall time of the evaluation; scale: the ICP scale factor; n_points: reconstructed points;
    hole_part_m + accuracy_part_m = error_m: what missing surface and what inaccurate surface contribute
    (each oracle's split is in its docstring: the synthetic oracle's by reconstruction probability, a point
    cloud's by tau); registered_mask: (total_views,) bool, which views are in the reconstruction, where the
    oracle tells (None otherwise).
    """

    error_m: float
    accuracy_m: float
    completeness: float
    precision: float
    fscore: float
    tau_m: float
    registered_views: int
    total_views: int
    failed: bool
    reason: str
    time_s: float
    scale: float = 1.0
    n_points: int = 0
    oracle: str = ""
    extra: dict = field(default_factory=dict)
    hole_part_m: float = float("nan")
    accuracy_part_m: float = float("nan")
    registered_mask: np.ndarray | None = field(default=None, compare=False)

    @property
    def registered_fraction(self) -> float:
        """registered_views / total_views (0 for an empty capture set)."""
        return self.registered_views / self.total_views if self.total_views else 0.0

    def metrics(self) -> dict[str, float]:
        """The figures by name (error_m, accuracy_m, completeness, precision, fscore, registered_fraction)."""
        return {"error_m": self.error_m, "hole_part_m": self.hole_part_m, "accuracy_part_m": self.accuracy_part_m,
                "accuracy_m": self.accuracy_m, "completeness": self.completeness,
                "precision": self.precision, "fscore": self.fscore,
                "registered_fraction": self.registered_fraction}

    def to_json_dict(self) -> dict:
        def num(x):
            return None if x is None or not np.isfinite(x) else float(x)
        return {"oracle": self.oracle, "error_m": num(self.error_m), "hole_part_m": num(self.hole_part_m),
                "accuracy_part_m": num(self.accuracy_part_m), "accuracy_m": num(self.accuracy_m),
                "completeness": num(self.completeness), "precision": num(self.precision),
                "fscore": num(self.fscore), "tau_m": self.tau_m, "registered_views": self.registered_views,
                "total_views": self.total_views,
                "registered_fraction": self.registered_fraction, "failed": self.failed, "reason": self.reason,
                "time_s": self.time_s, "scale": num(self.scale), "n_points": self.n_points,
                "extra": self.extra}


class Oracle(Protocol):
    """A reconstruction-quality oracle: the capture poses actually flown + the true ship -> a verdict."""

    name: str

    def evaluate(self, capture_set: CaptureSet, ship_mesh: trimesh.Trimesh, seed: int = 0) -> ReconResult:
        ...


@dataclass(frozen=True)
class Surfels:
    """A reconstruction as surfels: points (m, 3), unit normals (m, 3), radii (m,) in metres."""

    points: np.ndarray
    normals: np.ndarray
    radii: np.ndarray

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def score(self, gt: "GroundTruth", section, seed: int = 0) -> "Scores":
        """Align to ``gt`` and compute the metrics (:func:`score_reconstruction`) with ``section``'s settings."""
        return score_reconstruction(self, gt, section.tau_m, section.icp_max_correspondence_m,
                                    section.icp_max_iterations, seed)


@dataclass(frozen=True)
class GroundTruth:
    """The true ship, prepared once per mesh for repeated evaluation.

    occluder_scene: ship + sea plane (z = 0) for visibility; ship_scene: the ship alone for distances;
    ship_geometry_id: the ship's id in occluder_scene; samples (m, 3) / sample_normals (m, 3): the visible
    ground truth (above the waterline, reachable from outside); cloud: the samples as an open3d point cloud
    (the ICP target); area_m2: total mesh area above the waterline.
    """

    mesh: trimesh.Trimesh
    occluder_scene: o3d.t.geometry.RaycastingScene
    ship_scene: o3d.t.geometry.RaycastingScene
    ship_geometry_id: int
    samples: np.ndarray
    sample_normals: np.ndarray
    cloud: o3d.geometry.PointCloud
    area_m2: float


def mesh_key(mesh: trimesh.Trimesh) -> str:
    """A content hash of a mesh's vertices and faces (for caching its prepared ground truth)."""
    h = hashlib.blake2b(digest_size=16)
    h.update(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    return h.hexdigest()


def in_plan_order(capture_set: CaptureSet) -> tuple[CaptureSet, np.ndarray | None]:
    """(the set's views in the order of the plan's viewpoints, ``view_ids()``, and that order (n,) as indices into
    the set; None when it already is): what an oracle reconstructs, so that a tour's result does not depend on the
    order it was flown in."""
    order = np.argsort(capture_set.view_ids(), kind="stable")
    if np.all(order == np.arange(len(order))):
        return capture_set, None
    return capture_set.subset(order), order


def check_inputs(capture_set: CaptureSet, mesh: trimesh.Trimesh) -> None:
    """Refuse malformed capture sets and meshes with one :class:`InputError` line."""
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError("ship mesh", "expected a non-empty triangle mesh")
    if not np.all(np.isfinite(mesh.vertices)):
        raise InputError("ship mesh", "vertices are not all finite")
    if mesh.vertices[:, 2].max() <= 0:
        raise InputError("ship mesh", "nothing above the waterline (z > 0)")
    n = len(capture_set)
    shapes = {"positions": (capture_set.positions, (n, 3)), "yaw": (capture_set.yaw, (n,)),
              "pitch": (capture_set.pitch, (n,)), "planned_index": (capture_set.planned_index, (n,))}
    # optional fields: None means level camera / priors = true positions
    if capture_set.roll is not None:
        shapes["roll"] = (capture_set.roll, (n,))
    if capture_set.prior_positions is not None:
        shapes["prior_positions"] = (capture_set.prior_positions, (n, 3))
    if capture_set.blur_px is not None:
        shapes["blur_px"] = (capture_set.blur_px, (n,))
    for name, (arr, shape) in shapes.items():
        arr = np.asarray(arr)
        if arr.shape != shape:
            raise InputError("capture set", f"{name} has shape {arr.shape}, expected {shape}")
        if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
            raise InputError("capture set", f"{name} is not all finite")
    if capture_set.blur_px is not None and np.any(np.asarray(capture_set.blur_px) < 0):
        raise InputError("capture set", "blur_px is negative")
    for name in ("planned_index", "view_id"):
        index = getattr(capture_set, name)
        if index is None:
            continue
        index = np.asarray(index)
        if index.shape != (n,) or index.dtype.kind not in "iu" or np.any(index < 0) or len(np.unique(index)) != n:
            raise InputError("capture set", f"{name} must be distinct non-negative integers (one per view)")


def _fibonacci_sphere(count: int) -> np.ndarray:
    """(count, 3) nearly uniform unit directions (golden-angle spiral)."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _tensor_mesh(vertices: np.ndarray, faces: np.ndarray) -> o3d.t.geometry.TriangleMesh:
    tm = o3d.t.geometry.TriangleMesh()
    tm.vertex.positions = o3d_tensor(np.ascontiguousarray(vertices, dtype=np.float32))
    tm.triangle.indices = o3d_tensor(np.ascontiguousarray(faces, dtype=np.int32))
    return tm


def prepare_ground_truth(mesh: trimesh.Trimesh, density_per_m2: float = 2.0, seed: int = 0) -> GroundTruth:
    """Build the ray-casting scenes and the visible ground-truth samples of ``mesh``.

    Samples are drawn uniformly on the surface (``density_per_m2`` per m^2, seeded, fixed across trials),
    kept when above the waterline (z > 0: the keel is never seen, paper Sec. 5.1) and when at least one of
    48 outward directions escapes the mesh (faces enclosed by other parts, e.g. a deckhouse's floor, are
    invisible to any camera and would otherwise count as missing).
    """
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    ship_scene = o3d.t.geometry.RaycastingScene()
    ship_scene.add_triangles(_tensor_mesh(vertices, faces))
    occluder_scene = o3d.t.geometry.RaycastingScene()
    ship_id = int(occluder_scene.add_triangles(_tensor_mesh(vertices, faces)))
    e = SEA_HALF_EXTENT_M
    sea_v = np.array([[-e, -e, 0.0], [e, -e, 0.0], [e, e, 0.0], [-e, e, 0.0]])
    occluder_scene.add_triangles(_tensor_mesh(sea_v, np.array([[0, 1, 2], [0, 2, 3]])))

    tri_z = vertices[faces][:, :, 2]
    # area above the waterline, approximated per triangle by the fraction of its vertices above z = 0
    above = mesh.area_faces * (tri_z > 0).mean(axis=1)
    area = float(above.sum())
    count = int(np.ceil(density_per_m2 * float(mesh.area)))
    points, face_index = trimesh.sample.sample_surface(mesh, count, seed=np.random.default_rng(seed))
    normals = np.asarray(mesh.face_normals)[face_index]
    keep = points[:, 2] > 1e-6
    points, normals = points[keep], normals[keep]

    # Enclosure test: batched rays from every sample along the outward directions (one open3d call).
    dirs = _fibonacci_sphere(_ENCLOSURE_DIRECTIONS)
    eps = 1e-3
    origins = np.repeat(points, len(dirs), axis=0)
    ray_dirs = np.tile(dirs, (len(points), 1))
    facing = (ray_dirs * np.repeat(normals, len(dirs), axis=0)).sum(axis=1)
    # a face's back side also counts (meshes with mixed winding): offset along the ray, not the normal
    rays = np.concatenate([origins + eps * ray_dirs, ray_dirs], axis=1).astype(np.float32)
    t_hit = ship_scene.cast_rays(o3d_tensor(rays))["t_hit"].numpy()
    escaped = (~np.isfinite(t_hit)) & (np.abs(facing) > 0.1)
    visible = escaped.reshape(len(points), len(dirs)).any(axis=1)
    points, normals = points[visible], normals[visible]
    if len(points) == 0:
        raise InputError("ship mesh", "no surface above the waterline is visible from outside")

    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.normals = o3d.utility.Vector3dVector(normals)
    return GroundTruth(mesh, occluder_scene, ship_scene, ship_id, points, normals, cloud, area)


class GroundTruthCache:
    """Prepared ground truth per mesh content (campaigns evaluate thousands of capture sets on one ship)."""

    def __init__(self, density_per_m2: float, seed: int, max_entries: int = 4):
        self.density_per_m2 = density_per_m2
        self.seed = seed
        self.max_entries = max_entries
        self._entries: dict[str, GroundTruth] = {}

    def get(self, mesh: trimesh.Trimesh) -> GroundTruth:
        key = mesh_key(mesh)
        gt = self._entries.get(key)
        if gt is None:
            if len(self._entries) >= self.max_entries:
                self._entries.pop(next(iter(self._entries)))
            gt = prepare_ground_truth(mesh, self.density_per_m2, self.seed)
            self._entries[key] = gt
        return gt


class MeshOracle:
    """What the oracles share: their config section and the ground truth prepared per ship mesh (cached by
    content, since a campaign scores thousands of capture sets of one ship)."""

    name: str

    def __init__(self, section):
        self.section = section
        self._gt_cache = GroundTruthCache(section.gt_density_per_m2, section.gt_seed)

    def ground_truth(self, ship_mesh: trimesh.Trimesh) -> GroundTruth:
        """The prepared ground truth of ``ship_mesh``."""
        return self._gt_cache.get(ship_mesh)

    def reconstruct(self, capture_set: CaptureSet, gt: GroundTruth, seed: int = 0) -> tuple:
        """(reconstruction, registered views, failure reason or "", extra diagnostics): the oracle's own part.
        The reconstruction has ``len`` (points) and ``score(gt, section, seed) -> Scores``; registered views: their
        count, or the (n,) bool mask of the views registered."""
        raise NotImplementedError

    def evaluate(self, capture_set: CaptureSet, ship_mesh: trimesh.Trimesh, seed: int = 0) -> ReconResult:
        """Reconstruct, align to the ground truth (ICP with scale) and score: the :class:`Oracle` interface. The
        views are reconstructed in the order of the plan's viewpoints (``view_ids()``; the registered mask comes
        back in the set's own order): the result of a tour does not depend on the order it was flown in (the
        incremental registration breaks its ties by position)."""
        start = time.perf_counter()
        check_inputs(capture_set, ship_mesh)
        gt = self.ground_truth(ship_mesh)
        planned, order = in_plan_order(capture_set)
        recon, registered, reason, extra = self.reconstruct(planned, gt, seed)
        mask = np.asarray(registered, dtype=bool) if np.ndim(registered) == 1 else None
        if order is not None:       # per-view results back in the set's own order
            mask = None if mask is None else mask[np.argsort(order)]
            if "registration_order" in extra:
                extra = {**extra, "registration_order": [int(order[v]) for v in extra["registration_order"]]}
        s = self.section
        scores = recon.score(gt, s, seed)
        return ReconResult(scores.error_m, scores.accuracy_m, scores.completeness, scores.precision,
                           scores.fscore, s.tau_m, int(mask.sum()) if mask is not None else int(registered),
                           len(capture_set), bool(reason), reason, time.perf_counter() - start, scores.scale,
                           len(recon), self.name, extra, scores.hole_part_m, scores.accuracy_part_m, mask)


def align_to_ground_truth(points: np.ndarray, gt: GroundTruth, max_correspondence_m: float,
                          max_iterations: int, max_source_points: int = 5000,
                          seed: int = 0, tolerance: float = 1e-6) -> np.ndarray:
    """4x4 similarity (scale allowed, as the paper's CloudCompare ICP) taking ``points`` (m, 3) onto the GT.

    ICP from the identity (both are in the ship frame): each iteration pairs every source point with its
    closest point on the ground-truth *mesh* (open3d ``compute_closest_points``, exact, so no bias from a
    sampled target), drops pairs farther than ``max_correspondence_m``, and solves the similarity with
    open3d's ``TransformationEstimationPointToPoint(with_scaling=True)`` (Umeyama 1991). At most
    ``max_source_points`` points (a seeded subset) drive the estimate. Stops when the update moves no point
    by more than ``tolerance`` x the cloud's extent.
    """
    transform = np.eye(4)
    if max_iterations <= 0 or len(points) < 3:
        return transform
    src = np.asarray(points, dtype=np.float64)
    if len(src) > max_source_points:
        idx = np.sort(np.random.default_rng(seed).choice(len(src), max_source_points, replace=False))
        src = src[idx]
    extent = float(np.linalg.norm(src.max(axis=0) - src.min(axis=0))) or 1.0
    estimator = o3d.pipelines.registration.TransformationEstimationPointToPoint(with_scaling=True)
    source = o3d.geometry.PointCloud()
    target = o3d.geometry.PointCloud()
    for _ in range(max_iterations):
        moved = src @ transform[:3, :3].T + transform[:3, 3]
        closest = gt.ship_scene.compute_closest_points(
            o3d_tensor(moved.astype(np.float32)))["points"].numpy().astype(np.float64)
        close = np.einsum("kj,kj->k", closest - moved, closest - moved) <= max_correspondence_m ** 2
        if close.sum() < 3:
            break
        source.points = o3d.utility.Vector3dVector(moved[close])
        target.points = o3d.utility.Vector3dVector(closest[close])
        pairs = np.repeat(np.arange(int(close.sum()), dtype=np.int32)[:, None], 2, axis=1)
        step = np.asarray(estimator.compute_transformation(source, target, o3d.utility.Vector2iVector(pairs)))
        transform = step @ transform
        change = np.abs(step - np.eye(4))
        if change[:3, :3].max() * extent + change[:3, 3].max() <= tolerance * extent:
            break
    return transform


def apply_similarity(transform: np.ndarray, surfels: Surfels) -> Surfels:
    """Apply a 4x4 similarity to surfels (points moved, normals rotated, radii scaled)."""
    m = transform[:3, :3]
    scale = float(np.cbrt(np.linalg.det(m))) if len(surfels) else 1.0
    rot = m / scale if scale > 0 else m
    pts = surfels.points @ m.T + transform[:3, 3]
    nrm = surfels.normals @ rot.T
    return Surfels(pts, nrm, surfels.radii * scale)


def surfel_distances(queries: np.ndarray, surfels: Surfels, k: int = 4) -> np.ndarray:
    """Distance (m) from each query point (q, 3) to the nearest of the ``k`` nearest surfel discs.

    Point-to-disc distance: sqrt(dn^2 + max(0, dt - r)^2), dn along the surfel normal, dt in its plane.
    """
    if len(surfels) == 0:
        return np.full(len(queries), np.inf)
    k = min(k, len(surfels))
    tree = cKDTree(surfels.points, balanced_tree=False, compact_nodes=False)  # faster build, same answers
    _, idx = tree.query(queries, k=k)
    idx = idx.reshape(len(queries), k)
    rel = queries[:, None, :] - surfels.points[idx]
    dn = np.einsum("qkj,qkj->qk", rel, surfels.normals[idx])
    dt = np.sqrt(np.maximum(np.einsum("qkj,qkj->qk", rel, rel) - dn * dn, 0.0))
    d = np.sqrt(dn * dn + np.maximum(dt - surfels.radii[idx], 0.0) ** 2)
    return d.min(axis=1)


@dataclass(frozen=True)
class Scores:
    """The metrics of :class:`ReconResult` (see there), as a reconstruction's ``score`` returns them."""

    error_m: float
    accuracy_m: float
    completeness: float
    precision: float
    fscore: float
    scale: float
    hole_part_m: float = float("nan")
    accuracy_part_m: float = float("nan")


def score_reconstruction(surfels: Surfels, gt: GroundTruth, tau_m: float, max_correspondence_m: float,
                         max_iterations: int, seed: int = 0, max_accuracy_points: int = 20000) -> Scores:
    """Align the reconstruction to the ground truth (ICP with scale) and compute the paper-style metrics.

    Accuracy and precision are means over at most ``max_accuracy_points`` reconstructed points (a seeded
    subset; the sampling error of the mean is far below the metric's resolution). The split of error_m: the
    hole part sums the visible samples farther than tau from the reconstruction, the accuracy part the rest.
    """
    if len(surfels) == 0:
        return Scores(float("nan"), float("nan"), 0.0, 0.0, 0.0, 1.0)
    transform = align_to_ground_truth(surfels.points, gt, max_correspondence_m, max_iterations, seed=seed)
    aligned = apply_similarity(transform, surfels)
    scale = float(np.cbrt(np.linalg.det(transform[:3, :3])))
    # accuracy: reconstruction -> ground-truth mesh (exact point-to-triangle distance, open3d)
    acc_points = aligned.points
    if len(acc_points) > max_accuracy_points:
        acc_points = acc_points[np.random.default_rng(seed).choice(len(acc_points), max_accuracy_points,
                                                                   replace=False)]
    acc = gt.ship_scene.compute_distance(
        o3d_tensor(acc_points.astype(np.float32))).numpy().astype(np.float64)
    # error / completeness: visible ground truth -> reconstruction surfels
    comp = surfel_distances(gt.samples, aligned)
    completeness = float((comp <= tau_m).mean())
    precision = float((acc <= tau_m).mean())
    f = 0.0 if completeness + precision == 0 else 2 * completeness * precision / (completeness + precision)
    far = comp > tau_m
    return Scores(float(comp.mean()), float(acc.mean()), completeness, precision, f, scale,
                  float(np.sum(comp[far]) / len(comp)), float(np.sum(comp[~far]) / len(comp)))
