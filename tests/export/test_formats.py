"""Every format round-trips through its reader back to the ship frame; sorties split; unsafe paths refused."""

from __future__ import annotations

import dataclasses
import json
import re
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.export.config import ExportSection
from wrp_eval.export.dji import KML_NS, WPML_NS
from wrp_eval.export.formats import FORMATS, export_path, sortie_files, write_all_atomic
from wrp_eval.export.mission import FlightStyle, build_missions, home_point
from wrp_eval.export.qgc import qgc_plan_bytes
from wrp_eval.frames import compass_to_yaw_rad, geographic_to_ship, ship_pose, wrap_180
from wrp_eval.ship.nofly import inside_no_fly_box


@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_round_trip_to_ship_frame(fmt, ship, path, section, tmp_path):
    particulars, proxy = ship
    written = export_path(path, particulars, proxy, fmt, tmp_path / f"mission{FORMATS[fmt].suffix}", section)
    assert [m.sortie for _, m in written] == [0, 1]
    pose, home = ship_pose(particulars), home_point(particulars, section)
    for file, mission in written:
        back = FORMATS[fmt].read(file)
        idx = mission.index
        xy = geographic_to_ship(back.lat_deg, back.lon_deg, pose)
        z = back.alt_rel_m + home[2]
        err = np.linalg.norm(np.column_stack([xy, z]) - path.positions[idx], axis=1)
        assert err.max() < 0.05
        yaw = compass_to_yaw_rad(back.heading_deg, pose.heading_deg)
        assert np.abs(wrap_180(np.degrees(yaw - path.yaw[idx]))).max() < 0.1
        assert np.abs(back.gimbal_pitch_deg - np.degrees(path.pitch[idx])).max() < 0.1
        assert back.photos == len(idx)


def test_qgc_wpl_loads_with_pymavlink(ship, path, section, tmp_path):
    from pymavlink import mavutil, mavwp

    particulars, proxy = ship
    (file, mission), _ = export_path(path, particulars, proxy, "qgc-wpl", tmp_path / "m.waypoints", section)
    loader = mavwp.MAVWPLoader()
    n = loader.load(str(file))
    k = len(mission)
    assert n == 1 + 1 + 1 + 3 * k + 1      # home, takeoff, speed, (waypoint, gimbal, photo) per view, RTL
    wps = [loader.wp(i) for i in range(n)]
    mav = mavutil.mavlink
    assert wps[0].frame == mav.MAV_FRAME_GLOBAL and wps[0].z == pytest.approx(mission.home_alt_m)
    assert wps[1].command == mav.MAV_CMD_NAV_TAKEOFF
    assert wps[2].command == mav.MAV_CMD_DO_CHANGE_SPEED and wps[2].param2 == pytest.approx(path.speed_m_s)
    assert [w.command for w in wps[3:6]] == [mav.MAV_CMD_NAV_WAYPOINT, mav.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                            mav.MAV_CMD_IMAGE_START_CAPTURE]
    assert wps[-1].command == mav.MAV_CMD_NAV_RETURN_TO_LAUNCH
    nav = [w for w in wps if w.command == mav.MAV_CMD_NAV_WAYPOINT and w.frame == mav.MAV_FRAME_GLOBAL_RELATIVE_ALT]
    np.testing.assert_allclose([w.x for w in nav], mission.lat_deg, atol=1e-9)
    np.testing.assert_allclose([w.y for w in nav], mission.lon_deg, atol=1e-9)
    np.testing.assert_allclose([w.z for w in nav], mission.alt_rel_m, atol=1e-5)
    np.testing.assert_allclose([w.param1 for w in nav], path.dwell_s)        # hold time
    np.testing.assert_allclose([w.param4 for w in nav], mission.heading_deg, atol=1e-6)
    assert [w.seq for w in wps] == list(range(n))


def test_qgc_plan_schema_facts(ship, path, section):
    particulars, proxy = ship
    mission = build_missions(path, particulars, proxy, section)[0]
    doc = json.loads(qgc_plan_bytes(mission, "ardupilot"))
    assert doc["fileType"] == "Plan" and doc["version"] == 1
    plan = doc["mission"]
    assert plan["firmwareType"] == 3 and plan["plannedHomePosition"][:2] == pytest.approx(
        [mission.home_lat_deg, mission.home_lon_deg])
    commands = [it["command"] for it in plan["items"]]
    assert commands.count(16) == commands.count(1000) == commands.count(2000) == len(mission)
    assert [it["doJumpId"] for it in plan["items"]] == list(range(1, len(commands) + 1))
    fence = doc["geoFence"]["polygons"]
    assert len(fence) == 1 and fence[0]["inclusion"] is False and len(fence[0]["polygon"]) == 4
    # the fence corners are the no-fly box corners
    back = geographic_to_ship(*np.array(fence[0]["polygon"]).T, ship_pose(particulars))
    lo, hi = proxy.no_fly_bounds()
    np.testing.assert_allclose(np.sort(np.unique(back[:, 0].round(6))), [lo[0], hi[0]], atol=1e-6)
    np.testing.assert_allclose(np.sort(np.unique(back[:, 1].round(6))), [lo[1], hi[1]], atol=1e-6)


