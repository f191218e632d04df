"""Shared fixtures of the recon tests: small meshes and camera rings built here, known by construction."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.recon.config import OracleSection, SyntheticOracleSection
from wrp_eval.sim.captures import CaptureSet


def make_box(extents, center) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=extents)
    box.apply_translation(center)
    return box


def ring_views(center, radius: float, heights, per_ring: int, target=None, phase: float = 0.0,
               camera: Camera = Camera()) -> CaptureSet:
    """Cameras on horizontal circles of ``radius`` around ``center``, each looking at ``target``
    (default: the centre)."""
    center = np.asarray(center, dtype=float)
    target = center if target is None else np.asarray(target, dtype=float)
    t = 2 * np.pi * (np.arange(per_ring) + phase) / per_ring
    pos = np.concatenate([np.column_stack([center[0] + radius * np.cos(t), center[1] + radius * np.sin(t),
                                           np.full(per_ring, h)]) for h in heights])
    yaw, pitch = yaw_pitch_towards(pos, np.broadcast_to(target, pos.shape))
    return CaptureSet(pos, yaw, pitch, np.arange(len(pos)), camera)


@pytest.fixture
def box_on_water() -> trimesh.Trimesh:
    """A 10 x 6 x 6 m box from z = -2 (below the waterline) to z = 4."""
    return make_box((10.0, 6.0, 6.0), (0.0, 0.0, 1.0))


@pytest.fixture
def hull_with_house() -> trimesh.Trimesh:
    """A hull-like prism (keel below the water) with a deckhouse box standing on its deck."""
    hull = trimesh.creation.box(extents=(30.0, 8.0, 6.0))
    hull.apply_translation((0.0, 0.0, 1.0))  # z in [-2, 4]
    house = make_box((6.0, 6.0, 5.0), (-8.0, 0.0, 6.5))  # z in [4, 9]
    return trimesh.util.concatenate([hull, house])


@pytest.fixture
def fast_section() -> OracleSection:
    """Default oracle with a coarser ray grid, to keep unit tests fast."""
    return OracleSection(synthetic=SyntheticOracleSection(rays_x=40, rays_y=27))
