"""``wrp-eval reconstruct`` on a planned path and on one trial of a captures table."""

from __future__ import annotations

import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from wrp_eval.cli import main
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_parquet
from wrp_eval.recon.scenarios import reference_capture_set


@pytest.fixture
def path_file(tmp_path):
    cs = reference_capture_set(50)
    n = len(cs)
    path = FlightPath(cs.positions, cs.yaw, cs.pitch, np.zeros(n, int), np.zeros(n, int), np.zeros(n, int))
    file = tmp_path / "path.json"
    path.save(file)
    return file


@pytest.fixture
def config_file(tmp_path):
    file = tmp_path / "cfg.yaml"
    file.write_text("run:\n  seed: 3\noracle:\n  synthetic:\n    rays_x: 32\n    rays_y: 22\n")
    return file


def _captures_table(file, path: FlightPath, taken_trial1: np.ndarray):
    n = len(path)
    rows = {"trial": np.repeat([0, 1], n), "view": np.tile(np.arange(n), 2),
            "taken": np.concatenate([np.ones(n, bool), taken_trial1]),
            "x_m": np.tile(path.positions[:, 0], 2), "y_m": np.tile(path.positions[:, 1], 2),
            "z_m": np.tile(path.positions[:, 2], 2), "yaw_deg": np.tile(np.degrees(path.yaw), 2),
            "pitch_deg": np.tile(np.degrees(path.pitch), 2)}
    pq.write_table(pa.table(rows), file)


def test_reconstruct_planned_path_json(path_file, config_file, capsys):
    assert main(["reconstruct", str(config_file), "--path", str(path_file), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["oracle"] == "synthetic" and out["total_views"] == 50 and not out["failed"]
    assert out["registered_views"] == 50 and 0.5 < out["completeness"] <= 1.0


def test_reconstruct_one_trial_of_captures(path_file, config_file, tmp_path, capsys):
    path = FlightPath.load(path_file)
    taken = np.zeros(len(path), bool)
    taken[:4] = True  # trial 1 lost all but four views
    table = tmp_path / "captures.parquet"
    _captures_table(table, path, taken)
    cs = captures_from_parquet(table, 1, path)
    assert len(cs) == 4 and list(cs.planned_index) == [0, 1, 2, 3]
    np.testing.assert_allclose(cs.yaw, path.yaw[:4])
    assert main(["reconstruct", str(config_file), "--path", str(path_file), "--captures", str(table),
                 "--trial", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["total_views"] == 4
    with pytest.raises(InputError, match="no rows for trial 7"):
        captures_from_parquet(table, 7, path)


def test_reconstruct_bad_input_exits_2(config_file, tmp_path, capsys):
    assert main(["reconstruct", str(config_file), "--path", str(tmp_path / "missing.json")]) == 2
    assert "no such path file" in capsys.readouterr().err