def test_dji_kmz_layout(ship, path, section, tmp_path):
    particulars, proxy = ship
    (file, mission), _ = export_path(path, particulars, proxy, "dji-wpml", tmp_path / "m.kmz", section)
    with zipfile.ZipFile(file) as kmz:
        assert set(kmz.namelist()) == {"wpmz/template.kml", "wpmz/waylines.wpml"}
        for name in kmz.namelist():
            root = ET.fromstring(kmz.read(name))
            assert root.tag == f"{{{KML_NS}}}kml"
            marks = list(root.iter(f"{{{KML_NS}}}Placemark"))
            assert [int(p.find(f"{{{WPML_NS}}}index").text) for p in marks] == list(range(len(mission)))
            funcs = [a.text for a in root.iter(f"{{{WPML_NS}}}actionActuatorFunc")]
            assert funcs == ["gimbalRotate", "hover", "takePhoto"] * len(mission)
            modes = {e.text for e in root.iter(f"{{{WPML_NS}}}executeHeightMode")} | {
                e.text for e in root.iter(f"{{{WPML_NS}}}heightMode")}
            assert modes == {"relativeToStartPoint"}
            angles = [int(e.text) for e in root.iter(f"{{{WPML_NS}}}waypointHeadingAngle")]
            assert all(-180 <= a <= 180 for a in angles)


def test_same_path_same_bytes(ship, path, section, tmp_path):
    particulars, proxy = ship
    for fmt, spec in FORMATS.items():
        a = export_path(path, particulars, proxy, fmt, tmp_path / f"a{spec.suffix}", section)[0][0].read_bytes()
        b = export_path(path, particulars, proxy, fmt, tmp_path / f"b{spec.suffix}", section)[0][0].read_bytes()
        assert a == b, fmt


def test_single_sortie_keeps_the_file_name(ship, section, tmp_path, make_ring_path):
    particulars, proxy = ship
    single = make_ring_path(proxy, n=6, sorties=1)
    written = export_path(single, particulars, proxy, "litchi-csv", tmp_path / "one.csv", section)
    assert [f.name for f, _ in written] == ["one.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.csv"]   # no temporaries left


def test_sortie_file_names(tmp_path):
    assert [f.name for f in sortie_files(tmp_path / "m.plan", [0, 1, 3])] == [
        "m_sortie0.plan", "m_sortie1.plan", "m_sortie3.plan"]


def test_sorties_keep_path_order(ship, section, make_ring_path):
    particulars, proxy = ship
    three = make_ring_path(proxy, n=9, sorties=3)
    missions = build_missions(three, particulars, proxy, section)
    assert [m.index.tolist() for m in missions] == [[0, 1, 2], [3, 4, 5], [6, 7, 8]]


def _with_position(path, i, xyz):
    positions = path.positions.copy()
    positions[i] = xyz
    return dataclasses.replace(path, positions=positions)


@pytest.mark.parametrize("xyz, message", [
    ((0.0, 0.0, 20.0), "no-fly zone"),           # over the deck
    ((72.0, 0.0, 29.0), "no-fly zone"),          # inside the margin ahead of the bow
    ((150.0, 0.0, 3.0), "minimum altitude"),     # clear of the ship but too low
])
def test_unsafe_waypoints_refused_and_nothing_written(ship, path, section, tmp_path, xyz, message):
    particulars, proxy = ship
    existing = tmp_path / "mission.plan"
    existing.write_text("previous mission")
    bad = _with_position(path, 5, xyz)
    with pytest.raises(InputError, match=message) as info:
        export_path(bad, particulars, proxy, "qgc-plan", existing, section, source="p.json")
    assert "\n" not in str(info.value) and "#5" in str(info.value)
    assert existing.read_text() == "previous mission"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mission.plan"]


def test_min_altitude_configurable(ship, path, tmp_path):
    particulars, proxy = ship
    low = _with_position(path, 2, (150.0, 0.0, 3.0))
    export_path(low, particulars, proxy, "qgc-plan", tmp_path / "m.plan", ExportSection(min_altitude_m=2.5))
    with pytest.raises(InputError, match="minimum altitude 10"):
        export_path(path, particulars, proxy, "qgc-plan", tmp_path / "m.plan", ExportSection(min_altitude_m=10))


