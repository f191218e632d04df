"""Log the ship mesh, its proxy, no-fly zone and per-face complexity to a rerun recording (.rrd)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import rerun as rr

from wrp_eval.recording import APPLICATION_ID, recording
from wrp_eval.ship.resolve import ResolvedShip


def save_ship_recording(ship: ResolvedShip, path: str | Path, application_id: str = APPLICATION_ID,
                        recording_id: str | None = None) -> Path:
    """Write ``path`` (atomically, :func:`wrp_eval.recording.recording`) with entities ship/mesh, ship/proxy,
    ship/no_fly, ship/faces, ship/info."""
    path = Path(path)
    with recording(path, recording_id=recording_id, application_id=application_id) as rec:
        _log_ship(rec, ship)
    return path


def _log_ship(rec: rr.RecordingStream, ship: ResolvedShip) -> None:
    """The ship's entities (all static; ship frame, metres) into ``rec``."""
    mesh, proxy, comp = ship.mesh, ship.proxy, ship.complexity
    rec.log("ship/mesh", rr.Mesh3D(vertex_positions=np.asarray(mesh.vertices, np.float32),
                                   triangle_indices=np.asarray(mesh.faces, np.uint32),
                                   vertex_normals=np.asarray(mesh.vertex_normals, np.float32),
                                   albedo_factor=[140, 140, 150, 255]), static=True)
    lo, hi = proxy.bounds
    rec.log("ship/proxy", rr.Boxes3D(mins=[lo], sizes=[hi - lo], colors=[[40, 200, 80]],
                                     labels=["proxy"]), static=True)
    nlo, nhi = proxy.no_fly_bounds()
    rec.log("ship/no_fly", rr.Boxes3D(mins=[nlo], sizes=[nhi - nlo], colors=[[220, 60, 60]],
                                      labels=[f"no-fly r={proxy.no_fly_margin_m:g} m"]), static=True)
    top = max(float(comp.complexity.max()), 1e-12)
    colours = (np.stack([comp.complexity / top, 0.2 * np.ones(5), 1 - comp.complexity / top], -1) * 255)
    labels = [f"{n}: c={c:.4g}/m2 ({k} tris)"
              for n, c, k in zip(comp.face_names, comp.complexity, comp.counts, strict=True)]
    rec.log("ship/faces", rr.Arrows3D(origins=proxy.centers, vectors=proxy.normals * max(proxy.height_m, 5.0),
                                      colors=colours.astype(np.uint8), labels=labels), static=True)
    info = {"particulars": {k: ship.provenance.get(k) for k in ship.provenance},
            "complexity": comp.as_dict(), "mesh_source": ship.mesh_source}
    rec.log("ship/info", rr.TextDocument(json.dumps(info, indent=1), media_type="text/markdown"), static=True)
