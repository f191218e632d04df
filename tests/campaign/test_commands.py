"""``wrp-eval campaign CONFIG`` / ``campaign run CONFIG`` / ``campaign status DIR`` through the CLI."""

from __future__ import annotations

import json

import yaml

from wrp_eval.cli import main


def test_cli_status_of_a_campaign_and_bad_inputs(tmp_path, path_file, make_config, run_analytic, capsys):
    run_analytic(make_config(path_file, n_trials=4), tmp_path / "c")
    assert main(["campaign", "status", str(tmp_path / "c"), "--json"]) == 0
    status = json.loads(capsys.readouterr().out)
    assert (status["done"], status["remaining"], status["n_trials"]) == (4, 0, 4)
    assert main(["campaign", "status", str(tmp_path / "missing")]) == 2
    assert "not a campaign folder" in capsys.readouterr().err
    assert main(["campaign", "status"]) == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({"campaign": {"n_trials": -1}}))
    assert main(["campaign", str(bad)]) == 2
    assert "n_trials" in capsys.readouterr().err


def test_cli_run_needs_an_existing_path_file(tmp_path, capsys):
    config = tmp_path / "exp.yaml"
    config.write_text(yaml.safe_dump({"campaign": {"path": "nowhere/path.json", "n_trials": 2}}))
    assert main(["campaign", "run", str(config), "--out", str(tmp_path / "c"), "--workers", "0"]) == 2
    assert "no such path file" in capsys.readouterr().err
