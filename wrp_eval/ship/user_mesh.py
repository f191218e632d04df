"""User ship meshes (STL, OBJ, PLY, GLB/GLTF): load, place in the ship frame, check against the particulars."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from wrp_eval.errors import InputError
from wrp_eval.ship.particulars import ShipParticulars

SUPPORTED_SUFFIXES = (".stl", ".obj", ".ply", ".glb", ".gltf", ".off")
MAX_RELATIVE_DEVIATION = 0.30  # a mesh further than this from the particulars is probably mis-scaled

# rotations taking the file's up axis onto +z (right-handed, x stays the ship's length where possible)
_UP_ROTATIONS = {
    "z": np.eye(3),
    "y": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),    # +90 deg about x: +y -> +z
    "x": np.array([[0.0, 0, -1], [0, 1, 0], [1, 0, 0]]),    # -90 deg about y: +x -> +z
}


def load_user_mesh(path: str | Path, scale: float = 1.0, up_axis: str = "z",
                   offset_m=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """Load ``path``, rotate its up axis onto +z, scale, then add ``offset_m`` (metres).

    Raises :class:`InputError` for a missing, unreadable, empty or non-finite mesh.
    """
    path = Path(path)
    if up_axis not in _UP_ROTATIONS:
        raise InputError(path, f"up_axis must be one of z, y, x, got {up_axis!r}")
    if path.suffix.lower() not in SUPPORTED_SUFFIXES:
        raise InputError(path, f"unsupported mesh format {path.suffix!r} (use {', '.join(SUPPORTED_SUFFIXES)})")
    if not path.is_file():
        raise InputError(path, "no such mesh file")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as err:  # trimesh raises many types for malformed files
        raise InputError(path, f"cannot read mesh: {type(err).__name__}: {err}") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise InputError(path, "the mesh has no triangles")
    vertices = np.asarray(loaded.vertices, dtype=float)
    if not np.isfinite(vertices).all():
        raise InputError(path, "the mesh has non-finite vertex coordinates (nan or inf)")
    vertices = vertices @ _UP_ROTATIONS[up_axis].T * float(scale) + np.asarray(offset_m, dtype=float)
    return trimesh.Trimesh(vertices, np.asarray(loaded.faces), process=False)


def check_mesh_against_particulars(mesh: trimesh.Trimesh, particulars: ShipParticulars, source: str | Path,
                                   tolerance: float = MAX_RELATIVE_DEVIATION) -> None:
    """Refuse a mesh whose length, breadth or height above water differs from the particulars by more than
    ``tolerance`` (relative): usually a wrong scale, up axis or offset."""
    lo, hi = mesh.bounds
    measured = {"length (x extent)": (hi[0] - lo[0], particulars.length_bp_m),
                "breadth (y extent)": (hi[1] - lo[1], particulars.breadth_m),
                "height above water (max z)": (hi[2], particulars.height_above_water_m)}
    for what, (have, want) in measured.items():
        if not abs(have - want) <= tolerance * want:
            raise InputError(source, f"mesh {what} is {have:.4g} m but the particulars say {want:.4g} m "
                                     f"(more than {tolerance:.0%} off): check scale, up_axis and offset_m")
