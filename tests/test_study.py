"""Studies (`study:` configs, wrp_eval/study): validation, the variant mechanics, and the paper configs
(experiments/paper/table1..8.yaml) run end to end at their smallest setting through `wrp-eval run --smallest`:
tables 1, 2, 6, 7 and 8 as they are; tables 3, 4 and 5, which share one base config, as one study holding a
variant of each kind from the three (25-34 s here; the three tables' own smallest runs, 82-88 s: `wrp-eval bench
--only study`)."""

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from wrp_eval.cli import main
from wrp_eval.config import ExperimentConfig, load_experiment
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.schema import parse_model
from wrp_eval.study.runner import deep_merge, random_offsets, variant_configs
from wrp_eval.wrp.optimize import apply_offsets, offset_totals

PAPER = Path(__file__).resolve().parents[1] / "experiments" / "paper"
STUDY = {"columns": ["views", "error_m"], "variants": [{"name": "a"}]}


def _study(**changes):
    return {"study": {**STUDY, **changes}}


def test_deep_merge_merges_mappings_and_replaces_the_rest():
    base = {"ship": {"type": "stylized", "particulars": {"draft_m": 6}}, "run": {"seed": 1}}
    out = deep_merge(base, {"ship": {"particulars": {"breadth_m": 20}}, "run": {"seed": 2}, "x": [1]})
    assert out == {"ship": {"type": "stylized", "particulars": {"draft_m": 6, "breadth_m": 20}},
                   "run": {"seed": 2}, "x": [1]}
    assert base["ship"]["particulars"] == {"draft_m": 6}   # the base is not modified


@pytest.mark.parametrize("changes, message", [
    ({"columns": ["views", "speed"]}, "unknown column"),
    ({"variants": [{"name": "a"}, {"name": "a"}]}, "unique"),
    ({"variants": [{"name": "a", "paper": {"length_m": 1.0}}]}, "not in study.columns"),
    ({"variants": [{"name": "a", "repetitions": 3}]}, "random_offsets"),
    ({"variants": [{"name": "a", "random_offsets": True, "repetitions": 3, "paper": [{}, {}]}]}, "repetitions"),
    ({"variants": [{"name": "a", "path": "wrp"}]}, "path"),
    ({"variants": []}, "variants"),
    ({"variants": [{"name": "a", "overrides": {"run": {"name": "other"}}}]}, "run.name"),
])
def test_bad_study_sections_are_refused_with_one_line(changes, message):
    with pytest.raises(InputError, match=message) as err:
        parse_model(ExperimentConfig, _study(**changes), "cfg.yaml")
    assert "\n" not in str(err.value)


def test_a_bad_override_names_the_variant_and_exits_2(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    cfg = tmp_path / "bad.yaml"
    cfg.write_text("study: {columns: [views], variants: [{name: ok}, {name: broken, overrides: "
                   "{planning: {method: magic}}}]}\n")
    assert main(["run", str(cfg)]) == 2
    err = capsys.readouterr().err.strip()
    assert "variant 'broken'" in err and "planning.method" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "logs" / "quickstart" / "study.json").exists()   # nothing ran


def test_variants_keep_the_base_and_apply_their_overrides():
    config = parse_model(ExperimentConfig, {
        "run": {"name": "t", "seed": 4}, "ship": {"type": "cruise"},
        "study": {"columns": ["views"], "variants": [{"name": "a"},
                                                     {"name": "b", "overrides": {"planning": {"max_rounds": 0}}}],
                  "smallest": {"planning": {"threshold": 0.5}}, "smallest_variants": 1}}, "cfg")
    (va, a), (vb, b) = variant_configs(config, "cfg")
    assert (a.ship.type.value, a.run.seed, a.planning.max_rounds) == ("cruise", 4, 2)
    assert b.planning.max_rounds == 0 and b.ship.type_given      # "type given" survives the round trip
    assert a.study is None and b.study is None
    (only, small), = variant_configs(config, "cfg", smallest=True)
    assert only.name == "a" and small.planning.threshold == 0.5 and small.run.name == "t-smallest"


