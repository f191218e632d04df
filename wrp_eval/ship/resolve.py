"""The ship stage end to end: config section -> particulars, proxy, mesh (and complexity)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import cast

import trimesh

from wrp_eval.errors import InputError
from wrp_eval.ship.ais import decode_ais, particulars_from_report
from wrp_eval.ship.complexity import SurfaceComplexity, mesh_surface_complexity
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.derive import complete_particulars
from wrp_eval.ship.meshes import cached_procedural_mesh
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import Proxy, build_proxy
from wrp_eval.ship.user_mesh import check_mesh_against_particulars, load_user_mesh


@dataclass(frozen=True)
class ResolvedShip:
    """Everything the ship stage produces. provenance: field -> "ais" | "config" | "type default" | "derived: ..."""

    particulars: ShipParticulars
    provenance: dict
    proxy: Proxy
    mesh: trimesh.Trimesh
    mesh_source: str
    complexity: SurfaceComplexity

    def report(self) -> dict:
        """The JSON document printed by ``wrp-eval ship --json`` (and logs/<run>/ship.json)."""
        ship = self
        p, proxy = ship.particulars, ship.proxy
        particulars = {
            "ship_type": p.ship_type.value, "name": p.name, "mmsi": p.mmsi,
            "length_bp_m": p.length_bp_m, "breadth_m": p.breadth_m, "depth_m": p.depth_m,
            "superstructure_height_m": p.superstructure_height_m, "draft_m": p.draft_m,
            "freeboard_m": p.freeboard_m, "height_above_water_m": p.height_above_water_m,
            "lat_deg": p.lat_deg, "lon_deg": p.lon_deg, "heading_deg": p.heading_deg,
            "derived": sorted(p.derived), "provenance": ship.provenance,
        }
        faces = [{"name": name, "area_m2": float(area), "normal": proxy.normals[i].tolist(),
                  "center": proxy.centers[i].tolist(), "half_extents_m": proxy.half_extents[i].tolist()}
                 for i, (name, area) in enumerate(zip(proxy.face_names, proxy.areas, strict=True))]
        mesh = ship.mesh
        return {
            "particulars": particulars,
            "proxy": {"length_m": proxy.length_m, "breadth_m": proxy.breadth_m, "height_m": proxy.height_m,
                      "no_fly_margin_m": proxy.no_fly_margin_m, "no_fly_bounds": proxy.no_fly_bounds().tolist(),
                      "faces": faces},
            "complexity": ship.complexity.as_dict(),
            "mesh": {"source": ship.mesh_source, "triangles": int(len(mesh.faces)),
                     "watertight": bool(mesh.is_watertight), "bounds": mesh.bounds.tolist()},
        }


def resolve_particulars(section: ShipSection, config_dir: str | Path = ".", source: str = "config"
                        ) -> tuple[ShipParticulars, dict[str, str]]:
    """Particulars from the section's AIS data (if any), its overrides and the type defaults."""
    config_dir = Path(config_dir)
    overrides = section.particulars.given()
    ship_type = section.type if section.type_given else None
    if section.ais is not None or section.ais_file is not None:
        if section.ais is not None:
            sentences = list(section.ais)
            labels = [f"{source} ship.ais[{i}]" for i in range(len(sentences))]
        else:
            path = config_dir / cast(str, section.ais_file)
            try:
                sentences = path.read_text(encoding="ascii").splitlines()
            except FileNotFoundError:
                raise InputError(path, "no such AIS file (ship.ais_file)") from None
            except (OSError, UnicodeError) as err:
                raise InputError(path, f"cannot read AIS file: {err}") from None
            labels = [f"{path} line {i + 1}" for i in range(len(sentences))]
        report = decode_ais(sentences, f"{source} ship.ais" if section.ais is not None else str(path), labels)
        return particulars_from_report(report, overrides, ship_type, f"{source} ship")
    given_by = {k: "config" for k in overrides}
    if section.type_given:
        given_by["ship_type"] = "config"
    particulars, provenance = complete_particulars(section.type, overrides, f"{source} ship", given_by)
    provenance["ship_type"] = "config" if section.type_given else "default"
    return particulars, provenance


def resolve_ship_full(section: ShipSection, config_dir: str | Path = ".", source: str = "config",
                      cache_dir: Path | None = None) -> ResolvedShip:
    """Particulars, proxy, mesh and per-face surface complexity of the configured ship."""
    particulars, provenance = resolve_particulars(section, config_dir, source)
    proxy = build_proxy(particulars, section.no_fly_margin_m, section.proxy_height_error)
    if section.mesh is None:
        mesh, path = cached_procedural_mesh(particulars, cache_dir)
        mesh_source = f"procedural ({path})"
    else:
        path = Path(config_dir) / section.mesh.path
        mesh = load_user_mesh(path, section.mesh.scale, section.mesh.up_axis, section.mesh.offset_m)
        check_mesh_against_particulars(mesh, particulars, path)
        mesh_source = str(path)
    return ResolvedShip(particulars, provenance, proxy, mesh, mesh_source,
                        mesh_surface_complexity(mesh, proxy))


def resolve_ship(section: ShipSection, config_dir: str | Path = ".", source: str = "config"
                 ) -> tuple[ShipParticulars, Proxy, trimesh.Trimesh]:
    """The stage's outputs: (particulars, proxy, mesh). Raises :class:`InputError` for bad input."""
    ship = resolve_ship_full(section, config_dir, source)
    return ship.particulars, ship.proxy, ship.mesh
