"""QGroundControl missions: the ``.plan`` JSON and the plain ``QGC WPL 110`` text, from one item list.

Items per sortie (MAVLink common.xml command ids; the .plan layout follows QGC's "Plan File Format" page,
file version 1, mission version 2, geoFence version 2, polygon version 1):
  MAV_CMD_NAV_TAKEOFF (22) above home to clear the no-fly box, MAV_CMD_DO_CHANGE_SPEED (178: ground speed,
  the cruise speed, throttle -1 = unchanged), then per viewpoint
  MAV_CMD_NAV_WAYPOINT (16): param1 hold, param2 acceptance radius, param3 pass radius 0 (through the point),
  param4 yaw = compass heading, lat, lon, alt. The capture mode (:class:`~wrp_eval.export.mission.FlightStyle`)
  sets param1/param2: ``stop`` holds the simulator's dwell with the autopilot's default acceptance (0 =
  NAV_ACC_RAD); ``fly-through`` holds 0 s and accepts the waypoint ``pass_radius_m`` before it (the
  simulator's corner_radius_m, the distance at which PX4 turns to the next leg), so the photo item that
  follows fires on reaching the waypoint. MAVLink carries no interpolated heading: param4 is the heading
  to reach at the waypoint (PX4/ArduPilot turn towards it at their own yaw rate, not over the leg);
  MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW (1000): pitch (deg, + up), yaw 0 (relative to the vehicle, flags 0),
  rates NaN (ignored);  MAV_CMD_IMAGE_START_CAPTURE (2000): all cameras, interval 0, 1 image, sequence k;
  a MAV_CMD_DO_CHANGE_SPEED where the leg leaving the waypoint has another speed (the path's speed per leg;
  PX4 runs it once that waypoint is reached); and MAV_CMD_NAV_RETURN_TO_LAUNCH (20) at the end. A path with
  per-view capture modes sets param1/param2 waypoint by waypoint.
Navigation items use MAV_FRAME_GLOBAL_RELATIVE_ALT (3, metres above home); the others MAV_FRAME_MISSION (2).
In the WPL file line 0 is the home position (MAV_FRAME_GLOBAL, metres above mean sea level), as
Mission Planner and pymavlink expect. NaN parameters are ``null`` in the .plan (QGC's own convention) and
``nan`` in the WPL text.
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np
from pymavlink import mavwp

from wrp_eval.errors import InputError
from wrp_eval.export.mission import GeoMission, ReadMission, turn_mode_of

MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_RETURN_TO_LAUNCH = 20
MAV_CMD_NAV_TAKEOFF = 22
MAV_CMD_DO_CHANGE_SPEED = 178
SPEED_TYPE_GROUND = 1
MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW = 1000
MAV_CMD_IMAGE_START_CAPTURE = 2000
MAV_FRAME_GLOBAL = 0
MAV_FRAME_MISSION = 2
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
QGC_FIRMWARE = {"px4": 12, "ardupilot": 3}   # MAV_AUTOPILOT_PX4 / MAV_AUTOPILOT_ARDUPILOTMEGA
MAV_TYPE_QUADROTOR = 2
NAN = float("nan")


def mission_items(m: GeoMission) -> list[tuple[int, int, list[float]]]:
    """(command, frame, params[7]) of every item of the sortie, in order."""
    items = [(MAV_CMD_NAV_TAKEOFF, MAV_FRAME_GLOBAL_RELATIVE_ALT,
              [0.0, 0.0, 0.0, float(m.heading_deg[0]), m.home_lat_deg, m.home_lon_deg, m.takeoff_alt_rel_m]),
             (MAV_CMD_DO_CHANGE_SPEED, MAV_FRAME_MISSION, [float(SPEED_TYPE_GROUND), m.speed_m_s, -1.0, 0.0, 0.0, 0.0,
                                                           0.0])]
    hold, accept = m.hold_s, m.pass_radius_m
    speed = m.speed_m_s
    for k in range(len(m)):
        items.append((MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL_RELATIVE_ALT,
                      [float(hold[k]), float(accept[k]), 0.0, float(m.heading_deg[k]), float(m.lat_deg[k]),
                       float(m.lon_deg[k]), float(m.alt_rel_m[k])]))
        items.append((MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, MAV_FRAME_MISSION,
                      [float(m.gimbal_pitch_deg[k]), 0.0, NAN, NAN, 0.0, 0.0, 0.0]))
        items.append((MAV_CMD_IMAGE_START_CAPTURE, MAV_FRAME_MISSION, [0.0, 0.0, 1.0, float(k + 1), 0.0, 0.0, 0.0]))
        if k < len(m) - 1 and m.leg_speed_m_s[k] != speed:    # the next leg's own speed (the path's speed per leg)
            speed = float(m.leg_speed_m_s[k])
            items.append((MAV_CMD_DO_CHANGE_SPEED, MAV_FRAME_MISSION, [float(SPEED_TYPE_GROUND), speed, -1.0, 0.0,
                                                                       0.0, 0.0, 0.0]))
    items.append((MAV_CMD_NAV_RETURN_TO_LAUNCH, MAV_FRAME_MISSION, [0.0] * 7))
    return items


def _json_number(v: float) -> float | None:
    return None if math.isnan(v) else v


def qgc_plan_bytes(m: GeoMission, firmware: str = "px4") -> bytes:
    """The sortie as a QGroundControl .plan document (UTF-8 JSON)."""
    items = []
    for jump_id, (command, frame, params) in enumerate(mission_items(m), start=1):
        item = {"autoContinue": True, "command": command, "doJumpId": jump_id, "frame": frame,
                "params": [_json_number(p) for p in params], "type": "SimpleItem"}
        if frame == MAV_FRAME_GLOBAL_RELATIVE_ALT:
            item.update({"AMSLAltAboveTerrain": None, "Altitude": params[6], "AltitudeMode": 1})
        items.append(item)
    doc = {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "QGroundControl",
        "mission": {
            "version": 2,
            "firmwareType": QGC_FIRMWARE[firmware],
            "vehicleType": MAV_TYPE_QUADROTOR,
            "cruiseSpeed": m.speed_m_s,
            "hoverSpeed": m.speed_m_s,
            "globalPlanAltitudeMode": 1,
            "plannedHomePosition": [m.home_lat_deg, m.home_lon_deg, m.home_alt_m],
            "items": items,
        },
        "geoFence": {"version": 2, "circles": [],
                     "polygons": [{"inclusion": False, "version": 1,
                                   "polygon": [[float(a), float(b)] for a, b in m.fence_lat_lon]}]},
        "rallyPoints": {"version": 2, "points": []},
    }
    return json.dumps(doc, indent=2, allow_nan=False).encode("utf-8")


def qgc_wpl_bytes(m: GeoMission, firmware: str = "px4") -> bytes:
    """The sortie as ``QGC WPL 110`` text: tab-separated, line 0 = home (absolute altitude)."""
    del firmware  # the text format names no autopilot
    rows = [(1, MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, [0.0, 0.0, 0.0, 0.0, m.home_lat_deg, m.home_lon_deg,
                                                         m.home_alt_m])]
    rows += [(0, frame, command, params) for command, frame, params in mission_items(m)]
    out = io.StringIO()
    out.write("QGC WPL 110\n")
    for seq, (current, frame, command, p) in enumerate(rows):
        fields = [str(seq), str(current), str(frame), str(command)]
        fields += [_fmt(v, 8) for v in p[:4]] + [_fmt(p[4], 10), _fmt(p[5], 10), _fmt(p[6], 6), "1"]
        out.write("\t".join(fields) + "\n")
    return out.getvalue().encode("ascii")


def _fmt(v: float, decimals: int) -> str:
    return "nan" if math.isnan(v) else f"{v:.{decimals}f}"


def _read_items(items: list[tuple[int, int, list[float]]], home: tuple[float, float] | None) -> ReadMission:
    """Waypoints (16 in the relative frame), the gimbal pitch set after each, the photo count, the speed set
    and the turn modes: a waypoint that holds 0 s and has an acceptance radius is passed, any other stops.
    MAVLink names no heading mode (None)."""
    lat: list[float] = []
    lon: list[float] = []
    alt: list[float] = []
    heading: list[float] = []
    pitch: list[float] = []
    hold: list[float] = []
    accept: list[float] = []
    leaving: list[float] = []
    photos, speed, current = 0, None, NAN
    for command, frame, p in items:
        if command == MAV_CMD_DO_CHANGE_SPEED and int(p[0]) == SPEED_TYPE_GROUND:
            speed = p[1] if speed is None else speed        # the mission's: the first one set
            current = p[1]
            if leaving:
                leaving[-1] = current
        if command == MAV_CMD_NAV_WAYPOINT and frame == MAV_FRAME_GLOBAL_RELATIVE_ALT:
            leaving.append(current)
            for column, value in ((lat, p[4]), (lon, p[5]), (alt, p[6]), (heading, p[3]), (pitch, NAN),
                                  (hold, p[0]), (accept, p[1])):
                column.append(value)
        elif command == MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW and pitch:
            pitch[-1] = p[0]
        elif command == MAV_CMD_IMAGE_START_CAPTURE:
            photos += int(p[2])
    arr = lambda v: np.asarray(v, dtype=float)  # noqa: E731
    stop = (arr(hold) > 0.0) | ~(arr(accept) > 0.0)
    return ReadMission(arr(lat), arr(lon), arr(alt), arr(heading), arr(pitch), photos, home, turn_mode_of(stop),
                       None, arr(hold), speed, float(np.max(arr(accept)[~stop], initial=0.0)), stop,
                       arr(leaving))


def read_qgc_plan(file: str | Path) -> ReadMission:
    """Parse a .plan written by :func:`qgc_plan_bytes` (plain ``json``)."""
    try:
        doc = json.loads(Path(file).read_text(encoding="utf-8"))
        if doc.get("fileType") != "Plan":
            raise ValueError("fileType is not 'Plan'")
        mission = doc["mission"]
        items = [(int(it["command"]), int(it["frame"]),
                  [NAN if v is None else float(v) for v in it["params"]]) for it in mission["items"]]
        home = mission.get("plannedHomePosition")
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise InputError(file, f"not a readable QGC plan: {err}") from None
    return _read_items(items, (float(home[0]), float(home[1])) if home else None)


def read_qgc_wpl(file: str | Path) -> ReadMission:
    """Parse a ``QGC WPL 110`` file with pymavlink's own loader (``mavwp.MAVWPLoader``)."""

    loader = mavwp.MAVWPLoader()
    try:
        count = loader.load(str(file))
    except (OSError, ValueError, mavwp.MAVWPError) as err:
        raise InputError(file, f"not a readable QGC WPL file: {err}") from None
    wps = [loader.wp(i) for i in range(count)]
    home = None
    if wps and wps[0].seq == 0 and wps[0].frame == MAV_FRAME_GLOBAL:
        home = (float(wps[0].x), float(wps[0].y))
        wps = wps[1:]
    items = [(int(w.command), int(w.frame), [w.param1, w.param2, w.param3, w.param4, w.x, w.y, w.z]) for w in wps]
    return _read_items(items, home)
