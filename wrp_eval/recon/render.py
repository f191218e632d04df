"""Offscreen images of the textured ship at the capture poses, for the photogrammetric oracle.

The renderer ray-casts every pixel centre with open3d's ``RaycastingScene`` (the same occluder scene as
the synthetic oracle: ship + sea plane) and shades the hits with a *solid* procedural texture: fractal
value noise evaluated at the 3-D hit point (Perlin 1985, "An image synthesizer", solid textures). A solid
texture needs no UV atlas and never repeats across the hull, so SIFT finds many distinctive features and,
unlike a tiled 2-D texture, makes no false matches between, e.g., port and starboard. The sea is a flat,
featureless colour (its real texture moves between photos and yields no stable matches); the sky is grey.
MuJoCo's OSMesa renderer also works on this machine, but a mesh needs per-vertex UVs there and a tiled
texture; ray casting was the simpler faithful choice.

Motion blur (``CaptureSet.blur_px``, the smear during the exposure in pixels of the capture camera): each
blurred view's image is convolved with a linear motion-blur kernel (:func:`motion_blur_kernel`, a normalised
line segment) of the view's blur scaled to the render width (``blur_px * width_px / camera.image_width_px``).
*Choice:* the smear is horizontal (along image rows): the drone's translation past the ship and its yaw, the
motions the simulator's blur comes from, move the image mostly sideways; the true direction is not recorded.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import convolve1d

from wrp_eval.camera import Camera, world_rays
from wrp_eval.open3d_arrays import o3d_tensor
from wrp_eval.recon.oracle import GroundTruth
from wrp_eval.sim.captures import CaptureSet

SEA_RGB = np.array([0.10, 0.20, 0.30])
SKY_RGB = np.array([0.78, 0.80, 0.83])
SUN_DIRECTION = np.array([0.35, 0.25, 0.9]) / np.linalg.norm([0.35, 0.25, 0.9])
_LATTICE = 64  # random lattice per octave: 64^3 values (periods are incommensurate across octaves)


class SolidTexture:
    """Fractal value noise in 3-D: ``albedo(points (m, 3)) -> (m, 3)`` RGB in [0, 1].

    ``cell_m``: lattice spacing of each octave (finest first); each octave has its own random lattice and
    a random rotation (no axis-aligned streaks); seeded.
    """

    def __init__(self, seed: int = 0, cell_m: tuple[float, ...] = (0.18, 0.6, 2.0)):
        rng = np.random.default_rng(seed)
        self.cell_m = cell_m
        self.lattices = rng.random((len(cell_m), _LATTICE, _LATTICE, _LATTICE), dtype=np.float32)
        q, _ = np.linalg.qr(rng.standard_normal((len(cell_m), 3, 3)))
        self.rotations = q
        self.tint = rng.uniform(0.6, 1.0, size=(len(cell_m), 3))

    def albedo(self, points: np.ndarray) -> np.ndarray:
        out = np.zeros((len(points), 3))
        weight_sum = 0.0
        for k, cell in enumerate(self.cell_m):  # a handful of octaves, each vectorised over all points
            x = ((points @ self.rotations[k].T) / cell).astype(np.float32)
            base = np.floor(x)
            frac = x - base
            w = frac * frac * (3 - 2 * frac)  # smoothstep interpolation weights
            i0 = base.astype(np.int64) % _LATTICE
            i1 = (i0 + 1) % _LATTICE
            lat = self.lattices[k].ravel()
            v = np.zeros(len(points), dtype=np.float32)
            for cx, wx in ((i0[:, 0], 1 - w[:, 0]), (i1[:, 0], w[:, 0])):
                for cy, wy in ((i0[:, 1], 1 - w[:, 1]), (i1[:, 1], w[:, 1])):
                    row = (cx * _LATTICE + cy) * _LATTICE
                    wxy = wx * wy
                    v += wxy * ((1 - w[:, 2]) * lat[row + i0[:, 2]] + w[:, 2] * lat[row + i1[:, 2]])
            amp = 1.0 / (k + 1)
            # contrast-stretched octave (value noise alone is grey-ish), tinted per octave
            out += amp * np.clip(1.8 * (v - 0.5) + 0.5, 0, 1)[:, None] * self.tint[k]
            weight_sum += amp
        return out / weight_sum


def motion_blur_kernel(length_px: float) -> np.ndarray:
    """A linear motion-blur kernel: the normalised box of a line segment ``length_px`` long centred on the
    pixel, each tap weighted by the length of the segment inside that pixel (so a sub-pixel length is handled
    by the end taps: 2 px -> [0.25, 0.5, 0.25], 3 px -> [1/3, 1/3, 1/3]); sums to 1, odd length, symmetric.
    A length <= 1 px lies inside one pixel: [1.0] (no blur)."""
    half = max(float(length_px), 1.0) / 2.0
    m = int(np.ceil(half - 0.5))
    k = np.arange(-m, m + 1, dtype=float)
    weights = np.clip(np.minimum(k + 0.5, half) - np.maximum(k - 0.5, -half), 0.0, None)
    return weights / weights.sum()


def motion_blur(image: np.ndarray, length_px: float) -> np.ndarray:
    """``image`` (h, w, c) or (h, w) uint8 smeared horizontally (along its rows) by a linear motion blur of
    ``length_px`` render pixels (:func:`motion_blur_kernel`; edges repeat the border pixel); the input itself
    when the kernel is a single tap."""
    kernel = motion_blur_kernel(length_px)
    if len(kernel) == 1:
        return image
    out = convolve1d(image.astype(np.float32), kernel.astype(np.float32), axis=1, mode="nearest")
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def render_blur_px(capture_set: CaptureSet, width_px: int) -> np.ndarray:
    """(n,) the views' motion blur in render pixels: ``blur_px`` of the capture camera scaled to ``width_px``."""
    return capture_set.blur() * width_px / capture_set.camera.image_width_px


