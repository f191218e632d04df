"""``wrp-eval bench ship``: time to build each procedural mesh and to compute its surface complexity.

The paper reports no timing for Alg. 1 (anchors are None); the records give the triangle counts and
per-face complexities beside the timings so a change in the generator shows up here.
"""

from __future__ import annotations

import time
from typing import Any

from wrp_eval.bench_record import BenchRecord
from wrp_eval.ship.complexity import mesh_surface_complexity
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.meshes import procedural_mesh
from wrp_eval.ship.particulars import ShipType
from wrp_eval.ship.proxy import build_proxy
from wrp_eval.ship.resolve import resolve_particulars


def _best_of(fn, repeats: int = 5) -> tuple[float, Any]:
    best, result = float("inf"), None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def run_bench() -> list[BenchRecord]:
    records = []
    for ship_type in ShipType:
        particulars, _ = resolve_particulars(ShipSection(type=ship_type))
        proxy = build_proxy(particulars)
        build_s, mesh = _best_of(lambda p=particulars: procedural_mesh(p))
        comp_s, comp = _best_of(lambda m=mesh, b=proxy: mesh_surface_complexity(m, b))
        faces = ", ".join(f"{n}={c:.4g}" for n, c in zip(comp.face_names, comp.complexity, strict=True))
        records += [
            BenchRecord(f"ship.{ship_type.value}.mesh_build", build_s * 1e3, "ms",
                        note=f"{len(mesh.faces)} triangles, best of 5"),
            BenchRecord(f"ship.{ship_type.value}.complexity", comp_s * 1e3, "ms",
                        note=f"eq. (3) per m^2: {faces}; best of 5"),
        ]
    return records