def test_random_offsets_are_seeded_bounded_and_summed_as_the_paper_does():
    a = random_offsets(200, 2.0, np.radians(20.0), np.random.default_rng(1))
    b = random_offsets(200, 2.0, np.radians(20.0), np.random.default_rng(1))
    np.testing.assert_array_equal(a, b)
    assert np.abs(a[:, :3]).max() <= 2.0 and np.abs(a[:, 3]).max() <= np.radians(20.0)
    assert np.abs(a[:, :3]).max() > 1.9                               # it fills the box
    pos, rot = offset_totals(a)
    assert pos == pytest.approx(np.linalg.norm(a[:, :3], axis=1).sum())
    assert rot == pytest.approx(np.degrees(np.abs(a[:, 3])).sum())


def test_offset_rows_move_positions_and_wrap_yaw(stylized_path):
    offsets = np.zeros((len(stylized_path), 4))
    offsets[0] = [1.0, -2.0, 0.5, np.pi]
    moved = apply_offsets(stylized_path, offsets, {"note": 1})
    np.testing.assert_allclose(moved.positions[0] - stylized_path.positions[0], [1.0, -2.0, 0.5])
    np.testing.assert_allclose(np.cos(moved.yaw[0]), -np.cos(stylized_path.yaw[0]), atol=1e-12)
    assert -np.pi < moved.yaw[0] <= np.pi and moved.metadata["note"] == 1
    np.testing.assert_array_equal(moved.positions[1:], stylized_path.positions[1:])


@pytest.fixture(scope="module")
def stylized_path():
    from wrp_eval.planning.planner import plan, planning_rng
    from wrp_eval.ship.config import ShipSection
    from wrp_eval.ship.resolve import resolve_ship_full
    ship = resolve_ship_full(ShipSection())
    return plan(ship.proxy, ship.complexity.complexity, ExperimentConfig().planning, planning_rng(0)).path


@pytest.mark.parametrize("table", range(1, 9))
def test_every_paper_config_is_valid_and_carries_the_papers_figures(table):
    config = load_experiment(PAPER / f"table{table}.yaml")
    assert config.study is not None and config.study.table == table
    assert config.run.name == f"paper-table{table}"
    assert any(v.paper for v in config.study.variants)     # the anchors are in the config, not only in comments
    assert len(variant_configs(config, "cfg")) == len(config.study.variants)


def _run_smallest(table, tmp_path, monkeypatch, config: Path | None = None) -> tuple[dict, str]:
    """Run table ``table``'s paper config (or ``config``, a study of that table) at its smallest setting in
    ``tmp_path``; returns its study.json and report.md after checking what every study writes."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(config or PAPER / f"table{table}.yaml"), "--smallest"]) == 0
    out = tmp_path / "logs" / f"paper-table{table}-smallest"
    doc = json.loads((out / "study.json").read_text())
    report = (out / "report.md").read_text()
    assert doc["smallest"] and f"Table {table}" in report
    # run.rrd: one recording per variant, named <run>/<variant>, each with the ship and the planned views
    from rerun.chunk import RrdReader
    reader = RrdReader(str(out / "run.rrd"))
    stores = {store.recording_id: store for store in reader.recordings()}
    assert set(stores) == {f"paper-table{table}-smallest/{name}" for name in {r["variant"] for r in doc["rows"]}}
    for store in stores.values():
        entities = {chunk.entity_path for chunk in reader.stream(store=store)}
        assert {"/ship/mesh", "/plan/tour", "/plan/views/0000"} <= entities
    header = next(line for line in report.splitlines() if line.startswith("| variant"))
    assert header.count("| paper ") == len(doc["columns"])           # the paper's column beside every one of ours
    for row in doc["rows"]:
        assert row["variant"] in report
        ours = row["ours"]
        assert ours["views"] >= ours["adopted"] >= 0
        assert ours["images_adopted"] == f"{ours['views']}/{ours['adopted']}"
        assert ours["failed"] or (ours["error_m"] is not None and ours["error_m"] > 0)
        assert Path(row["folder"], "plan", "path.json").is_file()
    return doc, report


def _top_view_z(row: dict) -> float:
    """Height (m) of the highest viewpoint of a variant's planned path."""
    return float(FlightPath.load(Path(row["folder"], "plan", "path.json")).positions[:, 2].max())