def test_gimbal_pitch_out_of_range_refused(ship, path, section, tmp_path):
    particulars, proxy = ship
    pitch = path.pitch.copy()
    pitch[3] = np.radians(-95.0)
    with pytest.raises(InputError, match="gimbal pitch range"):
        export_path(dataclasses.replace(path, pitch=pitch), particulars, proxy, "dji-wpml", tmp_path / "m.kmz",
                    section)


def test_home_point_sets_altitude_reference(ship, path, tmp_path):
    particulars, proxy = ship
    deck = build_missions(path, particulars, proxy, ExportSection())[0]
    assert deck.home_alt_m == pytest.approx(particulars.freeboard_m)
    helideck = build_missions(path, particulars, proxy, ExportSection(home_m=(-60.0, 0.0, 10.0)))[0]
    np.testing.assert_allclose(helideck.alt_rel_m, path.positions[helideck.index, 2] - 10.0)
    np.testing.assert_allclose(deck.alt_rel_m - helideck.alt_rel_m, 10.0 - particulars.freeboard_m)
    assert helideck.takeoff_alt_rel_m == pytest.approx(proxy.no_fly_bounds()[1, 2] - 10.0)


def test_readers_refuse_garbage(tmp_path):
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"\x00\x01 not a mission")
    for spec in FORMATS.values():
        with pytest.raises(InputError):
            spec.read(junk)


def test_leg_through_the_ship_refused_though_both_waypoints_are_clear(ship, path, section, tmp_path):
    particulars, proxy = ship
    x, y, z = path.positions[5]
    across = _with_position(path, 5, (x, -y, z))      # the mirror point on the other side of the hull
    assert not inside_no_fly_box(across.positions, proxy.no_fly_bounds()).any()
    with pytest.raises(InputError, match="leg") as info:
        export_path(across, particulars, proxy, "qgc-plan", tmp_path / "m.plan", section, source="p.json")
    assert "#4 -> #5" in str(info.value) and "\n" not in str(info.value)
    assert not (tmp_path / "m.plan").exists()


def test_a_failure_on_any_sortie_file_replaces_none(tmp_path):
    first, second = tmp_path / "m_sortie0.plan", tmp_path / "m_sortie1.plan"
    first.write_bytes(b"old 0")
    second.write_bytes(b"old 1")
    blocked = tmp_path / "not_a_folder"
    blocked.write_bytes(b"")          # a file where the third mission's folder should be: its write fails
    outputs = [(first, b"new 0"), (second, b"new 1"), (blocked / "m_sortie2.plan", b"new 2")]
    with pytest.raises(InputError, match="cannot write the mission file"):
        write_all_atomic(outputs)
    assert (first.read_bytes(), second.read_bytes()) == (b"old 0", b"old 1")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m_sortie0.plan", "m_sortie1.plan", "not_a_folder"]
    write_all_atomic(outputs[:2])
    assert (first.read_bytes(), second.read_bytes()) == (b"new 0", b"new 1")


# -- the simulated flight is the exported mission (issue 26) -------------------------------------------------
def _flown_and_read(path, mode, fmt, ship, section, tmp_path):
    """[(what the reader recovers, the mission written)] of ``path`` exported in ``fmt`` as the simulator flies it
    under ``mode`` with a dwell of its own (1.5 s, not the path's 2 s) and a corner radius of 3 m."""
    from wrp_eval.sim.config import SimSection

    sim = SimSection(dwell_s=1.5, capture={"mode": mode, "corner_radius_m": 3.0})
    particulars, proxy = ship
    written = export_path(path, particulars, proxy, fmt, tmp_path / f"m{FORMATS[fmt].suffix}", section,
                          style=FlightStyle.of(path, sim.capture, sim.dwell_s))
    return [(FORMATS[fmt].read(file), mission) for file, mission in written]


@pytest.mark.parametrize("mode", ["stop", "fly-through"])
@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_every_file_is_flown_as_the_simulator_flies(fmt, mode, ship, path, section, tmp_path):
    for back, mission in _flown_and_read(path, mode, fmt, ship, section, tmp_path):
        assert back.turn_mode == mode
        hold = 1.5 if mode == "stop" else 0.0          # the simulator dwells sim.dwell_s only when it stops
        np.testing.assert_allclose(back.hold_s, np.full(len(mission), hold))
        assert back.speed_m_s == pytest.approx(path.speed_m_s)
        assert back.photos == len(mission)
        if fmt == "dji-wpml":                           # the one format that names its heading mode
            assert back.heading_mode == "smoothTransition"
        else:                                           # MAVLink and the Litchi CSV carry none (README)
            assert back.heading_mode is None
        if fmt != "dji-wpml":                           # DJI's pass-through turn has no radius to write
            assert back.pass_radius_m == pytest.approx(3.0 if mode == "fly-through" else 0.0)


