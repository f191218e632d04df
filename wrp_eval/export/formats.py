"""Format registry and the export entry point: validate, render every sortie in memory, then write.

One file per sortie: ``FILE`` itself for a single-sortie path, else ``FILE`` with ``_sortie<k>`` before the
extension (k = the path's own sortie number). Nothing is written unless every sortie renders; each file
is written to a temporary name first and renamed into place, so an existing file is only ever replaced by
a complete one.
"""

from __future__ import annotations

from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from wrp_eval.atomic import atomic_path
from wrp_eval.errors import InputError
from wrp_eval.export.config import ExportSection
from wrp_eval.export.dji import dji_kmz_bytes, read_dji_kmz
from wrp_eval.export.litchi import litchi_csv_bytes, read_litchi_csv
from wrp_eval.export.mission import FlightStyle, GeoMission, ReadMission, build_missions
from wrp_eval.export.qgc import (
    qgc_plan_bytes,
    qgc_wpl_bytes,
    read_qgc_plan,
    read_qgc_wpl,
)
from wrp_eval.planning.path import FlightPath
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import Proxy


@dataclass(frozen=True)
class MissionFormat:
    """render(mission, firmware) -> file bytes; read(file) -> ReadMission; suffix: the usual extension."""

    render: Callable[[GeoMission, str], bytes]
    read: Callable[[str | Path], ReadMission]
    suffix: str


FORMATS: dict[str, MissionFormat] = {
    "qgc-plan": MissionFormat(qgc_plan_bytes, read_qgc_plan, ".plan"),
    "qgc-wpl": MissionFormat(qgc_wpl_bytes, read_qgc_wpl, ".waypoints"),
    "dji-wpml": MissionFormat(dji_kmz_bytes, read_dji_kmz, ".kmz"),
    "litchi-csv": MissionFormat(litchi_csv_bytes, read_litchi_csv, ".csv"),
}


def sortie_files(out: Path, sorties: list[int]) -> list[Path]:
    """Output file of each sortie: ``out`` alone, or ``<stem>_sortie<k><suffix>`` when there are several."""
    out = Path(out)
    if len(sorties) == 1:
        return [out]
    return [out.with_name(f"{out.stem}_sortie{k}{out.suffix}") for k in sorties]


def export_path(path: FlightPath, particulars: ShipParticulars, proxy: Proxy, fmt: str, out: str | Path,
                section: ExportSection = ExportSection(), source: str = "path",
                style: FlightStyle | None = None) -> list[tuple[Path, GeoMission]]:
    """Write ``path`` as ``fmt`` missions; returns (file, mission) per sortie. InputError for bad input.
    ``style``: how the aircraft flies and shoots, the simulator's (``FlightStyle.of(path, sim.capture,
    sim.dwell_s)``); None: the simulator's defaults."""
    if fmt not in FORMATS:
        raise InputError(fmt, f"unknown export format; choose one of {', '.join(FORMATS)}")
    missions = build_missions(path, particulars, proxy, section, source, style)
    files = sortie_files(Path(out), [m.sortie for m in missions])
    blobs = [FORMATS[fmt].render(m, section.firmware) for m in missions]
    write_all_atomic(list(zip(files, blobs, strict=True)))
    return list(zip(files, missions, strict=True))


def write_all_atomic(outputs: list[tuple[Path, bytes]]) -> None:
    """Write every file to its temporary (:func:`wrp_eval.atomic.atomic_path`) first and rename them only
    when all are written, so a failure on any file replaces none; the temporaries are removed on a failure."""
    try:
        with ExitStack() as stack:
            for file, data in outputs:
                stack.enter_context(atomic_path(file)).write_bytes(data)
    except OSError as err:
        raise InputError(outputs[0][0] if outputs else "export", f"cannot write the mission file: {err}") from None
