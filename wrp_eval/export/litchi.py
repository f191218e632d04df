"""Litchi Mission Hub CSV (metric variant): one row per waypoint.

Columns: latitude, longitude, altitude(m), heading(deg), curvesize(m), rotationdir, gimbalmode,
gimbalpitchangle, 15 x (actiontype_i, actionparam_i), altitudemode, speed(m/s), poi_latitude, poi_longitude,
poi_altitude(m), poi_altitudemode, photo_timeinterval, photo_distinterval.
Values used: altitude above the take-off point (altitudemode 0), heading in [0, 360) (effective with the
mission's Heading Mode "Custom", a global setting the CSV cannot carry: Litchi then interpolates the heading
linearly from one waypoint to the next, litchiutilities.com/docs/why.php - the simulator's smoothTransition),
rotationdir 0, gimbalmode 2 (interpolate, so the pitch column is used); the capture mode sets the rest:
``stop``: curvesize 0 (stop at each waypoint), actions 0 = "stay for" (ms, the simulator's dwell) then 1 =
"take photo"; ``fly-through``: curvesize = the simulator's corner_radius_m (the curve's size at the waypoint,
litchiutilities.com/docs/litchiCsv.php) and the photo action alone; per waypoint where the path gives
per-view modes (:attr:`wrp_eval.planning.path.FlightPath.capture`). Unused actions are -1; no POI; no
interval photos (-1). Litchi's Path Mode ("Curved Turns" for fly-through or a mixed mission) is global too;
that a curve size of 0 makes a Curved Turns mission stop at that waypoint and run its actions is our reading
of Litchi's per-waypoint curve size, not confirmed by its documentation.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from wrp_eval.errors import InputError
from wrp_eval.export.mission import GeoMission, ReadMission, turn_mode_of

N_ACTIONS = 15
ACTION_NONE, ACTION_STAY_MS, ACTION_PHOTO = -1, 0, 1
GIMBAL_INTERPOLATE = 2
HEADER = (["latitude", "longitude", "altitude(m)", "heading(deg)", "curvesize(m)", "rotationdir", "gimbalmode",
           "gimbalpitchangle"]
          + [f"action{kind}{i}" for i in range(1, N_ACTIONS + 1) for kind in ("type", "param")]
          + ["altitudemode", "speed(m/s)", "poi_latitude", "poi_longitude", "poi_altitude(m)", "poi_altitudemode",
             "photo_timeinterval", "photo_distinterval"])


def litchi_csv_bytes(m: GeoMission, firmware: str = "px4") -> bytes:
    """The sortie as a Litchi CSV."""
    del firmware
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(HEADER)
    hold, radius = m.hold_s, m.pass_radius_m
    for k in range(len(m)):
        curve = 0 if m.stop[k] else f"{radius[k]:.2f}"
        actions = [ACTION_STAY_MS, int(round(hold[k] * 1000))] if m.stop[k] else []
        actions += [ACTION_PHOTO, 0]
        actions += [ACTION_NONE, 0] * (N_ACTIONS - len(actions) // 2)
        writer.writerow([f"{m.lat_deg[k]:.10f}", f"{m.lon_deg[k]:.10f}", f"{m.alt_rel_m[k]:.4f}",
                         f"{m.heading_deg[k]:.4f}", curve, 0, GIMBAL_INTERPOLATE, f"{m.gimbal_pitch_deg[k]:.4f}"]
                        + actions + [0, f"{m.leg_speed_m_s[k]:.2f}", 0, 0, 0, 0, -1, -1])
    return out.getvalue().encode("ascii")


def read_litchi_csv(file: str | Path) -> ReadMission:
    """Parse a Litchi CSV (``csv.DictReader``)."""
    lat, lon, alt, heading, pitch, hold, curve, speed = [], [], [], [], [], [], [], []
    photos = 0
    try:
        with open(file, newline="", encoding="ascii") as fh:
            reader = csv.DictReader(fh)
            missing = {"latitude", "longitude", "altitude(m)", "heading(deg)", "gimbalpitchangle"} - set(
                reader.fieldnames or ())
            if missing:
                raise ValueError(f"missing columns {sorted(missing)}")
            for row in reader:
                lat.append(float(row["latitude"]))
                lon.append(float(row["longitude"]))
                alt.append(float(row["altitude(m)"]))
                heading.append(float(row["heading(deg)"]))
                pitch.append(float(row["gimbalpitchangle"]))
                kinds = [(int(row.get(f"actiontype{i}", ACTION_NONE)), float(row.get(f"actionparam{i}", 0)))
                         for i in range(1, N_ACTIONS + 1)]
                photos += sum(kind == ACTION_PHOTO for kind, _ in kinds)
                hold.append(sum(ms for kind, ms in kinds if kind == ACTION_STAY_MS) / 1000.0)
                curve.append(float(row.get("curvesize(m)", 0.0)))
                speed.append(float(row.get("speed(m/s)", "nan")))
    except (OSError, ValueError, UnicodeDecodeError) as err:
        raise InputError(file, f"not a readable Litchi CSV: {err}") from None
    arr = lambda v: np.asarray(v, dtype=float)  # noqa: E731
    stop = ~(arr(curve) > 0.0) | (arr(hold) > 0.0)
    return ReadMission(arr(lat), arr(lon), arr(alt), arr(heading), arr(pitch), photos, None, turn_mode_of(stop),
                       None, arr(hold), float(speed[-1]) if speed else None,     # the last row: the mission's
                       float(np.max(arr(curve)[~stop], initial=0.0)), stop, arr(speed))
