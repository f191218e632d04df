"""Candidate viewpoints (Zhou et al. 2020 style, paper Sec. 3.1) and the safety constraints on every view.

Each sample s with normal n gets a view at s + D n looking back at s (the "normal" candidate). Zhou et al.
generate several orientations per sample; we add ``n_tilts`` tilted candidates at the same distance on
the directions cos(t) n +- sin(t) v (and +- sin(t) u when n_tilts = 4), still looking at s. Minimisation
starts from the normal candidates only; the tilted ones are the replacement pool of the maximisation.

Safety (paper Sec. 3.1): a view lower than ``min_altitude_m`` is lifted to it, a view inside the no-fly box
is pushed out along its own direction from the sample, both keep looking at their sample; views the
gimbal cannot point (pitch above +30 deg) are dropped. "Inside" and "flyable" are the ship stage's one
no-fly geometry (:mod:`wrp_eval.ship.nofly`: an open box, touching it is not an intrusion).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.camera import yaw_pitch_towards
from wrp_eval.planning.sampling import Samples
from wrp_eval.ship.nofly import flyable, inside_no_fly_box
from wrp_eval.ship.proxy import Proxy

GIMBAL_MAX_PITCH = np.radians(30.0)  # DJI-class gimbals reach about +30 deg up
_PUSH_CLEARANCE_M = 0.5               # how far outside the no-fly box a pushed view lands


@dataclass(frozen=True)
class ViewSet:
    """Viewpoints: positions (n, 3) m, yaw/pitch (n,) rad, face (n,) int, sample (n,) int index into the
    sample set that generated the view (-1 for none), tilt (n,) int (0 = along the normal)."""

    positions: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    face: np.ndarray
    sample: np.ndarray
    tilt: np.ndarray

    def __len__(self) -> int:
        return int(self.positions.shape[0])

    def subset(self, index: np.ndarray) -> "ViewSet":
        return ViewSet(self.positions[index], self.yaw[index], self.pitch[index], self.face[index],
                       self.sample[index], self.tilt[index])


def exit_distance(origins: np.ndarray, directions: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Distance (n,) along unit ``directions`` from ``origins`` (inside or on ``box`` (2, 3)) to leave it."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t_hi = (box[1] - origins) / directions
        t_lo = (box[0] - origins) / directions
    t_axis = np.where(directions > 0, t_hi, np.where(directions < 0, t_lo, np.inf))
    return np.maximum(np.min(t_axis, axis=1), 0.0)


def make_safe(positions: np.ndarray, anchors: np.ndarray, proxy: Proxy, min_altitude_m: float) -> np.ndarray:
    """Lift views below ``min_altitude_m`` and push views out of the no-fly box (returns new positions).

    A view inside the box moves along the ray anchor -> view until it is ``_PUSH_CLEARANCE_M`` outside; the
    anchor is the point it looks at (a sample, or the proxy axis for transition views).
    """
    pos = np.array(positions, dtype=float, copy=True)
    pos[:, 2] = np.maximum(pos[:, 2], min_altitude_m)
    box = proxy.no_fly_bounds()
    inside = inside_no_fly_box(pos, box)
    if np.any(inside):
        box = box + np.array([[-1.0, -1.0, -np.inf], [1.0, 1.0, 1.0]]) * _PUSH_CLEARANCE_M
        d = pos[inside] - anchors[inside]
        norm = np.linalg.norm(d, axis=1, keepdims=True)
        d = np.where(norm > 1e-9, d / np.maximum(norm, 1e-9), np.array([0.0, 0.0, 1.0]))
        start = np.clip(anchors[inside], box[0], box[1])
        pos[inside] = start + exit_distance(start, d, box)[:, None] * d
        pos[:, 2] = np.maximum(pos[:, 2], min_altitude_m)
    return pos


def candidate_views(samples: Samples, proxy: Proxy, distance_m: float, *, tilt_rad: float, n_tilts: int,
                    min_altitude_m: float) -> ViewSet:
    """All candidates, normal ones first (index i = sample i when none was dropped), then the tilted ones."""
    n = len(samples)
    face_u = proxy.u_axes[samples.face]
    face_v = proxy.v_axes[samples.face]
    dirs = [samples.normals]
    if n_tilts:
        c, s = np.cos(tilt_rad), np.sin(tilt_rad)
        dirs += [c * samples.normals + s * face_v, c * samples.normals - s * face_v]
        if n_tilts == 4:
            dirs += [c * samples.normals + s * face_u, c * samples.normals - s * face_u]
    directions = np.concatenate(dirs)
    anchors = np.tile(samples.points, (len(dirs), 1))
    positions = make_safe(anchors + distance_m * directions, anchors, proxy, min_altitude_m)
    yaw, pitch = yaw_pitch_towards(positions, anchors)
    keep = (pitch <= GIMBAL_MAX_PITCH) & flyable(positions, proxy.no_fly_bounds(), min_altitude_m)
    tilt = np.repeat(np.arange(len(dirs)), n)
    sample = np.tile(np.arange(n), len(dirs))
    face = np.tile(samples.face, len(dirs))
    return ViewSet(positions[keep], yaw[keep], pitch[keep], face[keep], sample[keep], tilt[keep])
