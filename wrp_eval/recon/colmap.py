"""Photogrammetric validation oracle: render the textured ship at the capture poses, run COLMAP (pycolmap).

Pipeline (the open stand-in for the paper's ContextCapture, Sec. 4.1):
1. render every capture pose (:mod:`wrp_eval.recon.render`, solid procedural texture, sea as occluder), a view
   with motion blur (``CaptureSet.blur_px``) smeared horizontally by it, scaled to the render width;
2. pycolmap SIFT feature extraction with the known pinhole intrinsics (drone images carry them in EXIF),
   exhaustive (or sequential) matching with geometric verification (RANSAC seeded);
3. pose priors: every image's recorded position (``CaptureSet.prior_positions``, the drone's navigation /
   GNSS estimate that a photo's GPS tag carries; the true position where none was recorded; ContextCapture's
   aerotriangulation takes the same) is written to the COLMAP database as a position prior with a standard
   deviation of ``prior_position_sigma_m``;
4. incremental mapping (default) with position-prior bundle adjustment (COLMAP's ``use_prior_position``:
   the model is aligned to the priors and every global bundle adjustment keeps the cameras near them, so a
   weakly chained view graph cannot fold), single-threaded with a fixed seed (reproducible); or global
   mapping (GLOMAP, no priors; random position initialisation, not reproducible);
5. keep the model with the most registered images; failed when it holds fewer than half the images (or
   fewer than 3), issue 6's rule, as the synthetic oracle;
6. georeference: similarity from the registered cameras' centres to the true capture positions (with exact
   priors a no-op up to their residual after prior BA; with GNSS priors it removes their common error, the
   evaluator's coarse alignment before ICP, as a CloudCompare user aligns by hand first), then ICP with scale
   against the ground truth (:mod:`base`);
   optionally (``max_camera_residual_m``, off by default) a model whose cameras stay farther than that
   (RMS) from their positions after the similarity has broken geometry and counts as failed;
7. score the sparse points as surfels: normal from the 12 nearest neighbours (PCA, open3d), radius the
   distance to the 4th nearest neighbour (capped at 2 m), so that the sparse cloud covers the surface it
   sampled and the metrics compare with the synthetic oracle's.

With a ``work_dir``, the rendered features and matches (``database.db``) are kept there with a fingerprint
of what produced them, and a later run on the same capture set, ship and settings maps again from them
(rendering + SIFT + matching are ~80 % of the time).

Needs ``pip install .[photogrammetry]`` (pycolmap). Slow (tens of seconds per capture set on 2 cores).
"""

from __future__ import annotations

import hashlib
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import open3d as o3d
from scipy.spatial import cKDTree

from wrp_eval.errors import InputError
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.oracle import GroundTruth, MeshOracle, Surfels, mesh_key
from wrp_eval.recon.render import SolidTexture, render_views
from wrp_eval.sim.captures import CaptureSet

_MAX_SURFEL_RADIUS_M = 2.0
_FINGERPRINT = "fingerprint.json"


def _similarity_from_centres(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """4x4 similarity taking ``src`` (k, 3) onto ``dst`` (k, 3) in least squares (Umeyama 1991, open3d)."""
    est = o3d.pipelines.registration.TransformationEstimationPointToPoint(with_scaling=True)
    a = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(src))
    b = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(dst))
    pairs = o3d.utility.Vector2iVector(np.repeat(np.arange(len(src), dtype=np.int32)[:, None], 2, axis=1))
    return np.asarray(est.compute_transformation(a, b, pairs))


