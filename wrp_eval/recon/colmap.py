"""Photogrammetric validation oracle: render the textured ship at the capture poses, run COLMAP (pycolmap).

Pipeline (the open stand-in for the paper's ContextCapture, Sec. 4.1):
1. render every capture pose (:mod:`wrp_eval.recon.render`, solid procedural texture, sea as occluder);
2. pycolmap SIFT feature extraction with the known pinhole intrinsics (drone images carry them in EXIF),
   exhaustive (or sequential) matching with geometric verification, global mapping (GLOMAP, default) or
   incremental mapping;
3. keep the model with the most registered images; failed when it holds fewer than half the images (or
   fewer than 3), as the synthetic oracle;
4. georeference: similarity from the registered cameras' centres to the true capture positions (as
   ContextCapture does with the drone's GPS), then ICP with scale against the ground truth (:mod:`base`);
   optionally (``max_camera_residual_m``, off by default) a model whose cameras stay farther than that
   (RMS) from their positions after the similarity has broken geometry and counts as failed;
5. score the sparse points as surfels: normal from the 12 nearest neighbours (PCA, open3d), radius the
   distance to the 4th nearest neighbour (capped at 2 m), so that the sparse cloud covers the surface it
   sampled and the metrics compare with the synthetic oracle's.

Needs ``pip install .[photogrammetry]`` (pycolmap). Slow (tens of seconds per capture set on 2 cores).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
import open3d as o3d
from scipy.spatial import cKDTree

from wrp_eval.errors import InputError
from wrp_eval.recon.base import GroundTruth, MeshOracle, Surfels
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.render import SolidTexture, render_views
from wrp_eval.sim.captures import CaptureSet

_MAX_SURFEL_RADIUS_M = 2.0


def _similarity_from_centres(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """4x4 similarity taking ``src`` (k, 3) onto ``dst`` (k, 3) in least squares (Umeyama 1991, open3d)."""
    est = o3d.pipelines.registration.TransformationEstimationPointToPoint(with_scaling=True)
    a = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(src))
    b = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(dst))
    pairs = o3d.utility.Vector2iVector(np.repeat(np.arange(len(src), dtype=np.int32)[:, None], 2, axis=1))
    return np.asarray(est.compute_transformation(a, b, pairs))


def sparse_surfels(points: np.ndarray) -> Surfels:
    """Surfels from a sparse cloud: PCA normals (12 neighbours) and the 4th-neighbour distance as radius."""
    if len(points) < 5:
        return Surfels(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(12))
    dist, _ = cKDTree(points).query(points, k=5)
    radii = np.minimum(dist[:, 4], _MAX_SURFEL_RADIUS_M)
    return Surfels(points, np.asarray(pcd.normals), radii)


class ColmapOracle(MeshOracle):
    """Render + pycolmap SfM. ``evaluate(capture_set, ship_mesh, seed)`` -> :class:`ReconResult`."""

    name = "colmap"

    def __init__(self, section: OracleSection = OracleSection(), work_dir: str | Path | None = None):
        try:
            import pycolmap  # noqa: F401
        except ImportError:
            raise InputError("oracle colmap", "pycolmap is not installed: pip install .[photogrammetry]") from None
        super().__init__(section)
        self.work_dir = Path(work_dir) if work_dir is not None else None

    def reconstruct(self, capture_set: CaptureSet, gt: GroundTruth, seed: int = 0):
        """Render, run SfM in ``work_dir`` (kept) or a temporary folder (removed)."""
        if self.work_dir is not None:
            self.work_dir.mkdir(parents=True, exist_ok=True)
            return self._run(capture_set, gt, seed, self.work_dir)
        with tempfile.TemporaryDirectory(prefix="wrp-colmap-") as tmp:
            return self._run(capture_set, gt, seed, Path(tmp))

    def _run(self, capture_set: CaptureSet, gt: GroundTruth, seed: int,
             work: Path) -> tuple[Surfels, int, str, dict]:
        import pycolmap
        from PIL import Image

        c = self.section.colmap
        n = len(capture_set)
        empty = Surfels(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
        if n == 0:
            return empty, 0, "no views captured", {}
        t0 = time.perf_counter()
        images, cam = render_views(capture_set, gt, c.image_width_px, SolidTexture(seed=self.section.gt_seed))
        image_dir = work / "images"
        image_dir.mkdir(parents=True, exist_ok=True)
        names = [f"view{i:04d}.png" for i in range(n)]
        for name, img in zip(names, images):  # one file per image: COLMAP reads files
            Image.fromarray(img).save(image_dir / name)
        t_render = time.perf_counter() - t0

        database = work / "database.db"
        if database.exists():
            database.unlink()
        reader = pycolmap.ImageReaderOptions()
        reader.camera_model = "SIMPLE_PINHOLE"
        reader.camera_params = f"{cam.focal_px},{cam.image_width_px / 2},{cam.image_height_px / 2}"
        extraction = pycolmap.FeatureExtractionOptions()
        extraction.sift.max_num_features = c.max_num_features
        extraction.use_gpu = False
        pycolmap.extract_features(database, image_dir, image_names=names, camera_mode=pycolmap.CameraMode.SINGLE,
                                  reader_options=reader, extraction_options=extraction,
                                  device=pycolmap.Device.cpu)
        matching = pycolmap.FeatureMatchingOptions()
        matching.use_gpu = False
        if c.match_exhaustive:
            pycolmap.match_exhaustive(database, matching_options=matching, device=pycolmap.Device.cpu)
        else:
            pairing = pycolmap.SequentialPairingOptions()
            pairing.overlap = 10
            pycolmap.match_sequential(database, matching_options=matching, pairing_options=pairing,
                                      device=pycolmap.Device.cpu)
        t_match = time.perf_counter() - t0 - t_render

        out = work / "sparse"
        out.mkdir(exist_ok=True)
        seed32 = int(seed) % (2 ** 31)  # COLMAP takes a 32-bit seed
        if c.mapper == "global":
            # global SfM (GLOMAP in pycolmap): rotation averaging + global positioning over the whole verified
            # view graph, robust where incremental mapping stalls on weakly-chained views (see README)
            options = pycolmap.GlobalPipelineOptions()
            options.random_seed = seed32
            options.num_threads = 2
            options.mapper.random_seed = seed32
            options.mapper.global_positioning.use_gpu = False
            options.mapper.bundle_adjustment.refine_focal_length = False
            options.mapper.bundle_adjustment.refine_extra_params = False
            models = pycolmap.global_mapping(database, image_dir, out, options)
        else:
            options = pycolmap.IncrementalPipelineOptions()
            options.random_seed = seed32
            options.ba_refine_focal_length = False
            options.ba_refine_principal_point = False
            options.ba_refine_extra_params = False
            options.multiple_models = True
            options.num_threads = 2
            models = pycolmap.incremental_mapping(database, image_dir, out, options)
        t_map = time.perf_counter() - t0 - t_render - t_match
        extra = {"render_s": t_render, "features_matching_s": t_match, "mapping_s": t_map,
                 "models": len(models)}
        if not models:
            return empty, 0, f"COLMAP registered no images ({n} given)", extra
        best = max(models.values(), key=lambda r: r.num_reg_images())
        registered = int(best.num_reg_images())
        extra["model_sizes"] = sorted((int(r.num_reg_images()) for r in models.values()), reverse=True)

        # georeference with the registered cameras' centres -> true capture positions
        name_to_view = {name: i for i, name in enumerate(names)}
        centres, truth = [], []
        for image in best.images.values():
            if image.has_pose:
                centres.append(np.asarray(image.projection_center()))
                truth.append(capture_set.positions[name_to_view[image.name]])
        centres, truth = np.asarray(centres), np.asarray(truth)
        pts = np.array([p.xyz for p in best.points3D.values()]) if best.num_points3D() else np.zeros((0, 3))
        if len(centres) >= 3:
            transform = _similarity_from_centres(centres, truth)
            pts = pts @ transform[:3, :3].T + transform[:3, 3]
            moved = centres @ transform[:3, :3].T + transform[:3, 3]
            extra["camera_residual_m"] = float(np.sqrt(np.mean(np.sum((moved - truth) ** 2, axis=1))))
        # keep points on the ship side of the sea (a few triangulated sea/sky outliers are dropped)
        pts = pts[np.isfinite(pts).all(axis=1)]
        extra["points3D"] = int(len(pts))
        reason = ""
        residual = extra.get("camera_residual_m", 0.0)
        if registered >= 3 and c.max_camera_residual_m is not None and residual > c.max_camera_residual_m:
            # the model's cameras cannot be placed at their GPS positions by any similarity: its geometry is
            # broken (e.g. a weakly chained view graph folded by global positioning), the model is unusable
            reason = (f"COLMAP model geometry is inconsistent: registered cameras are {residual:.1f} m RMS from "
                      f"their capture positions after the best similarity")
        elif registered < 3:
            reason = f"only {registered} view(s) registered (fewer than 3)"
        elif 2 * registered < n:
            reason = f"only {registered} of {n} views registered ({len(models)} COLMAP model(s), largest kept)"
        return sparse_surfels(pts), registered, reason, extra
