"""Why COLMAP's error is several times the synthetic oracle's: the synthetic reconstruction
made under the COLMAP oracle's conditions.

The two oracles do not measure the same product. The synthetic oracle models a dense reconstruction (as the
paper's ContextCapture makes) from the capture camera's full-resolution images (6000 px); the COLMAP oracle
is a sparse SfM cloud (a few thousand SIFT points, no dense MVS: pycolmap's PatchMatchStereo needs CUDA) from
800-px renders. :func:`colmap_equivalent` removes these differences one at a time from the synthetic side:

* ``width``: the same capture set with the camera at the render width (same field of view, coarser pixels:
  the pixel noise in metres scales with it; the same keypoints per image and no range cut, as COLMAP);
* ``sparse``: that reconstruction thinned to COLMAP's number of points (drawn by reconstruction
  probability, seeded) and scored as COLMAP's cloud is (surfels with the 4th-neighbour radius,
  :func:`wrp_eval.recon.colmap.sparse_surfels`).

If the ``sparse`` error is close to COLMAP's, the gap is the product (sparse, low-resolution), not optimism of
the synthetic oracle about the scene, and its absolute scale stays that of a dense full-resolution model.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import trimesh

from wrp_eval.camera import Camera
from wrp_eval.recon.colmap import sparse_surfels
from wrp_eval.recon.oracle import in_plan_order
from wrp_eval.sim.captures import CaptureSet


def at_width(capture_set: CaptureSet, width_px: int) -> CaptureSet:
    """``capture_set`` with its camera resampled to ``width_px`` (same sensor, lens and aspect ratio); the
    recorded blur, in pixels, is rescaled with it."""
    cam = capture_set.camera
    height = int(round(width_px * cam.image_height_px / cam.image_width_px))
    small = Camera(cam.focal_mm, cam.sensor_width_mm, int(width_px), height)
    blur = None if capture_set.blur_px is None else capture_set.blur() * width_px / cam.image_width_px
    return replace(capture_set, camera=small, blur_px=blur)


def _at_render_width(oracle, shrink: float):
    """A copy of the synthetic ``oracle`` for images ``shrink`` times narrower: the GSD range cut kept where it
    was in metres of standoff (COLMAP has none; at the capture width it never binds), and the same matched
    keypoints per image (COLMAP extracts up to ``oracle.colmap.max_num_features`` per render whatever its
    width), so only the coarser pixels change."""
    from wrp_eval.recon.synthetic import SyntheticOracle

    syn = oracle.section.synthetic
    section = oracle.section.model_copy(update={"synthetic": syn.model_copy(update={
        "max_gsd_m": syn.max_gsd_m * shrink, "keypoints_per_mpx": syn.keypoints_per_mpx * shrink ** 2})})
    return SyntheticOracle(section)


def colmap_equivalent(oracle, capture_set: CaptureSet, mesh: trimesh.Trimesh, n_points: int, width_px: int,
                      seed: int = 0) -> dict[str, float]:
    """The synthetic ``oracle``'s figures under COLMAP's conditions (module docstring): ``width_error_m`` /
    ``width_completeness`` (dense, at ``width_px``) and ``sparse_error_m`` / ``sparse_completeness`` /
    ``sparse_hole_part_m`` (thinned to ``n_points``)."""
    gt = oracle.ground_truth(mesh)
    small = _at_render_width(oracle, capture_set.camera.image_width_px / width_px)
    fused, _, _, _ = small.reconstruct(in_plan_order(at_width(capture_set, width_px))[0], gt, seed)
    dense = fused.score(gt, small.section, seed)
    out = {"width_error_m": dense.error_m, "width_completeness": dense.completeness}
    present = np.flatnonzero(fused.existence > 0)
    count = int(min(n_points, len(present)))
    if count < 5:
        return {**out, "sparse_error_m": float("nan"), "sparse_completeness": 0.0, "sparse_hole_part_m": float("nan")}
    weights = fused.existence[present] / fused.existence[present].sum()
    chosen = np.random.default_rng(seed).choice(present, count, replace=False, p=weights)
    sparse = sparse_surfels(fused.estimates[np.sort(chosen)]).score(gt, oracle.section, seed)
    return {**out, "sparse_error_m": sparse.error_m, "sparse_completeness": sparse.completeness,
            "sparse_hole_part_m": sparse.hole_part_m}