def rotation_errors_deg(world_from_cam: np.ndarray, similarity: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Angles (k,) in degrees between a model's camera orientations, world-from-camera (k, 3, 3) in the model
    frame, carried into the capture frame by the rotation of ``similarity`` (4x4, scale removed), and the
    true world-from-camera rotations ``truth`` (k, 3, 3) (COLMAP's camera frame is OpenCV's, as ours)."""
    lin = similarity[:3, :3]
    rot = lin / np.cbrt(np.linalg.det(lin))
    rel = np.einsum("kji,jl,klm->kim", truth, rot, world_from_cam)  # truth^T Q R_model
    cos = (np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def sparse_surfels(points: np.ndarray) -> Surfels:
    """Surfels from a sparse cloud: PCA normals (12 neighbours) and the 4th-neighbour distance as radius."""
    if len(points) < 5:
        return Surfels(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(12))
    dist, _ = cKDTree(points).query(points, k=5)
    radii = np.minimum(dist[:, 4], _MAX_SURFEL_RADIUS_M)
    return Surfels(points, np.asarray(pcd.normals), radii)


def database_fingerprint(capture_set: CaptureSet, mesh_key: str, section: OracleSection, seed: int) -> str:
    """Hash of everything the features and matches depend on (poses, roll, motion blur, camera, ship, texture,
    settings, seed)."""
    c = section.colmap
    h = hashlib.sha256()
    for arr in (capture_set.positions, capture_set.yaw, capture_set.pitch):
        h.update(np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    # roll changes the rendered images; a level set hashes as before (kept databases stay valid). The
    # position priors are not hashed: they are rewritten before every mapping
    if capture_set.roll is not None and np.any(np.asarray(capture_set.roll) != 0):
        h.update(b"roll" + np.ascontiguousarray(capture_set.roll, dtype=np.float64).tobytes())
    # motion blur smears the rendered images (render.py); a sharp set hashes as before
    if np.any(capture_set.blur() != 0):
        h.update(b"blur" + np.ascontiguousarray(capture_set.blur(), dtype=np.float64).tobytes())
    cam = capture_set.camera
    h.update(json.dumps([cam.focal_mm, cam.sensor_width_mm, cam.image_width_px, cam.image_height_px, mesh_key,
                         section.gt_seed, c.image_width_px, c.max_num_features, c.match_exhaustive,
                         int(seed)]).encode())
    return h.hexdigest()


def write_position_priors(database_path: Path, names: list[str], capture_set: CaptureSet, sigma_m: float) -> int:
    """Write one Cartesian position prior (m, isotropic covariance sigma_m^2) per image of ``names`` (aligned
    with the views of ``capture_set``): the recorded navigation positions ``capture_set.prior_positions``
    (what an image's GPS tag gives a photogrammetry tool), or the true positions where there are none.
    Positions in the ship frame. Returns the number of priors in the database.
    """
    import pycolmap  # lazily: pycolmap is the optional [photogrammetry] extra
    positions = capture_set.position_priors()
    db = pycolmap.Database.open(str(database_path))
    try:
        db.clear_pose_priors()
        by_name = {image.name: image for image in db.read_all_images()}
        for name, pos in zip(names, positions, strict=True):
            prior = pycolmap.PosePrior()
            prior.corr_data_id = by_name[name].data_id
            prior.position = pos
            prior.position_covariance = np.eye(3) * sigma_m ** 2
            prior.coordinate_system = pycolmap.PosePriorCoordinateSystem.CARTESIAN
            db.write_pose_prior(prior)
        return db.num_pose_priors()
    finally:
        db.close()


def _georeferenced_points(model, names: list[str], capture_set: CaptureSet, extra: dict) -> np.ndarray:
    """The sparse points (k, 3) of the COLMAP ``model`` carried into the capture frame by the similarity from its
    registered cameras' centres to the true capture positions (fewer than 3 cameras: as they are); the camera
    residuals and the rotation check go into ``extra``. ``names``: the image names in view order."""
    # georeference with the registered cameras' centres -> true capture positions
    name_to_view = {name: i for i, name in enumerate(names)}
    centre_list, views, model_rot = [], [], []
    for image in model.images.values():
        if image.has_pose:
            centre_list.append(np.asarray(image.projection_center()))
            views.append(name_to_view[image.name])
            pose = image.cam_from_world() if callable(image.cam_from_world) else image.cam_from_world
            model_rot.append(np.asarray(pose.rotation.matrix()).T)  # world-from-camera, model frame
    centres, truth = np.asarray(centre_list), capture_set.positions[np.asarray(views, dtype=int)]
    if len(centres) and capture_set.prior_positions is not None:
        # how far the model sits from the recorded positions it was held to (prior BA), before any similarity
        priors = capture_set.position_priors()[np.asarray(views, dtype=int)]
        extra["camera_prior_residual_m"] = float(np.sqrt(np.mean(np.sum((centres - priors) ** 2, axis=1))))
    pts = np.array([p.xyz for p in model.points3D.values()]) if model.num_points3D() else np.zeros((0, 3))
    if len(centres) >= 3:
        extra["camera_residual_before_m"] = float(np.sqrt(np.mean(np.sum((centres - truth) ** 2, axis=1))))
        transform = _similarity_from_centres(centres, truth)
        pts = pts @ transform[:3, :3].T + transform[:3, 3]
        moved = centres @ transform[:3, :3].T + transform[:3, 3]
        extra["camera_residual_m"] = float(np.sqrt(np.mean(np.sum((moved - truth) ** 2, axis=1))))
        # orientation check of the whole chain (render, camera model with roll, SfM): median angle between
        # the model's georeferenced cameras and the capture rotations
        truth_rot = capture_set.rotations()[np.asarray(views, dtype=int)]
        extra["camera_rotation_error_deg"] = float(np.median(rotation_errors_deg(np.asarray(model_rot),
                                                                                 transform, truth_rot)))
    return pts


class ColmapOracle(MeshOracle):
    """Render + pycolmap SfM. ``evaluate(capture_set, ship_mesh, seed)`` -> :class:`ReconResult`."""

    name = "colmap"

    def __init__(self, section: OracleSection = OracleSection(), work_dir: str | Path | None = None):
        try:
            import pycolmap  # noqa: F401  # lazily: pycolmap is the optional [photogrammetry] extra
        except ImportError:
            raise InputError("oracle colmap", "pycolmap is not installed: pip install .[photogrammetry]") from None
        super().__init__(section)
        self.work_dir = Path(work_dir) if work_dir is not None else None

    def reconstruct(self, capture_set: CaptureSet, gt: GroundTruth, seed: int = 0):
        """Render, run SfM in ``work_dir`` (kept, database reused when it fits) or a temporary folder."""
        if self.work_dir is not None:
            self.work_dir.mkdir(parents=True, exist_ok=True)
            return self._run(capture_set, gt, seed, self.work_dir)
        with tempfile.TemporaryDirectory(prefix="wrp-colmap-") as tmp:
            return self._run(capture_set, gt, seed, Path(tmp))

    def _features_and_matches(self, capture_set: CaptureSet, gt: GroundTruth, seed: int, work: Path,
                              names: list[str]) -> tuple[dict, bool]:
        """Render, SIFT, match into ``work/database.db`` unless a database with the same fingerprint is there.

        Returns (timings in s: render_s, features_s (SIFT), matching_s (matching + geometric verification),
        features_matching_s (their sum); reused)."""
        import pycolmap  # lazily: pycolmap is the optional [photogrammetry] extra
        from PIL import Image  # lazily: pillow comes with the [photogrammetry] extra

        c = self.section.colmap
        database = work / "database.db"
        fingerprint = database_fingerprint(capture_set, mesh_key(gt.mesh), self.section, seed)
        stamp = work / _FINGERPRINT
        if database.exists() and stamp.exists() and json.loads(stamp.read_text()).get("fingerprint") == fingerprint:
            return {"render_s": 0.0, "features_matching_s": 0.0}, True
        for stale in (database, stamp):
            if stale.exists():
                stale.unlink()
        t0 = time.perf_counter()
        images, cam = render_views(capture_set, gt, c.image_width_px, SolidTexture(seed=self.section.gt_seed))
        image_dir = work / "images"
        image_dir.mkdir(parents=True, exist_ok=True)
        for name, img in zip(names, images, strict=True):  # one file per image: COLMAP reads files
            Image.fromarray(img).save(image_dir / name)
        t_render = time.perf_counter() - t0

        reader = pycolmap.ImageReaderOptions()
        reader.camera_model = "SIMPLE_PINHOLE"
        reader.camera_params = f"{cam.focal_px},{cam.image_width_px / 2},{cam.image_height_px / 2}"
        extraction = pycolmap.FeatureExtractionOptions()
        extraction.sift.max_num_features = c.max_num_features
        extraction.use_gpu = False
        pycolmap.extract_features(database, image_dir, image_names=names, camera_mode=pycolmap.CameraMode.SINGLE,
                                  reader_options=reader, extraction_options=extraction,
                                  device=pycolmap.Device.cpu)
        t_features = time.perf_counter() - t0 - t_render
        matching = pycolmap.FeatureMatchingOptions()
        matching.use_gpu = False
        verification = pycolmap.TwoViewGeometryOptions()
        # COLMAP's RANSAC draws from an unseeded generator by default (random_seed = -1): seed it, so the
        # verified view graph, and everything after it, is reproducible
        verification.ransac.random_seed = int(seed) % (2 ** 31)
        if c.match_exhaustive:
            pycolmap.match_exhaustive(database, matching_options=matching, verification_options=verification,
                                      device=pycolmap.Device.cpu)
        else:
            pairing = pycolmap.SequentialPairingOptions()
            pairing.overlap = 10
            pycolmap.match_sequential(database, matching_options=matching, pairing_options=pairing,
                                      verification_options=verification, device=pycolmap.Device.cpu)
        if self.work_dir is not None:  # the database is what a re-run needs; the PNGs are 0.5 MB each
            shutil.rmtree(image_dir, ignore_errors=True)
        stamp.write_text(json.dumps({"fingerprint": fingerprint}))
        elapsed = time.perf_counter() - t0
        return {"render_s": t_render, "features_matching_s": elapsed - t_render, "features_s": t_features,
                "matching_s": elapsed - t_render - t_features}, False

    def _map(self, database: Path, image_dir: Path, out: Path, seed: int) -> dict:
        """COLMAP mapping of ``database`` into ``out``; {index: pycolmap.Reconstruction}."""
        import pycolmap  # lazily: pycolmap is the optional [photogrammetry] extra

        c = self.section.colmap
        seed32 = int(seed) % (2 ** 31)  # COLMAP takes a 32-bit seed
        if c.mapper == "global":
            # global SfM (GLOMAP in pycolmap): rotation averaging + global positioning from random initial
            # positions; no pose priors, and it folded weakly chained view graphs at random (see README)
            global_options = pycolmap.GlobalPipelineOptions()
            global_options.random_seed = seed32
            global_options.num_threads = c.num_threads
            global_options.mapper.random_seed = seed32
            global_options.mapper.global_positioning.use_gpu = False
            global_options.mapper.bundle_adjustment.refine_focal_length = False
            global_options.mapper.bundle_adjustment.refine_extra_params = False
            return pycolmap.global_mapping(database, image_dir, out, global_options)
        options = pycolmap.IncrementalPipelineOptions()
        options.random_seed = seed32
        options.num_threads = c.num_threads
        options.extract_colors = False  # the images may be gone (work_dir keeps only the database)
        options.ba_refine_focal_length = False  # known intrinsics (EXIF)
        options.ba_refine_principal_point = False
        options.ba_refine_extra_params = False
        options.multiple_models = True
        options.use_prior_position = c.prior_position_sigma_m is not None
        # a robust (Cauchy) loss on the priors: a wrong GPS fix cannot drag the model (COLMAP's default
        # scale, the 95 % chi-square quantile for 3 dof, 7.815)
        options.use_robust_loss_on_prior_position = True
        # COLMAP's registration thresholds (30 inliers, ratio 0.25) are tuned for photo collections with
        # thousands of features per image; our 800-px renders share 20-80 verified inliers between
        # neighbouring views, and with the defaults a connected view graph split into two models (README)
        options.mapper.abs_pose_min_num_inliers = c.abs_pose_min_num_inliers
        options.mapper.abs_pose_min_inlier_ratio = c.abs_pose_min_inlier_ratio
        return pycolmap.incremental_mapping(database, image_dir, out, options)

    def _run(self, capture_set: CaptureSet, gt: GroundTruth, seed: int,
             work: Path) -> tuple[Surfels, int, str, dict]:
        c = self.section.colmap
        n = len(capture_set)
        empty = Surfels(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
        if n == 0:
            return empty, 0, "no views captured", {}
        names = [f"view{i:04d}.png" for i in range(n)]
        extra, reused = self._features_and_matches(capture_set, gt, seed, work, names)
        extra["database_reused"] = reused
        database = work / "database.db"
        if c.prior_position_sigma_m is not None:
            write_position_priors(database, names, capture_set, c.prior_position_sigma_m)
        out = work / "sparse"
        if out.exists():
            shutil.rmtree(out)
        out.mkdir()
        t0 = time.perf_counter()
        image_dir = work / "images"
        image_dir.mkdir(exist_ok=True)  # COLMAP checks that it exists (colours are not extracted)
        models = self._map(database, image_dir, out, seed)
        extra["mapping_s"] = time.perf_counter() - t0
        extra["models"] = len(models)
        if not models:
            return empty, 0, f"COLMAP registered no images ({n} given)", extra
        best = max(models.values(), key=lambda r: r.num_reg_images())
        registered = int(best.num_reg_images())
        extra["model_sizes"] = sorted((int(r.num_reg_images()) for r in models.values()), reverse=True)

        pts = _georeferenced_points(best, names, capture_set, extra)
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
