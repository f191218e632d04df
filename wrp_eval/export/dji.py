"""DJI WPML 1.0.2 KMZ: ``wpmz/template.kml`` (editable template) + ``wpmz/waylines.wpml`` (what the aircraft
executes), following DJI's Cloud API "DJI WPML" reference (template.kml, waylines.wpml, common elements).

Choices:
- heights ``relativeToStartPoint`` (template ``heightMode``, waylines ``executeHeightMode``): metres above the
  take-off point on the ship, like every other format here;
- the aircraft heading per waypoint follows the mission's heading mode (``smoothTransition``: interpolated
  over the leg, what the simulator flies) with ``waypointHeadingAngle`` in [-180, 180] (DJI types it as an
  integer, so it is rounded), and the camera is pointed exactly by a ``gimbalRotate`` action in
  ``absoluteAngle`` mode (yaw relative to north, pitch), both floats. Readers take the heading from the
  gimbal yaw;
- the turn mode follows the capture mode (:class:`~wrp_eval.export.mission.FlightStyle`): ``stop`` ->
  ``toPointAndStopWithDiscontinuityCurvature`` (stop at the point) and the actions gimbalRotate, ``hover``
  (the simulator's dwell), ``takePhoto``; ``fly-through`` -> ``toPointAndPassWithContinuityCurvature``
  (pass through the point without stopping) and gimbalRotate, ``takePhoto`` on reaching it, no hover; per
  placemark (``waypointTurnParam``, ``useGlobalTurnParam`` 0 in the template) where the path gives per-view
  modes (:attr:`wrp_eval.planning.path.FlightPath.capture`);
- drone/payload enums: Mavic 3 Enterprise (droneEnumValue 77, sub 0; payload 66), the closest WPML-capable
  airframe to the paper's Phantom 4-class quadrotor - change them in DJI Pilot 2 for another aircraft.
"""

from __future__ import annotations

import io
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from wrp_eval.errors import InputError
from wrp_eval.export.mission import GeoMission, ReadMission, turn_mode_of
from wrp_eval.frames import wrap_180

KML_NS = "http://www.opengis.net/kml/2.2"
WPML_NS = "http://www.dji.com/wpmz/1.0.2"
DRONE_ENUM, DRONE_SUB_ENUM, PAYLOAD_ENUM = 77, 0, 66
TEMPLATE_PATH, WAYLINES_PATH = "wpmz/template.kml", "wpmz/waylines.wpml"
ET.register_namespace("", KML_NS)
ET.register_namespace("wpml", WPML_NS)


def _k(tag: str) -> str:
    return f"{{{KML_NS}}}{tag}"


def _w(tag: str) -> str:
    return f"{{{WPML_NS}}}{tag}"


def _sub(parent: ET.Element, tag: str, text: object | None = None) -> ET.Element:
    el = ET.SubElement(parent, tag)
    if text is not None:
        el.text = str(text)
    return el


def _num(v: float, decimals: int = 4) -> str:
    return f"{v:.{decimals}f}"


def _find(node: ET.Element | None, path: str) -> ET.Element:
    found = None if node is None else node.find(path)
    if found is None:
        raise ValueError(f"missing {path}")
    return found


def _text(node: ET.Element | None, path: str) -> str:
    text = _find(node, path).text
    if text is None:
        raise ValueError(f"empty {path}")
    return text


def _mission_config(doc: ET.Element, m: GeoMission) -> None:
    cfg = _sub(doc, _w("missionConfig"))
    _sub(cfg, _w("flyToWaylineMode"), "safely")
    _sub(cfg, _w("finishAction"), "goHome")
    _sub(cfg, _w("exitOnRCLost"), "executeLostAction")
    _sub(cfg, _w("executeRCLostAction"), "goBack")
    _sub(cfg, _w("takeOffSecurityHeight"), _num(min(max(m.takeoff_alt_rel_m, 2.0), 1500.0), 2))
    _sub(cfg, _w("globalTransitionalSpeed"), _num(m.speed_m_s, 2))
    drone = _sub(cfg, _w("droneInfo"))
    _sub(drone, _w("droneEnumValue"), DRONE_ENUM)
    _sub(drone, _w("droneSubEnumValue"), DRONE_SUB_ENUM)
    payload = _sub(cfg, _w("payloadInfo"))
    _sub(payload, _w("payloadEnumValue"), PAYLOAD_ENUM)
    _sub(payload, _w("payloadPositionIndex"), 0)


TURN_MODES = {"stop": "toPointAndStopWithDiscontinuityCurvature",
              "fly-through": "toPointAndPassWithContinuityCurvature"}