def test_table1_smallest_plans_on_the_disturbed_proxy(tmp_path, monkeypatch):
    doc, _ = _run_smallest(1, tmp_path, monkeypatch)
    original, disturbed = doc["rows"]
    variant = load_experiment(PAPER / "table1.yaml").study.variants[1]
    assert disturbed["variant"] == variant.name
    fraction = variant.overrides["ship"]["proxy_height_error"]
    # the variant's override reached its proxy ...
    height, shift = original["ours"]["proxy_height_m"], disturbed["ours"]["height_disturbance_m"]
    assert original["ours"]["height_disturbance_m"] == 0.0 and shift != 0.0
    assert shift == pytest.approx(fraction * height)
    assert disturbed["ours"]["proxy_height_m"] == pytest.approx(height + shift)
    # ... and its plan: the views above the deck are planned on the disturbed proxy's top, shift lower/higher
    assert _top_view_z(disturbed) - _top_view_z(original) == pytest.approx(shift, abs=1e-6)


def test_table2_smallest_maximisation_raises_h(tmp_path, monkeypatch):
    doc, _ = _run_smallest(2, tmp_path, monkeypatch)
    min_only, min_max = (r["ours"] for r in doc["rows"])
    assert min_max["H"] > min_only["H"] and min_only["max_s"] < min_max["max_s"]
    assert min_only["minmax_s"] == pytest.approx(min_only["min_s"] + min_only["max_s"])


def test_table6_smallest_drops_the_transition_views(tmp_path, monkeypatch):
    doc, report = _run_smallest(6, tmp_path, monkeypatch)
    ours, zhou = (r["ours"] for r in doc["rows"])
    assert ours["transition_views"] > zhou["transition_views"] and ours["views"] > zhou["views"]
    assert "![stylized ours](study/stylized_ours/path.png)" in report


def test_table7_and_table8_smallest(tmp_path, monkeypatch):
    doc, _ = _run_smallest(7, tmp_path / "7", monkeypatch)
    ours, zhou = (r["ours"] for r in doc["rows"])
    assert zhou["transition_views"] == 0 < ours["transition_views"]   # zhou2020 plans no transition views
    assert all(r["ours"]["tsp_s"] > 0 for r in doc["rows"])
    doc, _ = _run_smallest(8, tmp_path / "8", monkeypatch)
    ours, op = (r["ours"] for r in doc["rows"])
    assert ours["pitch_deg"] is None and op["views"] > ours["views"]
    # the OP variant's overrides reached its flown path: nadir plus four obliques at the configured pitch ...
    planning = load_experiment(PAPER / "table8.yaml").study.variants[1].overrides["planning"]
    path = FlightPath.load(Path(doc["rows"][1]["folder"], "plan", "path.json"))
    pitch = np.round(np.degrees(path.pitch), 6)
    assert set(pitch) == {-90.0, -planning["oblique_pitch_deg"]}
    nadir = path.positions[pitch == -90.0]
    assert (pitch != -90.0).sum() == 4 * len(nadir)
    # ... flown on a grid whose spacing the overlaps set: stations no further apart than footprint x (1 - overlap)
    width, length = path.camera.footprint_m(path.metadata["planned_distance_m"])
    for axis, footprint, overlap in ((0, length, planning["front_overlap"]), (1, width, planning["side_overlap"])):
        stations = np.unique(np.round(nadir[:, axis], 6))
        extent = stations[-1] - stations[0]
        assert len(stations) - 1 == int(np.ceil(extent / (footprint * (1.0 - overlap))))


