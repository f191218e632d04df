"""``wrp-eval export``: files written on good input, exit 2 with one stderr line on bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from wrp_eval.cli import main
from wrp_eval.export.qgc import read_qgc_plan
from wrp_eval.frames import ShipPose, geographic_to_ship


@pytest.fixture
def path_file(tmp_path, path):
    file = tmp_path / "run" / "path.json"
    path.save(file)
    return file


@pytest.fixture
def config_file(tmp_path):
    file = tmp_path / "ship.yaml"
    file.write_text("ship:\n  particulars: {lat_deg: -33.9, lon_deg: 151.2, heading_deg: 301.5}\n"
                    "export:\n  min_altitude_m: 6\n")
    return file


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_export_writes_one_file_per_sortie(path_file, config_file, path, tmp_path, capsys):
    out = tmp_path / "out" / "mission.plan"
    assert main(["export", str(path_file), "--format", "qgc-plan", "--out", str(out),
                 "--config", str(config_file)]) == 0
    files = sorted((tmp_path / "out").iterdir())
    assert [f.name for f in files] == ["mission_sortie0.plan", "mission_sortie1.plan"]
    assert "sortie 1: 12 waypoints" in capsys.readouterr().out
    # the config's ship position and heading were used
    back = read_qgc_plan(files[0])
    xy = geographic_to_ship(back.lat_deg, back.lon_deg, ShipPose(-33.9, 151.2, 301.5))
    np.testing.assert_allclose(xy, path.positions[path.sortie == 0, :2], atol=0.01)


def test_export_defaults_without_config(path_file, tmp_path):
    out = tmp_path / "m.csv"
    assert main(["export", str(path_file), "--format", "litchi-csv", "--out", str(out)]) == 0
    assert (tmp_path / "m_sortie0.csv").exists() and (tmp_path / "m_sortie1.csv").exists()


def test_missing_path_file(tmp_path, capsys):
    code = main(["export", str(tmp_path / "nope.json"), "--format", "qgc-wpl", "--out", str(tmp_path / "m.txt")])
    assert code == 2
    assert "nope.json" in _one_error_line(capsys)
    assert not (tmp_path / "m.txt").exists()


@pytest.mark.parametrize("content", ["{not json", json.dumps({"format_version": 1, "viewpoints": []}),
                                     json.dumps({"format_version": 7})])
def test_malformed_path_file(tmp_path, capsys, content):
    bad = tmp_path / "path.json"
    bad.write_text(content)
    assert main(["export", str(bad), "--format", "dji-wpml", "--out", str(tmp_path / "m.kmz")]) == 2
    assert "path.json" in _one_error_line(capsys)
    assert not (tmp_path / "m.kmz").exists()


def test_bad_config(path_file, tmp_path, capsys):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text("export:\n  min_altitude_m: -3\n")
    assert main(["export", str(path_file), "--format", "qgc-plan", "--out", str(tmp_path / "m.plan"),
                 "--config", str(cfg)]) == 2
    assert "min_altitude_m" in _one_error_line(capsys)


def test_unsafe_path_refused_keeps_previous_output(path_file, config_file, tmp_path, capsys):
    out = tmp_path / "m.plan"
    strict = tmp_path / "strict.yaml"
    strict.write_text(config_file.read_text().replace("min_altitude_m: 6", "min_altitude_m: 30"))
    assert main(["export", str(path_file), "--format", "qgc-plan", "--out", str(out), "--config", str(strict)]) == 2
    assert "minimum altitude 30" in _one_error_line(capsys)
    assert not any(tmp_path.glob("m*.plan*"))


def test_the_configs_capture_mode_is_exported(path_file, config_file, tmp_path, capsys):
    from wrp_eval.export.litchi import read_litchi_csv

    cfg = tmp_path / "through.yaml"
    cfg.write_text(config_file.read_text() + "sim:\n  dwell_s: 3\n  capture: {mode: fly-through, corner_radius_m: 4}\n")
    out = tmp_path / "m.csv"
    assert main(["export", str(path_file), "--format", "litchi-csv", "--out", str(out), "--config", str(cfg)]) == 0
    assert "capture mode fly-through" in capsys.readouterr().out
    back = read_litchi_csv(tmp_path / "m_sortie0.csv")
    assert back.turn_mode == "fly-through" and back.pass_radius_m == pytest.approx(4.0) and not back.hold_s.any()
    assert main(["export", str(path_file), "--format", "litchi-csv", "--out", str(out),
                 "--config", str(config_file)]) == 0           # no sim section: the default, stop
    back = read_litchi_csv(tmp_path / "m_sortie0.csv")
    assert back.turn_mode == "stop" and back.hold_s == pytest.approx(np.full(12, 2.0))   # the path's dwell