def _heading_param(parent: ET.Element, heading_deg: float, heading_mode: str) -> None:
    hp = _sub(parent, _w("waypointHeadingParam"))
    _sub(hp, _w("waypointHeadingMode"), heading_mode)
    _sub(hp, _w("waypointHeadingAngle"), int(round(float(wrap_180(heading_deg)))))
    _sub(hp, _w("waypointHeadingPathMode"), "followBadArc")


def _turn_param(parent: ET.Element, m: GeoMission, k: int) -> None:
    turn = _sub(parent, _w("waypointTurnParam"))
    _sub(turn, _w("waypointTurnMode"), TURN_MODES["stop" if m.stop[k] else "fly-through"])
    _sub(turn, _w("waypointTurnDampingDist"), 0)


def _action_group(parent: ET.Element, m: GeoMission, k: int) -> None:
    group = _sub(parent, _w("actionGroup"))
    _sub(group, _w("actionGroupId"), k)
    _sub(group, _w("actionGroupStartIndex"), k)
    _sub(group, _w("actionGroupEndIndex"), k)
    _sub(group, _w("actionGroupMode"), "sequence")
    _sub(_sub(group, _w("actionTrigger")), _w("actionTriggerType"), "reachPoint")
    actions: list[tuple[str, Sequence[tuple[str, object]]]] = [
        ("gimbalRotate", [("gimbalHeadingYawBase", "north"), ("gimbalRotateMode", "absoluteAngle"),
                          ("gimbalPitchRotateEnable", 1), ("gimbalPitchRotateAngle", _num(m.gimbal_pitch_deg[k])),
                          ("gimbalRollRotateEnable", 0), ("gimbalRollRotateAngle", 0),
                          ("gimbalYawRotateEnable", 1),
                          ("gimbalYawRotateAngle", _num(float(wrap_180(m.heading_deg[k])))),
                          ("gimbalRotateTimeEnable", 0), ("gimbalRotateTime", 0), ("payloadPositionIndex", 0)]),
        *([("hover", [("hoverTime", _num(m.hold_s[k], 2))])] if m.stop[k] else []),
        ("takePhoto", [("payloadPositionIndex", 0), ("fileSuffix", f"s{m.sortie}_v{int(m.view_id[k])}"),
                       ("useGlobalPayloadLensIndex", 1)]),
    ]
    for action_id, (func, params) in enumerate(actions):
        action = _sub(group, _w("action"))
        _sub(action, _w("actionId"), action_id)
        _sub(action, _w("actionActuatorFunc"), func)
        holder = _sub(action, _w("actionActuatorFuncParam"))
        for name, value in params:
            _sub(holder, _w(name), value)


def _placemark(folder: ET.Element, m: GeoMission, k: int, executable: bool) -> None:
    pm = _sub(folder, _k("Placemark"))
    _sub(_sub(pm, _k("Point")), _k("coordinates"), f"{m.lon_deg[k]:.10f},{m.lat_deg[k]:.10f}")
    _sub(pm, _w("index"), k)
    if executable:
        _sub(pm, _w("executeHeight"), _num(m.alt_rel_m[k]))
        _sub(pm, _w("waypointSpeed"), _num(m.leg_speed_m_s[k], 2))
        _heading_param(pm, m.heading_deg[k], m.style.heading_mode)
        _turn_param(pm, m, k)
    else:
        _sub(pm, _w("height"), _num(m.alt_rel_m[k]))
        _sub(pm, _w("useGlobalHeight"), 0)
        own_speed = bool(m.leg_speed_m_s[k] != m.speed_m_s)     # the leg's own speed (the path's per leg)
        _sub(pm, _w("useGlobalSpeed"), 0 if own_speed else 1)
        if own_speed:
            _sub(pm, _w("waypointSpeed"), _num(m.leg_speed_m_s[k], 2))
        _sub(pm, _w("useGlobalHeadingParam"), 0)
        _heading_param(pm, m.heading_deg[k], m.style.heading_mode)
        own_turn = bool(m.stop[k]) != (m.style.mode == "stop")     # a per-view mode other than the mission's
        _sub(pm, _w("useGlobalTurnParam"), 0 if own_turn else 1)
        if own_turn:
            _turn_param(pm, m, k)
        _sub(pm, _w("gimbalPitchAngle"), _num(m.gimbal_pitch_deg[k]))
    _action_group(pm, m, k)