def _variants(doc: dict, *names: str) -> list[dict]:
    """The variants ``names`` of a study config's document, in that order."""
    by_name = {v["name"]: v for v in doc["study"]["variants"]}
    return [by_name[name] for name in names]


@pytest.fixture(scope="module")
def tables_3_to_5_smallest(tmp_path_factory):
    """Tables 3, 4 and 5 share their base config (the same ship, plan, wind, campaign and surrogate sections; checked
    here): one study of table 3's base with the variants of each kind from all three, at the tables' smallest setting,
    runs every mechanism they run once (the tables' own --smallest runs: `wrp-eval bench --only study`)."""
    docs = {n: yaml.safe_load((PAPER / f"table{n}.yaml").read_text()) for n in (3, 4, 5)}

    def shared(doc: dict) -> dict:      # all but the run's name and the table's own rows and headings
        return {**doc, "run": {k: v for k, v in doc["run"].items() if k != "name"},
                "study": {k: v for k, v in doc["study"].items() if k not in ("table", "title", "columns", "variants")}}
    assert shared(docs[4]) == shared(docs[3]) == shared(docs[5])
    docs[3]["study"]["variants"] = (
        _variants(docs[3], "initial path", "ISWRP 0.20", "ISWRP 0.30", "SWRP 0.30", "ISWRP 0.30 Alg. 3 as written")
        + _variants(docs[4], "no-WRP path + random offsets") + _variants(docs[5], "SWRP 0.30 + secondary offsets"))
    folder = tmp_path_factory.mktemp("tables-3-5")
    config = folder / "table3.yaml"
    config.write_text(yaml.safe_dump(docs[3]))
    with pytest.MonkeyPatch.context() as monkeypatch:
        doc, _ = _run_smallest(3, folder, monkeypatch, config)
    return doc, docs[3]["study"]["variants"], folder


def test_tables_3_to_5_smallest_share_one_surrogate_across_the_wrps(tables_3_to_5_smallest):
    doc, variants, _ = tables_3_to_5_smallest
    assert [r["variant"] for r in doc["rows"]] == [v["name"] for v in variants for _ in range(v.get("repetitions", 1))]
    assert len(doc["shared_training"]) == 1
    rows = {r["variant"]: r for r in doc["rows"]}
    e0 = rows["initial path"]["ours"]["error_m"]
    wrp = [(v, rows[v["name"]]) for v in variants if v.get("path") and not v.get("random_offsets")]
    assert len(wrp) == 4
    for variant, row in wrp:   # each variant's threshold fraction reached its optimisation, against E_original
        ours = row["ours"]
        assert ours["e_original_m"] == pytest.approx(e0) and row["path"] == variant["path"]
        assert ours["threshold_m"] == pytest.approx(variant["overrides"]["wrp"]["threshold_fraction"] * e0)
        assert 0 <= ours["offset_rate_pct"] <= 100 and ours["wrp_time_s"] > 0
    assert rows["initial path"]["path"] == "plan"


