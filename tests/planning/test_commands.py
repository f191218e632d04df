import dataclasses
import json

import numpy as np
import pytest

from wrp_eval.atomic import temporaries
from wrp_eval.cli import main
from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.planning.config import PlanningSection
from wrp_eval.planning.path import FlightPath
from wrp_eval.schema import parse_model


def test_path_json_round_trip(plans, tmp_path):
    path = plans[("stylized", "ours")].path
    path.save(tmp_path / "path.json")
    back = FlightPath.load(tmp_path / "path.json")
    np.testing.assert_allclose(back.positions, path.positions)
    np.testing.assert_allclose(back.yaw, path.yaw, atol=1e-12)
    np.testing.assert_allclose(back.pitch, path.pitch, atol=1e-12)
    for field in ("face_id", "kind", "sortie"):
        np.testing.assert_array_equal(getattr(back, field), getattr(path, field))
    assert back.camera == path.camera and back.dwell_s == path.dwell_s and back.method == "ours"


def test_a_reversed_tour_keeps_its_viewpoints_ids_and_legs(plans, tmp_path):
    path = plans[("stylized", "ours")].path
    back = path.reversed()
    np.testing.assert_array_equal(back.positions, path.positions[::-1])
    np.testing.assert_array_equal(back.view_ids(), np.arange(len(path))[::-1])
    np.testing.assert_allclose(np.sort(back.segment_lengths_m), np.sort(path.segment_lengths_m))
    assert back.sortie[0] == path.sortie.min() and np.all(np.diff(back.sortie) >= 0)
    back.save(tmp_path / "back.json")
    again = FlightPath.load(tmp_path / "back.json")
    np.testing.assert_array_equal(again.view_id, back.view_id)
    assert back.digest() != path.digest()       # a reloaded path may differ in a last digit (degrees): not compared
    assert back.reversed().view_id is None and back.reversed().digest() == path.digest()
    # a path in plan order meeting its own errors writes neither field: its document and digest are what they were
    doc = path.to_json_dict()
    assert "noise_draw" not in doc and not any("view_id" in v for v in doc["viewpoints"])
    again_drawn = path.redrawn(3)
    assert FlightPath.from_json_dict(again_drawn.to_json_dict()).noise_draw == 3
    assert again_drawn.digest() != path.digest()
    doc["viewpoints"][0]["view_id"] = 3      # one viewpoint with an id, the others without
    with pytest.raises(InputError, match="view_id"):
        FlightPath.from_json_dict(doc)


def test_per_view_capture_modes_round_trip_and_enter_the_digest(plans, tmp_path):
    path = plans[("stylized", "ours")].path
    stop = np.zeros(len(path), dtype=bool)
    stop[[1, 4]] = True
    mixed = path.with_stops(stop, "fly-through")
    assert mixed.capture[1] == "stop" and mixed.capture[0] == "fly-through"
    np.testing.assert_array_equal(mixed.stops("fly-through"), stop)
    np.testing.assert_array_equal(mixed.stops("stop"), stop)        # the path's modes override the mission's
    np.testing.assert_array_equal(path.stops("stop"), np.ones(len(path), bool))
    assert path.with_stops(stop * 0, "fly-through").capture is None   # every view as the mission says: none written
    assert "capture" not in path.to_json_dict()["viewpoints"][0]
    mixed.save(tmp_path / "mixed.json")
    again = FlightPath.load(tmp_path / "mixed.json")
    assert again.capture == mixed.capture and mixed.digest() != path.digest()
    np.testing.assert_array_equal(mixed.reversed().stops("stop"), stop[::-1])
    doc = mixed.to_json_dict()
    doc["viewpoints"][2]["capture"] = "hover"
    with pytest.raises(InputError, match="capture"):
        FlightPath.from_json_dict(doc, source="mixed.json")
    del doc["viewpoints"][2]["capture"]
    with pytest.raises(InputError, match="capture"):
        FlightPath.from_json_dict(doc, source="mixed.json")


