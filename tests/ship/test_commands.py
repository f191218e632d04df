import json

import pytest
import trimesh
import yaml

from wrp_eval.cli import build_parser, main

from .conftest import type1, type5


def _write(tmp_path, ship, name="c.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump({"run": {"name": "t"}, "ship": ship}))
    return path


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("WRP_EVAL_CACHE_DIR", str(tmp_path / "cache"))


def test_ship_listed_in_help():
    assert "ship" in build_parser().format_help()


@pytest.mark.parametrize("ship_type", ["stylized", "cruise", "container", "fishing", "tanker"])
def test_ship_json_for_every_type(tmp_path, capsys, ship_type):
    assert main(["ship", str(_write(tmp_path, {"type": ship_type})), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    faces = doc["proxy"]["faces"]
    assert [f["name"] for f in faces] == ["bow", "stern", "port", "starboard", "top"]
    p = doc["particulars"]
    assert faces[4]["area_m2"] == pytest.approx(p["length_bp_m"] * p["breadth_m"])
    assert faces[2]["normal"] == [0.0, 1.0, 0.0]
    assert "depth_m" in p["derived"] and doc["mesh"]["watertight"]
    assert set(doc["complexity"]) == {"bow", "stern", "port", "starboard", "top"}
    assert all(v["complexity_per_m2"] > 0 for v in doc["complexity"].values())
    assert doc["proxy"]["no_fly_margin_m"] > 0
    assert list((tmp_path / "cache" / "ships").glob(f"{ship_type}-*.npz"))


def test_stylized_is_the_papers_ship(tmp_path, capsys):
    assert main(["ship", str(_write(tmp_path, {"no_fly_margin_m": 7.5})), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["proxy"]["length_m"], doc["proxy"]["breadth_m"]) == (140.0, 20.0)
    assert doc["proxy"]["height_m"] == pytest.approx(25.0) and doc["proxy"]["no_fly_margin_m"] == 7.5


def test_ship_from_ais_json(tmp_path, capsys):
    assert main(["ship", str(_write(tmp_path, {"ais": type5() + type1()})), "--json"]) == 0
    p = json.loads(capsys.readouterr().out)["particulars"]
    assert p["ship_type"] == "container" and p["mmsi"] == 211234567 and p["draft_m"] == 8.5
    assert p["derived"] == ["depth_m", "superstructure_height_m"] and p["provenance"]["length_bp_m"] == "ais"


def test_user_mesh_through_the_cli(tmp_path, capsys):
    mesh = trimesh.creation.box(extents=(138.0, 20.0, 33.0))
    mesh.apply_translation((0, 0, 8.5))   # 24.9 m above the water
    mesh.export(tmp_path / "ship.ply")
    cfg = _write(tmp_path, {"mesh": {"path": "ship.ply"}})
    assert main(["ship", str(cfg), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["mesh"]["triangles"] == 12 and doc["mesh"]["source"].endswith("ship.ply")
    # the box's 2 triangles per face: bow/stern 2, port/starboard 2, top 2; the bottom is under water
    assert [v["triangles"] for v in doc["complexity"].values()] == [2, 2, 2, 2, 2]


def test_rerun_recording_reads_back(tmp_path, capsys):
    from rerun.chunk import RrdReader
    rrd = tmp_path / "logs" / "t" / "ship.rrd"
    assert main(["ship", str(_write(tmp_path, {"type": "fishing"})), "--rerun", str(rrd)]) == 0
    assert "rerun recording" in capsys.readouterr().out
    chunks = list(RrdReader(rrd).stream())
    paths = {c.entity_path for c in chunks}
    assert {"/ship/mesh", "/ship/proxy", "/ship/no_fly", "/ship/faces", "/ship/info"} <= paths
    info = next(c for c in chunks if c.entity_path == "/ship/info").to_record_batch()
    text = info.column("TextDocument:text").to_pylist()[0][0]
    assert json.loads(text)["complexity"]["port"]["triangles"] > 0
    assert not list(rrd.parent.glob(".*tmp"))


@pytest.mark.parametrize("ship,needle", [
    ({"particulars": {"length_bp_m": -140}}, "key 'ship.particulars.length_bp_m'"),
    ({"particulars": {"draft_m": 30, "depth_m": 20}}, "must be less than depth_m"),
    ({"ais": ["!AIVDM,1,1,,A,15M67FC000G?ufbE`FepT@3n00Sa,0*00"]}, "checksum mismatch"),
    ({"ais": type5()[:1]}, "missing fragment 2 of 2"),
    ({"mesh": {"path": "missing.stl"}}, "no such mesh file"),
    ({"mesh": {"path": "small.stl"}}, "more than 30% off"),
])
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, ship, needle):
    trimesh.creation.box(extents=(10.0, 2.0, 3.0)).export(tmp_path / "small.stl")
    assert main(["ship", str(_write(tmp_path, ship))]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("wrp-eval: error: ") and needle in lines[0]
    assert captured.out == ""


def test_missing_and_malformed_config(tmp_path, capsys):
    assert main(["ship", str(tmp_path / "nope.yaml")]) == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text("ship: [unclosed\n")
    assert main(["ship", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "no such file" in err[0] and "invalid YAML" in err[1]
