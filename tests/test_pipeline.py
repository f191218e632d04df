"""`wrp-eval run` end to end on a small config: every stage's output, the report, the recording, the
missions; a second run with the same seed reproduces the same numbers (the campaigns resume)."""

import json

import pytest

from wrp_eval.campaign.rerun_log import read_trial_ids
from wrp_eval.cli import main

SMALL = """
run: {name: pipeline-test, seed: 3}
ship: {type: fishing}
wind: {speed_10m_m_s: 5.0, turbulence: {severity: light}}
campaign:
  n_trials: 12
  batch_size: 12
  wind: {speed_10m_m_s: {dist: uniform, low: 2.0, high: 6.0}, turbulence: {severity: light}}
  perturbation: {design: box, position_half_width_m: 1.0, yaw_half_width_deg: 10.0}
  backend: {kind: local, workers: 1}
surrogate: {epochs: 20, use_failed_trials: true, validation_moves: 8}   # the fishing path registers 8-10 of 17
                                                                        # views: most trials fail
wrp: {iterations: 50, acceptance: paper, evaluate: {n_trials: 4, placebos: 2, forecast_trials: 4},
      robust: {screen_flights: 4}}
envelope: {run_grid: {speeds_m_s: [0, 8], directions: 2, max_flights: 4, look_flights: 4, resolution_m_s: 8}}
"""


@pytest.mark.slow
def test_run_writes_report_recording_and_missions_and_is_reproducible(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    cfg = tmp_path / "small.yaml"
    cfg.write_text(SMALL)
    assert main(["run", str(cfg)]) == 0
    printed = capsys.readouterr().out
    out = tmp_path / "logs" / "pipeline-test"
    assert "rerun logs/pipeline-test/run.rrd" in printed and "logs/pipeline-test/report.md" in printed
    report = (out / "report.md").read_text()
    assert report.split("\n## ")[1].startswith("Go / no-go")           # the operator's first page
    for heading in ("## Go / no-go", "### Wind envelope", "**Earth frame**", "## Ship and path",
                    "## Monte Carlo campaign", "## Surrogate", "## ISWRP and SWRP",
                    "## Robustness", "## Per-view risk", "## Missions"):
        assert heading in report
    for png in ("figures/ship_path.png", "figures/wind_field.png", "figures/offsets.png", "figures/view_risk.png",
                "surrogate/parity.png", "evaluate/boxplot.png", "envelope/envelope.png"):
        assert (out / png).stat().st_size > 1000, png
    assert sorted(read_trial_ids(out / "run.rrd")) == list(range(12))
    for name in ("initial", "iswrp", "swrp"):
        assert (out / "missions" / f"{name}.plan").is_file() and (out / "missions" / f"{name}.kmz").is_file()
    first = json.loads((out / "run_summary.json").read_text())
    assert first["campaign"]["trials"] == 12 and len(first["evaluate"]["paths"]) == 3
    # the verdict: every WRP against its placebos, and the path to fly, in the summary and the report
    for kind, verdict in first["evaluate"]["robustness"].items():   # placebos only for a WRP that moved
        moved = first["evaluate"]["wrp"][kind]["moved"]
        assert verdict["placebos_flown"] == (2 if moved else 0)
        assert moved or "moved no viewpoint" in verdict["reason"]
    assert first["evaluate"]["recommended_path"] in ("initial", "iswrp", "swrp")
    assert first["envelope"]["path"] == first["evaluate"]["recommended_path"]
    assert set(first["envelope"]["boundaries_m_s"]) == {"bow", "stern"}
    assert f"Path to fly: {first['evaluate']['recommended_path']}" in report
    sources = json.loads((out / "error_sources.json").read_text())
    assert set(sources["flights"]) <= set(range(12))
    if sources["sources"]:       # the flights that did not fail, re-scored without each capture error
        assert "## Where the error's spread comes from" in report and "| position |" in report

    assert main(["run", str(cfg)]) == 0
    second = json.loads((out / "run_summary.json").read_text())
    for key in ("plan", "campaign", "surrogate"):
        a, b = dict(first[key]), dict(second[key])
        for volatile in ("timings", "trials_per_min"):
            a.pop(volatile, None), b.pop(volatile, None)
        assert a == b, key
    assert first["evaluate"]["paths"] == second["evaluate"]["paths"]


def test_the_missions_of_every_path_the_evaluation_built_are_exported(tmp_path, monkeypatch):
    import numpy as np

    from tests.surrogate.helpers import make_path
    from wrp_eval.config import ExperimentConfig
    from wrp_eval.experiment import ExperimentContext
    from wrp_eval.export.formats import FORMATS
    from wrp_eval.pipeline import export_missions

    monkeypatch.chdir(tmp_path)
    config = ExperimentConfig.model_validate({
        "run": {"name": "missions-test"}, "ship": {"type": "fishing"}, "sim": {"capture": {"mode": "fly-through"}},
        "wrp": {"evaluate": {"kinds": [], "capture_stops": True, "slow_legs": True}}})
    ctx = ExperimentContext(config, tmp_path)
    path = make_path(16)        # a ring round the ship (no planning: the export is what is tested)
    ctx.folders.plan.mkdir(parents=True)
    path.save(ctx.folders.plan / "path.json")
    stop = np.zeros(len(path), dtype=bool)
    stop[2] = True
    ctx.folders.evaluated_wrp("stops").mkdir(parents=True)       # the slow-legs lever changed nothing: no path
    path.with_stops(stop, "fly-through").save(ctx.folders.evaluated_wrp("stops") / "path.json")
    missions = export_missions(ctx)
    assert set(missions) == {"initial", "stops"}
    back = FORMATS["qgc-plan"].read(next(f for f in missions["stops"] if f.endswith(".plan")))
    assert back.stop.sum() == 1 and back.turn_mode == "mixed"
