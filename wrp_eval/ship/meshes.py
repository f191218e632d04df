"""Procedural ship meshes: a Wigley hull plus type-specific superstructure, and their on-disk cache.

Frame: x along the ship (bow +x), y to port, z up, waterline z = 0, keel at z = -draft. The hull spans
x in [-L/2, L/2] and |y| <= B/2 exactly, and the highest part reaches freeboard + superstructure height, so
the mesh matches the particulars and the proxy.

Hull form: the Wigley hull (Wigley 1934; the standard test hull of ITTC resistance/seakeeping comparisons),
half-breadth y = B/2 (1 - (2x/L)^2) (1 - (z/T)^2) below the waterline; above it the sides are continued wall-
sided, y = B/2 (1 - (2x/L)^2), up to the main deck at z = D - T.

The mesh is the union (concatenation, no booleans) of closed, outward-oriented parts: the hull and boxes /
cylinders / capsules for decks, bridge, funnel, masts, container stacks, cranes and gantries. Every part is
watertight, so the whole is watertight and consistently oriented (parts may overlap; for surface complexity
and ray casting this is harmless). Tessellation is fixed per part (not per metre), so a ship's triangle count
reflects how much detail it has, which is what the paper's surface complexity (eq. 3) counts.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import cast

import numpy as np
import trimesh

from wrp_eval import resources
from wrp_eval.atomic import atomic_path
from wrp_eval.ship.particulars import ShipParticulars, ShipType

GENERATOR_VERSION = 1  # bump when the geometry changes: it is part of the cache key
HULL_SECTIONS = 48     # stations along x
HULL_LEVELS = 12       # levels from keel to deck


# ---------------------------------------------------------------- primitives (vectorised, watertight)

_UNIT_BOX = trimesh.creation.box()
_BOX_VERTS = np.asarray(_UNIT_BOX.vertices) + 0.5   # (8, 3) corners in {0, 1}
_BOX_FACES = np.asarray(_UNIT_BOX.faces)            # (12, 3) outward


def boxes(lows: np.ndarray, highs: np.ndarray) -> trimesh.Trimesh:
    """Axis-aligned boxes (n, 3) lows/highs as one mesh of n closed, outward-oriented boxes."""
    lows = np.atleast_2d(np.asarray(lows, dtype=float))
    highs = np.atleast_2d(np.asarray(highs, dtype=float))
    verts = lows[:, None, :] + _BOX_VERTS[None] * (highs - lows)[:, None, :]
    faces = _BOX_FACES[None] + 8 * np.arange(len(lows))[:, None, None]
    return trimesh.Trimesh(verts.reshape(-1, 3), faces.reshape(-1, 3), process=False)


def cylinder(p0, p1, radius: float, sections: int = 16) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(radius=radius, segment=np.array([p0, p1], dtype=float), sections=sections)


def capsule_x(center, length: float, radius: float) -> trimesh.Trimesh:
    """A capsule (lifeboat-like) lying along x."""
    mesh = trimesh.creation.capsule(height=length, radius=radius, count=[8, 8])
    mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    mesh.apply_translation(center)
    return mesh


def wigley_hull(length: float, breadth: float, draft: float, freeboard: float,
                sections: int = HULL_SECTIONS, levels: int = HULL_LEVELS) -> trimesh.Trimesh:
    """Closed Wigley hull from the keel (z = -draft) to a flat main deck (z = freeboard).

    Port and starboard sides share the vertices on the centre plane (keel, stem, sternpost), and the deck
    closes the top, so the surface is watertight.
    """
    xi = np.linspace(-1.0, 1.0, sections + 1)                   # 2x/L
    below = np.linspace(-1.0, 0.0, levels + 1)                  # z/T, keel to waterline
    above = np.linspace(0.0, 1.0, max(2, levels // 3) + 1)[1:]  # wall-sided part up to the deck
    z = np.concatenate([below * draft, above * freeboard])
    depth_factor = np.where(z < 0, 1.0 - (z / draft) ** 2, 1.0)
    half = 0.5 * breadth * (1.0 - xi[:, None] ** 2) * depth_factor[None, :]   # (nx, nz)
    x = xi * length / 2
    nx, nz = half.shape
    on_centre = half <= 1e-12
    # vertex ids: port grid, then starboard only where off the centre plane
    port_ids = np.arange(nx * nz).reshape(nx, nz)
    stbd_ids = port_ids.copy()
    off = ~on_centre
    stbd_ids[off] = nx * nz + np.arange(off.sum())
    xx, zz = np.meshgrid(x, z, indexing="ij")
    verts = np.concatenate([np.stack([xx, half, zz], -1).reshape(-1, 3),
                            np.stack([xx[off], -half[off], zz[off]], -1)])

    def grid_faces(ids: np.ndarray, flip: bool) -> np.ndarray:
        a, b, c, d = ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]
        tris = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
        return tris[:, ::-1] if flip else tris

    top_port, top_stbd = port_ids[:, -1], stbd_ids[:, -1]
    deck = np.concatenate([np.stack([top_port[:-1], top_stbd[:-1], top_stbd[1:]], -1),
                           np.stack([top_port[:-1], top_stbd[1:], top_port[1:]], -1)])
    faces = np.concatenate([grid_faces(port_ids, True), grid_faces(stbd_ids, False), deck])  # outward
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
    # a triangle with all three corners on the centre plane (at the keel/stem corners) has zero area and
    # would be emitted once per side: drop it (its edges are then shared by exactly two real triangles)
    centre_vertex = np.zeros(len(verts), dtype=bool)
    centre_vertex[port_ids[on_centre]] = True
    faces = faces[~centre_vertex[faces].all(axis=1)]
    hull = trimesh.Trimesh(verts, faces, process=False)
    hull.remove_unreferenced_vertices()
    if hull.volume < 0:
        hull.invert()
    return hull


class _Builder:
    """Collects parts on the deck of a hull of length L, breadth B, freeboard F, top at F + H."""

    def __init__(self, p: ShipParticulars):
        self.L, self.B = p.length_bp_m, p.breadth_m
        self.F, self.H = p.freeboard_m, p.superstructure_height_m
        self.top = self.F + self.H
        self.parts = [wigley_hull(self.L, self.B, p.draft_m, self.F)]
        self._box_lo: list[np.ndarray] = []
        self._box_hi: list[np.ndarray] = []

    def half_breadth(self, x: float) -> float:
        return 0.5 * self.B * (1.0 - (2.0 * x / self.L) ** 2)

    def deck_box(self, x0f: float, x1f: float, width: float, z0f: float, z1f: float, y_center: float = 0.0):
        """Box from x0f*L to x1f*L, half-width = width * hull half-breadth (at the narrower end),
        from z0f*H to z1f*H above the deck."""
        x0, x1 = x0f * self.L, x1f * self.L
        hw = width * min(self.half_breadth(x0), self.half_breadth(x1))
        self.box([x0, y_center - hw, self.F + z0f * self.H], [x1, y_center + hw, self.F + z1f * self.H])

    def box(self, lo, hi):
        self._box_lo.append(np.asarray(lo, float))
        self._box_hi.append(np.asarray(hi, float))

    def mast(self, xf: float, z0f: float, z1f: float, radius: float, sections: int = 12, y: float = 0.0):
        x = xf * self.L
        self.parts.append(cylinder([x, y, self.F + z0f * self.H], [x, y, self.F + z1f * self.H], radius, sections))

    def mesh(self) -> trimesh.Trimesh:
        if self._box_lo:
            self.parts.append(boxes(np.array(self._box_lo), np.array(self._box_hi)))
        mesh = cast(trimesh.Trimesh, trimesh.util.concatenate(self.parts))
        return trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)


def _stylized(b: _Builder) -> None:
    b.deck_box(0.36, 0.47, 0.9, 0.0, 0.12)                    # forecastle
    for x0 in (-0.12, 0.02, 0.16):                            # cargo hatches
        b.deck_box(x0, x0 + 0.11, 0.75, 0.0, 0.06)
    b.deck_box(-0.44, -0.18, 0.85, 0.0, 0.35)                 # deckhouse
    b.deck_box(-0.40, -0.22, 0.80, 0.35, 0.50)
    b.deck_box(-0.30, -0.22, 1.00, 0.50, 0.62)                # bridge with wings
    b.mast(-0.36, 0.35, 0.82, 0.06 * b.B, 20)                 # funnel
    b.mast(-0.26, 0.62, 1.00, 0.015 * b.B + 0.1)              # main mast: the top
    b.mast(0.40, 0.12, 0.55, 0.01 * b.B + 0.1)                # foremast


def _cruise(b: _Builder) -> None:
    n_decks = 10
    deck_h = 0.82 / n_decks
    for k in range(n_decks):                                  # terraced passenger decks
        b.deck_box(-0.44 + 0.012 * k, 0.36 - 0.018 * k, 0.86, k * deck_h, (k + 1) * deck_h)
    b.deck_box(0.20, 0.26, 1.0, 0.60, 0.68)                   # bridge with wings
    for side in (1.0, -1.0):                                  # lifeboats along both sides
        for k in range(10):
            x = (-0.30 + 0.05 * k) * b.L
            y = side * 0.93 * b.half_breadth(x)
            b.parts.append(capsule_x([x, y, b.F + 0.22 * b.H], 0.02 * b.L, 0.025 * b.B))
    b.mast(-0.28, 0.82, 1.00, 0.07 * b.B, 24)                 # funnel: the top
    b.mast(0.18, 0.82, 0.95, 0.01 * b.B + 0.1)                # radar mast
    b.deck_box(-0.12, 0.02, 0.6, 0.82, 0.86)                  # pool / sports deck
    for k in range(6):                                        # deck furniture (slides, domes)
        b.mast(-0.10 + 0.02 * k, 0.86, 0.90, 0.02 * b.B, 12, y=(k % 3 - 1) * 0.2 * b.B)


def _container(b: _Builder) -> None:
    tower0, tower1 = -0.34, -0.27
    b.deck_box(tower0, tower1, 0.9, 0.0, 0.78)                # accommodation tower
    b.deck_box(tower0 + 0.01, tower1, 1.0, 0.78, 0.92)        # bridge with wings
    b.mast(tower0 + 0.035, 0.92, 1.00, 0.01 * b.B + 0.1)      # radar mast: the top
    b.mast(-0.40, 0.0, 0.55, 0.05 * b.B, 20)                  # funnel aft of the tower
    b.deck_box(0.42, 0.47, 0.9, 0.0, 0.15)                    # forecastle / breakwater
    # 40 ft containers (12.19 x 2.44 x 2.59 m) in bays between the funnel and the forecastle, 0.1 m gaps
    bay_len, width, tier_h, gap = 12.19, 2.44, 2.59, 0.1
    stack_top = 0.62 * b.H
    max_tiers = max(1, int(stack_top / (tier_h + gap)))
    xs = np.arange(-0.44 * b.L, 0.40 * b.L - bay_len, bay_len + gap)
    lo, hi = [], []
    for k, x0 in enumerate(xs):
        x1 = x0 + bay_len
        if x1 > tower0 * b.L - 1 and x0 < tower1 * b.L + 1 or x0 < -0.42 * b.L:
            continue
        hw = 0.92 * min(b.half_breadth(x0), b.half_breadth(x1))
        rows = int(2 * hw // (width + gap))
        tiers = max(1, max_tiers - (k * 7) % 3)              # deterministic uneven stack heights
        ys = (np.arange(rows) - (rows - 1) / 2) * (width + gap)
        zs = b.F + np.arange(tiers) * (tier_h + gap)
        yy, zz = np.meshgrid(ys, zs, indexing="ij")
        n = yy.size
        lo.append(np.stack([np.full(n, x0), yy.ravel() - width / 2, zz.ravel()], -1))
        hi.append(np.stack([np.full(n, x1), yy.ravel() + width / 2, zz.ravel() + tier_h], -1))
    if lo:
        b.parts.append(boxes(np.concatenate(lo), np.concatenate(hi)))


def _fishing(b: _Builder) -> None:
    b.deck_box(0.02, 0.26, 0.85, 0.0, 0.30)                   # wheelhouse block
    b.deck_box(0.08, 0.22, 0.75, 0.30, 0.45)                  # wheelhouse
    b.mast(0.14, 0.45, 1.00, 0.02 * b.B + 0.05)               # main mast: the top
    for side in (1.0, -1.0):                                  # outrigger booms (raised) and A-frame legs
        x = 0.14 * b.L
        b.parts.append(cylinder([x, 0.0, b.F + 0.5 * b.H], [x, side * 0.9 * b.half_breadth(x), b.F + 0.95 * b.H],
                                0.012 * b.B + 0.03, 8))
        xa = -0.46 * b.L
        ya = side * 0.75 * b.half_breadth(xa)
        b.box([xa - 0.2, ya - 0.15, b.F], [xa + 0.2, ya + 0.15, b.F + 0.7 * b.H])
    xa = -0.46 * b.L
    b.box([xa - 0.2, -0.75 * b.half_breadth(xa), b.F + 0.65 * b.H],
          [xa + 0.2, 0.75 * b.half_breadth(xa), b.F + 0.72 * b.H])      # A-frame gantry beam
    x = -0.25 * b.L                                           # net drum lying across the deck
    b.parts.append(cylinder([x, -0.6 * b.half_breadth(x), b.F + 0.12 * b.H],
                            [x, 0.6 * b.half_breadth(x), b.F + 0.12 * b.H], 0.1 * b.H, 16))
    b.mast(-0.05, 0.0, 0.55, 0.02 * b.B + 0.05)               # crane pillar and jib
    b.parts.append(cylinder([-0.05 * b.L, 0, b.F + 0.55 * b.H], [-0.2 * b.L, 0.3 * b.B, b.F + 0.4 * b.H],
                            0.015 * b.B + 0.03, 8))
    b.deck_box(-0.40, -0.30, 0.7, 0.0, 0.08)                  # fish hold hatch


def _tanker(b: _Builder) -> None:
    b.deck_box(-0.47, -0.34, 0.9, 0.0, 0.62)                  # accommodation block aft
    b.deck_box(-0.43, -0.36, 1.0, 0.62, 0.78)                 # bridge with wings
    b.mast(-0.45, 0.55, 1.00, 0.06 * b.B, 20)                 # funnel: the top
    b.mast(-0.40, 0.78, 0.95, 0.01 * b.B + 0.1)               # radar mast
    for y in (-0.06, 0.0, 0.06):                              # cargo pipes along the deck
        b.parts.append(cylinder([-0.32 * b.L, y * b.B, b.F + 0.6], [0.40 * b.L, y * b.B, b.F + 0.6], 0.35, 10))
    b.deck_box(-0.32, 0.42, 0.08, 0.12, 0.14, y_center=0.15 * b.B)  # catwalk
    for xf in (-0.05, 0.05):                                  # manifold cranes
        b.mast(xf, 0.0, 0.45, 0.01 * b.B + 0.2)
        b.parts.append(cylinder([xf * b.L, 0, b.F + 0.45 * b.H], [xf * b.L, 0.4 * b.B, b.F + 0.3 * b.H], 0.2, 8))
    b.deck_box(-0.02, 0.02, 0.9, 0.0, 0.06)                   # manifold platform
    b.deck_box(0.42, 0.47, 0.9, 0.0, 0.12)                    # forecastle
    b.mast(0.44, 0.12, 0.55, 0.01 * b.B + 0.1)                # foremast


_SUPERSTRUCTURE = {ShipType.STYLIZED: _stylized, ShipType.CRUISE: _cruise, ShipType.CONTAINER: _container,
                   ShipType.FISHING: _fishing, ShipType.TANKER: _tanker}


def procedural_mesh(particulars: ShipParticulars) -> trimesh.Trimesh:
    """The procedural mesh of ``particulars.ship_type`` sized to ``particulars`` (deterministic)."""
    builder = _Builder(particulars)
    _SUPERSTRUCTURE[particulars.ship_type](builder)
    return builder.mesh()


# ---------------------------------------------------------------- cache

def mesh_parameters(particulars: ShipParticulars) -> dict:
    """Everything the procedural geometry depends on (the cache key)."""
    p = particulars
    return {"generator": GENERATOR_VERSION, "type": p.ship_type.value, "hull": "wigley",
            "sections": HULL_SECTIONS, "levels": HULL_LEVELS,
            **{k: round(float(getattr(p, k)), 6) for k in
               ("length_bp_m", "breadth_m", "depth_m", "draft_m", "superstructure_height_m")}}


def default_cache_dir() -> Path:
    """``ships/`` of the user cache folder (:func:`wrp_eval.resources.cache_dir`: ``$WRP_EVAL_CACHE_DIR`` or
    the platform's user cache folder), never the source tree."""
    return resources.cache_dir("ships")


def cached_procedural_mesh(particulars: ShipParticulars, cache_dir: Path | None = None
                           ) -> tuple[trimesh.Trimesh, Path]:
    """Procedural mesh, read from / written to ``cache_dir`` (``<type>-<hash>.npz``: float64 vertices and
    int64 faces, so the cached mesh is bit-identical to a fresh one; PLY/STL would round to float32)."""
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    params = mesh_parameters(particulars)
    digest = hashlib.sha256(json.dumps(params, sort_keys=True).encode()).hexdigest()[:16]
    path = folder / f"{particulars.ship_type.value}-{digest}.npz"
    if path.exists():
        try:
            with np.load(path, allow_pickle=False) as data:
                mesh = trimesh.Trimesh(data["vertices"], data["faces"], process=False)
            if len(mesh.faces):
                return mesh, path
        except (OSError, ValueError, KeyError):  # a damaged cache file is simply rebuilt
            pass
    mesh = procedural_mesh(particulars)
    # atomic: two processes building the same ship (campaign workers) never read each other's half file
    with atomic_path(path) as tmp:
        np.savez_compressed(tmp, vertices=np.asarray(mesh.vertices, np.float64),
                            faces=np.asarray(mesh.faces, np.int64))
    return mesh, path