def render_views(capture_set: CaptureSet, gt: GroundTruth, width_px: int, texture: SolidTexture,
                 max_rays_per_call: int = 2_000_000) -> tuple[np.ndarray, Camera]:
    """RGB images (n, h, w, 3) uint8 of every capture pose, and the camera they were rendered with.

    The capture camera's field of view is kept; the image is scaled to ``width_px`` (height in proportion).
    A view with motion blur (``capture_set.blur_px`` > 0) is smeared horizontally by its blur scaled to the
    render width (:func:`render_blur_px`, :func:`motion_blur`; module docstring).
    """
    cam = capture_set.camera
    height_px = int(round(width_px * cam.image_height_px / cam.image_width_px))
    render_cam = Camera(cam.focal_mm, cam.sensor_width_mm, width_px, height_px)
    f = render_cam.focal_px
    u = np.arange(width_px) + 0.5
    v = np.arange(height_px) + 0.5
    uu, vv = np.meshgrid(u, v)
    cam_dirs = np.stack([(uu - width_px / 2) / f, (vv - height_px / 2) / f, np.ones_like(uu)], axis=-1)
    cam_dirs = (cam_dirs / np.linalg.norm(cam_dirs, axis=-1, keepdims=True)).reshape(-1, 3)
    rot = capture_set.rotations()  # roll included: a rolled camera renders a rotated image
    n = len(capture_set)
    images = np.zeros((n, height_px, width_px, 3), dtype=np.uint8)
    per_call = max(1, max_rays_per_call // len(cam_dirs))
    for start in range(0, n, per_call):  # chunks of views, each one batched ray cast
        views = np.arange(start, min(n, start + per_call))
        dirs = world_rays(rot[views], cam_dirs).reshape(-1, 3)
        origins = np.repeat(np.asarray(capture_set.positions, dtype=float)[views], len(cam_dirs), axis=0)
        ans = gt.occluder_scene.cast_rays(o3d_tensor(np.concatenate([origins, dirs], 1).astype(np.float32)))
        t_hit = ans["t_hit"].numpy().astype(np.float64)
        gid = ans["geometry_ids"].numpy()
        normals = ans["primitive_normals"].numpy().astype(np.float64)
        rgb = np.tile(SKY_RGB, (len(dirs), 1))
        sea = np.isfinite(t_hit) & (gid != gt.ship_geometry_id)
        rgb[sea] = SEA_RGB
        ship = np.flatnonzero(gid == gt.ship_geometry_id)
        p = origins[ship] + dirs[ship] * t_hit[ship, None]
        nrm = normals[ship] * np.where(np.einsum("kj,kj->k", normals[ship], dirs[ship]) > 0, -1.0, 1.0)[:, None]
        shade = 0.45 + 0.55 * np.clip(nrm @ SUN_DIRECTION, 0, 1)
        rgb[ship] = texture.albedo(p) * shade[:, None]
        images[views] = np.clip(255 * rgb, 0, 255).astype(np.uint8).reshape(len(views), height_px, width_px, 3)
    for i, length in enumerate(render_blur_px(capture_set, width_px)):
        if length > 0:
            images[i] = motion_blur(images[i], length)
    return images, render_cam
