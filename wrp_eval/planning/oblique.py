"""Oblique-photography baseline (paper Sec. 5.4, Table 8): five single-camera sub-paths - nadir plus four
oblique cameras (forward, backward, port, starboard) - flown as lawnmower patterns at one fixed altitude.

Altitude = proxy height + planned distance (the deck is photographed at the planned GSD). Spacing from the
footprint at that distance, the standard flight-plan computation (Wolf, Dewitt & Wilkinson, *Elements of
Photogrammetry*, Ch. 18 "Project Planning"): flight-line spacing = footprint width x (1 - side overlap), photo
spacing = footprint length x (1 - front overlap); the image's long side lies across the track. Flight
lines run along the ship (x). The nadir grid covers the proxy's deck rectangle; an oblique camera looking
along horizontal direction d with depression angle p aims at mid-height, so its grid is the nadir grid
shifted by -(altitude - H/2) / tan(p) along d. Sub-paths are flown boustrophedon, one after the other,
each entered from its end nearer to where the previous one finished.
"""

from __future__ import annotations

import numpy as np

from wrp_eval.camera import Camera
from wrp_eval.planning.views import make_safe
from wrp_eval.ship.proxy import Proxy

# (yaw of the camera, the face it photographs): a camera looking +x sees the stern face (normal -x) etc.
_OBLIQUE_CAMERAS = ((0.0, 1), (np.pi, 0), (np.pi / 2, 3), (-np.pi / 2, 2))
NADIR_FACE = 4


def _axis_stations(extent: float, spacing: float) -> np.ndarray:
    """Evenly spaced stations covering [-extent/2, extent/2] no further apart than ``spacing``."""
    n = int(np.ceil(extent / spacing)) + 1 if extent > 0 else 1
    return np.linspace(-extent / 2, extent / 2, n) if n > 1 else np.zeros(1)


def lawnmower(xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Boustrophedon grid (len(xs) * len(ys), 2): lines along x at each y, alternating direction."""
    gx = np.tile(xs, (len(ys), 1))
    gx[1::2] = gx[1::2, ::-1]
    return np.stack([gx.ravel(), np.repeat(ys, len(xs))], axis=1)


def oblique_views(proxy: Proxy, camera: Camera, distance_m: float, pitch_deg: float, front_overlap: float,
                  side_overlap: float, min_altitude_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                          np.ndarray]:
    """(positions (n, 3), yaw (n,), pitch (n,), face (n,)) of the five sub-paths in flight order."""
    altitude = proxy.height_m + distance_m
    width, length = camera.footprint_m(distance_m)
    line_spacing = width * (1.0 - side_overlap)
    photo_spacing = length * (1.0 - front_overlap)
    grid = lawnmower(_axis_stations(proxy.length_m, photo_spacing), _axis_stations(proxy.breadth_m, line_spacing))
    depression = np.radians(pitch_deg)
    offset = (altitude - proxy.height_m / 2) / np.tan(depression)
    subpaths = [(grid, 0.0, -np.pi / 2, NADIR_FACE)]
    for yaw, face in _OBLIQUE_CAMERAS:
        shift = -offset * np.array([np.cos(yaw), np.sin(yaw)])
        subpaths.append((grid + shift, yaw, -depression, face))
    positions, yaws, pitches, faces = [], [], [], []
    last = None
    for xy, yaw, pitch, face in subpaths:
        pts = np.column_stack([xy, np.full(len(xy), altitude)])
        if last is not None and np.linalg.norm(pts[-1] - last) < np.linalg.norm(pts[0] - last):
            pts = pts[::-1]
        positions.append(pts)
        yaws.append(np.full(len(pts), yaw))
        pitches.append(np.full(len(pts), pitch))
        faces.append(np.full(len(pts), face))
        last = pts[-1]
    pos = np.concatenate(positions)
    anchors = pos.copy()
    anchors[:, 2] = proxy.height_m / 2
    pos = make_safe(pos, anchors, proxy, min_altitude_m)
    return pos, np.concatenate(yaws), np.concatenate(pitches), np.concatenate(faces)
