"""Known-by-construction scenes for the oracles' tests, bench and validation.

``ship_like_mesh``: a box hull (keel below the waterline) with a deckhouse and a funnel, 140 x 20 x 25 m
above the water by default (the paper's reference ship, Sec. 5.1), used until / unless the ship stage's
procedural mesh is available. ``orbit_capture_set``: cameras on rings around a box-shaped object, each
looking at the nearest point of the object's axis, the shape of a well-planned oblique-photography path.
"""

from __future__ import annotations

from typing import cast

import numpy as np
import trimesh

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.sim.captures import CaptureSet


def ship_like_mesh(length_m: float = 140.0, breadth_m: float = 20.0, height_m: float = 25.0,
                   freeboard_m: float = 10.0, draft_m: float = 8.0) -> trimesh.Trimesh:
    """A hull box from -draft to freeboard plus a deckhouse and a funnel reaching ``height_m``."""
    hull = trimesh.creation.box(extents=(length_m, breadth_m, freeboard_m + draft_m))
    hull.apply_translation((0.0, 0.0, (freeboard_m - draft_m) / 2))
    # a pointed bow: a triangular prism ahead of the box
    bow_len = 0.12 * length_m
    x0 = length_m / 2
    b = breadth_m / 2
    z0, z1 = -draft_m, freeboard_m
    bow_v = np.array([[x0, -b, z0], [x0, b, z0], [x0 + bow_len, 0, z0],
                      [x0, -b, z1], [x0, b, z1], [x0 + bow_len, 0, z1]])
    bow_f = np.array([[0, 2, 1], [3, 4, 5], [0, 3, 5], [0, 5, 2], [1, 2, 5], [1, 5, 4], [0, 1, 4], [0, 4, 3]])
    bow = trimesh.Trimesh(bow_v, bow_f, process=True)
    bow.fix_normals()
    house_h = height_m - freeboard_m
    house = trimesh.creation.box(extents=(0.18 * length_m, 0.8 * breadth_m, house_h))
    house.apply_translation((-0.3 * length_m, 0.0, freeboard_m + house_h / 2))
    funnel = trimesh.creation.box(extents=(0.05 * length_m, 0.25 * breadth_m, 0.6 * house_h))
    funnel.apply_translation((-0.12 * length_m, 0.0, freeboard_m + 0.3 * house_h))
    # move the whole ship so that its length above water is centred on x = 0
    mesh = cast(trimesh.Trimesh, trimesh.util.concatenate([hull, bow, house, funnel]))
    mesh.apply_translation((-bow_len / 2, 0.0, 0.0))
    return mesh


def orbit_capture_set(half_length_m: float, half_breadth_m: float, target_z_m: float, standoff_m: float,
                      heights_m: tuple[float, ...], views_per_ring: int,
                      camera: Camera = Camera(), phase: float = 0.0) -> CaptureSet:
    """Rings of cameras around a box-like object (an ellipse ``standoff_m`` outside its half-extents).

    Each camera looks at the nearest point of the object's long axis (x in +-half_length, y = 0) at
    ``target_z_m``. Views are ordered ring by ring; ``planned_index`` numbers them.
    """
    t = 2 * np.pi * (np.arange(views_per_ring) + phase) / views_per_ring
    a, b = half_length_m + standoff_m, half_breadth_m + standoff_m
    ring = np.stack([a * np.cos(t), b * np.sin(t)], axis=1)
    positions = np.concatenate([np.column_stack([ring, np.full(views_per_ring, h)]) for h in heights_m])
    targets = np.column_stack([np.clip(positions[:, 0], -half_length_m, half_length_m),
                               np.zeros(len(positions)), np.full(len(positions), target_z_m)])
    yaw, pitch = yaw_pitch_towards(positions, targets)
    return CaptureSet(positions, yaw, pitch, np.arange(len(positions)), camera)


def reference_capture_set(views: int = 50, standoff_m: float = 40.0, camera: Camera = Camera()) -> CaptureSet:
    """A 50-view oblique capture set around the reference ship: two rings of ``views // 2``."""
    per_ring = views // 2
    return orbit_capture_set(70.0, 10.0, 8.0, standoff_m, (12.0, 40.0), per_ring, camera)