def test_leg_speeds_round_trip_reverse_with_the_tour_and_enter_the_digest(plans, tmp_path):
    path = plans[("stylized", "ours")].path
    legs = np.full(len(path) - 1, path.speed_m_s)
    legs[3] = 2.0
    slow = path.with_leg_speeds(legs)
    assert path.with_leg_speeds(np.full(len(path) - 1, path.speed_m_s)).leg_speed_m_s is None
    assert "leg_speed_m_s" not in path.to_json_dict()["viewpoints"][0]
    slow.save(tmp_path / "slow.json")
    again = FlightPath.load(tmp_path / "slow.json")
    np.testing.assert_array_equal(again.leg_speeds(), legs)
    assert slow.digest() != path.digest()
    assert slow.flight_time_s == pytest.approx(path.flight_time_s + path.segment_lengths_m[3] * (1 / 2.0 - 1 / 5.0))
    np.testing.assert_array_equal(slow.reversed().leg_speeds(), legs[::-1])
    doc = slow.to_json_dict()
    doc["viewpoints"][3]["leg_speed_m_s"] = 0.0
    with pytest.raises(InputError, match="leg_speed_m_s"):
        FlightPath.from_json_dict(doc, source="slow.json")
    del doc["viewpoints"][3]["leg_speed_m_s"]
    with pytest.raises(InputError, match="leg_speed_m_s"):
        FlightPath.from_json_dict(doc, source="slow.json")
    with pytest.raises(ValueError, match="leg_speed_m_s"):
        path.with_leg_speeds(legs[:-1])


@pytest.mark.parametrize("text", ["{not json", '{"format_version": 1, "viewpoints": []}',
                                  '{"format_version": 1, "viewpoints": [{"x_m": 1}]}'])
def test_bad_path_file_is_an_input_error(tmp_path, text):
    f = tmp_path / "path.json"
    f.write_text(text)
    with pytest.raises(InputError) as err:
        FlightPath.load(f)
    assert str(f) in str(err.value) and "\n" not in str(err.value)


def test_planning_section_defaults_and_refusals():
    cfg = parse_model(ExperimentConfig, {}, "x.yaml")
    assert cfg.planning.method == "ours"
    # 7.5 mm/px with f = 44.7846 mm, 36 mm sensor, 6000 px: D = 0.0075 * 44.7846 * 6000 / 36
    assert cfg.planning.planned_distance_m() == pytest.approx(0.0075 * 44.7846 * 6000 / 36)
    assert PlanningSection(distance_m=40.0).planned_distance_m() == 40.0
    for bad in ({"planning": {"overlap_min": 0.9}}, {"planning": {"method": "magic"}},
                {"planning": {"wat": 1}}, {"planning": {"gsd_mm": -1}}):
        with pytest.raises(InputError) as err:
            parse_model(ExperimentConfig, bad, "x.yaml")
        assert "x.yaml" in str(err.value)


def test_cli_plan_writes_path_and_metrics(tmp_path, capsys):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("run: {seed: 3}\nship: {type: stylized}\n"
                   "planning: {tour_solver: ortools, tour_time_limit_s: 0.05}\n")
    out = tmp_path / "out"
    assert main(["plan", str(cfg), "--out", str(out), "--method", "zhou2020"]) == 0
    metrics = json.loads((out / "plan_metrics.json").read_text())
    for key in ("n_samples", "n_candidates", "n_views", "per_face", "H", "R", "length_m", "flight_time_s",
                "sorties", "n_transition_views"):
        assert key in metrics
    for key in ("sampling_s", "visibility_s", "min_s", "max_s", "tsp_s", "transitions_s", "total_s"):
        assert key in metrics["timings"]
    path = FlightPath.load(out / "path.json")
    assert path.method == "zhou2020" and len(path) == metrics["n_path_views"]
    assert temporaries(out) == []


def test_cli_bad_config_exits_2(tmp_path, capsys):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("planning: {threshold: -1}\n")
    assert main(["plan", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "planning.threshold" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_rerun_recording_is_written(plans, proxies, tmp_path):
    from rerun.chunk import RrdReader

    from wrp_eval.planning.rerun_log import save_plan_recording
    result = plans[("stylized", "ours")]
    moved = dataclasses.replace(result.path, positions=result.path.positions + [0.0, 0.0, 1.0])
    out = save_plan_recording(result, proxies["stylized"], tmp_path / "plan.rrd", other_paths={"wrp": moved})
    assert out.exists() and out.stat().st_size > 10_000
    assert temporaries(tmp_path) == []
    entities = {chunk.entity_path for chunk in RrdReader(str(out)).stream()}
    n = len(result.path)
    for prefix in ("/plan", "/paths/wrp"):    # both paths: one frustum entity per view and a tour
        assert {f"{prefix}/views/{i:04d}" for i in range(n)} <= entities and f"{prefix}/tour" in entities
    assert f"/plan/views/{n:04d}" not in entities and "/plan/proxy" in entities