def _document(m: GeoMission, executable: bool) -> bytes:
    root = ET.Element(_k("kml"))
    doc = _sub(root, _k("Document"))
    if not executable:
        _sub(doc, _w("author"), "wrp-eval")
    _mission_config(doc, m)
    folder = _sub(doc, _k("Folder"))
    if executable:
        _sub(folder, _w("templateId"), 0)
        _sub(folder, _w("executeHeightMode"), "relativeToStartPoint")
        _sub(folder, _w("waylineId"), 0)
        _sub(folder, _w("autoFlightSpeed"), _num(m.speed_m_s, 2))
    else:
        _sub(folder, _w("templateType"), "waypoint")
        _sub(folder, _w("templateId"), 0)
        coords = _sub(folder, _w("waylineCoordinateSysParam"))
        _sub(coords, _w("coordinateMode"), "WGS84")
        _sub(coords, _w("heightMode"), "relativeToStartPoint")
        _sub(folder, _w("autoFlightSpeed"), _num(m.speed_m_s, 2))
        _sub(folder, _w("gimbalPitchMode"), "usePointSetting")
        glob = _sub(folder, _w("globalWaypointHeadingParam"))
        _sub(glob, _w("waypointHeadingMode"), m.style.heading_mode)
        _sub(glob, _w("waypointHeadingPathMode"), "followBadArc")
        _sub(folder, _w("globalWaypointTurnMode"), TURN_MODES[m.style.mode])
        _sub(folder, _w("globalUseStraightLine"), 1)
    for k in range(len(m)):
        _placemark(folder, m, k, executable)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def dji_kmz_bytes(m: GeoMission, firmware: str = "px4") -> bytes:
    """The sortie as a DJI WPML KMZ (zip of template.kml and waylines.wpml)."""
    del firmware
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as kmz:
        # Fixed timestamps so that the same path gives the same bytes.
        for name, data in ((TEMPLATE_PATH, _document(m, False)), (WAYLINES_PATH, _document(m, True))):
            kmz.writestr(zipfile.ZipInfo(name, date_time=(2020, 1, 1, 0, 0, 0)), data)
    return buf.getvalue()


def read_dji_kmz(file: str | Path) -> ReadMission:
    """Parse the executable ``waylines.wpml`` of a KMZ (zipfile + xml.etree)."""
    try:
        with zipfile.ZipFile(file) as kmz:
            names = set(kmz.namelist())
            if TEMPLATE_PATH not in names:
                raise ValueError(f"missing {TEMPLATE_PATH}")
            root = ET.fromstring(kmz.read(WAYLINES_PATH))
        lat, lon, alt, heading, pitch, hold, turns, headings = [], [], [], [], [], [], [], set()
        leaving: list[float] = []
        photos = 0
        speed = float(_text(root, f"{_k('Document')}/{_k('Folder')}/{_w('autoFlightSpeed')}"))
        modes = {v: k for k, v in TURN_MODES.items()}
        for pm in root.iter(_k("Placemark")):
            lon_s, lat_s = _text(pm, f"{_k('Point')}/{_k('coordinates')}").strip().split(",")[:2]
            lat.append(float(lat_s))
            lon.append(float(lon_s))
            alt.append(float(_text(pm, _w("executeHeight"))))
            leaving.append(float(_text(pm, _w("waypointSpeed"))))
            turn = _find(pm, f"{_w('waypointTurnParam')}/{_w('waypointTurnMode')}").text
            if turn not in modes:
                raise ValueError(f"waypoint turn mode {turn!r} is neither of {sorted(modes)}")
            turns.append(modes[turn] == "stop")
            headings.add(_text(pm, f"{_w('waypointHeadingParam')}/{_w('waypointHeadingMode')}"))
            hold.append(0.0)
            for action in pm.iter(_w("action")):
                func = _find(action, _w("actionActuatorFunc")).text
                params = action.find(_w("actionActuatorFuncParam"))
                if func == "gimbalRotate":
                    pitch.append(float(_text(params, _w("gimbalPitchRotateAngle"))))
                    heading.append(float(_text(params, _w("gimbalYawRotateAngle"))) % 360.0)
                elif func == "hover":
                    hold[-1] += float(_text(params, _w("hoverTime")))
                elif func == "takePhoto":
                    photos += 1
        if len(headings) > 1:
            raise ValueError(f"mixed heading modes {sorted(headings)}")
    except (OSError, KeyError, ValueError, AttributeError, zipfile.BadZipFile, ET.ParseError) as err:
        raise InputError(file, f"not a readable DJI WPML KMZ: {err}") from None
    arr = lambda v: np.asarray(v, dtype=float)  # noqa: E731
    stop = np.asarray(turns, dtype=bool)
    return ReadMission(arr(lat), arr(lon), arr(alt), arr(heading), arr(pitch), photos, None, turn_mode_of(stop),
                       next(iter(headings), None), arr(hold), speed, stop=stop, leg_speed_m_s=arr(leaving))