@pytest.mark.parametrize("mission_mode", ["stop", "fly-through"])
@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_per_view_capture_modes_are_written_per_waypoint(fmt, mission_mode, ship, path, section, tmp_path):
    stop = np.zeros(len(path), dtype=bool)
    stop[1::3] = True
    mixed = path.with_stops(stop, mission_mode)
    for back, mission in _flown_and_read(mixed, mission_mode, fmt, ship, section, tmp_path):
        want = stop[mission.index]
        np.testing.assert_array_equal(back.stop, want)
        assert back.turn_mode == ("mixed" if 0 < want.sum() < len(want) else "stop" if want.all() else "fly-through")
        np.testing.assert_allclose(back.hold_s, np.where(want, 1.5, 0.0))
        assert back.photos == len(mission)
        if fmt != "dji-wpml":
            assert back.pass_radius_m == pytest.approx(3.0 if not want.all() else 0.0)


@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_each_legs_speed_is_written_at_the_waypoint_it_leaves(fmt, ship, path, section, tmp_path):
    legs = np.full(len(path) - 1, path.speed_m_s)
    legs[2::4] = 2.5
    slow = path.with_leg_speeds(legs)
    particulars, proxy = ship
    style = FlightStyle.of(slow)
    written = export_path(slow, particulars, proxy, fmt, tmp_path / f"m{FORMATS[fmt].suffix}", section, style=style)
    for file, mission in written:
        back = FORMATS[fmt].read(file)
        np.testing.assert_allclose(back.leg_speed_m_s[:-1], legs[mission.index[:-1]])   # no leg after the last
        assert back.speed_m_s == pytest.approx(path.speed_m_s) and back.photos == len(mission)
    (file, _), *_ = export_path(path, particulars, proxy, fmt, tmp_path / f"p{FORMATS[fmt].suffix}", section,
                                style=FlightStyle.of(path))
    np.testing.assert_allclose(FORMATS[fmt].read(file).leg_speed_m_s, path.speed_m_s)   # one speed: as before


def test_the_style_is_the_simulators(path):
    from wrp_eval.sim.config import SimSection

    default = FlightStyle.of(path, SimSection().capture, SimSection().dwell_s)
    assert (default.mode, default.heading_mode, default.hold_s, default.speed_m_s) == (
        "stop", "smoothTransition", path.dwell_s, path.speed_m_s)        # the path's dwell when sim.dwell_s is None
    through = FlightStyle.of(path, SimSection(capture={"mode": "fly-through"}).capture, 4.0)
    assert through.hold_s == 0.0 and through.pass_radius_m == SimSection().capture.corner_radius_m


def test_dji_fly_through_passes_and_shoots_without_hovering(ship, path, section, tmp_path):
    particulars, proxy = ship
    style = FlightStyle("fly-through", "smoothTransition", 0.0, 5.0, 2.0)
    (file, mission), _ = export_path(path, particulars, proxy, "dji-wpml", tmp_path / "m.kmz", section, style=style)
    with zipfile.ZipFile(file) as kmz:
        root = ET.fromstring(kmz.read("wpmz/waylines.wpml"))
    funcs = [a.text for a in root.iter(f"{{{WPML_NS}}}actionActuatorFunc")]
    assert funcs == ["gimbalRotate", "takePhoto"] * len(mission)
    turns = {e.text for e in root.iter(f"{{{WPML_NS}}}waypointTurnMode")}
    assert turns == {"toPointAndPassWithContinuityCurvature"}
    triggers = {e.text for e in root.iter(f"{{{WPML_NS}}}actionTriggerType")}
    assert triggers == {"reachPoint"}                   # the photo at the waypoint


def test_a_reversed_tour_names_its_photos_by_the_plans_viewpoints(ship, path, section, tmp_path):
    # DJI's fileSuffix s<sortie>_v<viewpoint>: the plan's viewpoint, whatever order the tour flies it in
    particulars, proxy = ship
    back = path.reversed()
    written = export_path(back, particulars, proxy, "dji-wpml", tmp_path / "mission.kmz", section)
    for file, mission in written:
        np.testing.assert_array_equal(mission.view_id, back.view_ids()[mission.index])
        with zipfile.ZipFile(file) as kmz:
            text = kmz.read("wpmz/waylines.wpml").decode()
        named = [int(v) for v in re.findall(r"fileSuffix>s\d+_v(\d+)<", text)]
        assert named == mission.view_id.tolist() and named != mission.index.tolist()