def test_tables_4_and_5_smallest_offset_rows(tables_3_to_5_smallest):
    doc, _, folder = tables_3_to_5_smallest     # the rows' folders are relative to the study's working folder
    for variant, path in (("no-WRP path + random offsets", "plan"), ("SWRP 0.30 + secondary offsets", "swrp")):
        offset_rows = [r for r in doc["rows"] if r["variant"] == variant]
        assert all(r["random_offsets"] and r["path"] == path for r in offset_rows)
        assert [r["repetition"] for r in offset_rows] == [1, 2, 3, 4, 5]
        totals = [r["ours"]["position_offset_m"] for r in offset_rows]
        n = offset_rows[0]["ours"]["views"]
        assert len(set(totals)) == 5 and all(0 < t <= n * 2.0 * np.sqrt(3) for t in totals)
        assert all(r["ours"]["wrp_time_s"] is None and r["paper"]["wrp_time_s"] is None for r in offset_rows)
        assert all((folder / r["folder"] / f"offsets-{r['repetition']}" / "path.json").is_file() for r in offset_rows)
        # the offset paths are drawn beside their variant's plan in its recording
        from rerun.chunk import RrdReader
        reader = RrdReader(str(folder / "logs" / "paper-table3-smallest" / "run.rrd"))
        store = next(s for s in reader.recordings() if s.recording_id.endswith("/" + variant))
        entities = {chunk.entity_path for chunk in reader.stream(store=store)}
        assert {f"/paths/offsets-{k}/tour" for k in range(1, 6)} <= entities
        assert ("/plan/tour" if path == "plan" else f"/paths/{path}/tour") in entities     # and the path they offset


def test_a_variant_reuses_what_an_earlier_one_resolved_only_where_its_sections_match():
    from wrp_eval.experiment import ExperimentContext

    base = ExperimentConfig.model_validate({"ship": {"type": "fishing"}})
    first = ExperimentContext(base, Path("."), "cfg")
    plan, scored = first.planned, first.scored_ship
    same = ExperimentContext(base.model_copy(update={"wrp": base.wrp.model_copy(update={"iterations": 7})}),
                             Path("."), "cfg")
    same.reuse_from(first)
    assert same.planned is plan and same.scored_ship is scored and same.ship is first.ship
    replanned = ExperimentContext(base.model_copy(update={"planning": base.planning.model_copy(
        update={"distance_m": 40.0})}), Path("."), "cfg")
    replanned.reuse_from(first)
    assert replanned.ship is first.ship and replanned.scored_ship is scored and "planned" not in replanned.__dict__
    reseeded = ExperimentContext(base.model_copy(update={"run": base.run.model_copy(update={"seed": 9})}),
                                 Path("."), "cfg")
    reseeded.reuse_from(first)
    assert "planned" not in reseeded.__dict__ and reseeded.scored_ship is scored
    other_oracle = ExperimentContext(base.model_copy(update={"campaign": base.campaign.model_copy(
        update={"oracle": "colmap"})}), Path("."), "cfg")
    other_oracle.reuse_from(first)
    assert other_oracle.planned is plan and "scored_ship" not in other_oracle.__dict__
    elsewhere = ExperimentContext(base, Path("other"), "cfg")
    elsewhere.reuse_from(first)
    assert not {"ship", "planned", "scored_ship"} & set(elsewhere.__dict__)


def test_a_study_plans_once_for_its_variants_that_share_the_planning(tmp_path, monkeypatch):
    import wrp_eval.experiment as experiment

    calls = []
    real_plan = experiment.plan
    monkeypatch.setattr(experiment, "plan", lambda *args: calls.append(args[2]) or real_plan(*args))
    monkeypatch.chdir(tmp_path)
    cfg = tmp_path / "study.yaml"
    cfg.write_text("run: {name: reuse}\nship: {type: fishing}\nstudy: {columns: [views, error_m], variants: [\n"
                   "  {name: a}, {name: b, overrides: {wrp: {iterations: 5}}},\n"
                   "  {name: c, overrides: {planning: {distance_m: 40.0}}}]}\n")
    assert main(["run", str(cfg)]) == 0
    assert [section.distance_m for section in calls] == [None, 40.0]      # a and b share one plan; c plans its own
    rows = json.loads((tmp_path / "logs" / "reuse" / "study.json").read_text())["rows"]
    assert rows[0]["ours"]["views"] == rows[1]["ours"]["views"] != rows[2]["ours"]["views"]
