"""The envelope flown by the analytic stand-in evaluator: the search, the sequential stop, common random
numbers across cells, resume, and the files written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from tests.envelope.conftest import FAIL_SPEED, cells_without_folders, fly
from wrp_eval.campaign.store import TrialStore
from wrp_eval.envelope.result import Envelope


def test_every_direction_finds_the_boundary_and_stops_cells_early(flown):
    _, job = flown
    env = job.envelope
    assert [b.direction for b in env.boundaries] == ["bow", "stern"]
    for b in env.boundaries:
        assert b.bracket_m_s == (9.0, 10.0) and b.proved_m_s == 9.0 and not b.above_grid
        assert "reconstruction failed" in b.limit          # the analytic evaluator fails flights above 9 m/s
    cells = {(c.relative_deg, c.speed_m_s): c for c in env.cells}
    # a clearly failing cell stops at the first look, a clearly meeting one at 24 flights (3 looks)
    assert cells[(0.0, 12.0)].flights == 8 and cells[(0.0, 12.0)].decision == "fails"
    assert cells[(0.0, 4.0)].flights == 24 and cells[(0.0, 4.0)].decision == "meets"
    assert all((c.speed_m_s <= FAIL_SPEED) == c.meets for c in env.cells)
    assert env.flights_total == env.flights_flown == sum(c.flights for c in env.cells)


def test_the_forecast_cell_gives_the_verdict(flown):
    _, job = flown
    env = job.envelope
    cell = env.forecast_cell
    assert env.forecast.speed_m_s == 6.0 and env.forecast.relative_deg == 270.0   # heading 0
    assert cell.speed_m_s == 6.0 and cell.relative_deg == 270.0 and cell.decision == "meets"
    assert env.go is True


def test_flight_k_of_every_cell_draws_the_same_streams(flown):
    tmp, job = flown
    tables = [TrialStore(c.folder).read_table(["trial_id", "flight_seed", "oracle_seed", "wind_seed",
                                                "wind_speed_10m_m_s"]).sort_by("trial_id")
              for c in job.envelope.cells if c.flights == 24]
    assert len(tables) >= 3
    for table in tables[1:]:
        for name in ("flight_seed", "oracle_seed", "wind_seed"):
            assert table.column(name).to_pylist() == tables[0].column(name).to_pylist()
    speeds = {t.column("wind_speed_10m_m_s")[0].as_py() for t in tables}
    assert len(speeds) > 1                                   # and they are different winds


def test_the_calm_cell_and_the_cells_folders_are_named_by_their_key(flown):
    _, job = flown
    names = {Path(c.folder).name for c in job.envelope.cells}
    assert "r0.0_u4.0" in names and "r180.0_u9.0" in names
    assert len({Path(c.folder).parent for c in job.envelope.cells}) == 1   # one folder per path digest


def test_a_second_run_flies_nothing_and_says_the_same(flown):
    tmp, job = flown
    again = fly(tmp)
    assert again.envelope.flights_flown == 0
    assert cells_without_folders(again.envelope) == cells_without_folders(job.envelope)


def test_the_outputs_are_written_and_read_back(flown):
    _, job = flown
    files = job.files
    doc = json.loads(open(files["json"]).read())
    env = Envelope.from_json_dict(doc)
    assert json.dumps(env.to_json_dict(), sort_keys=True) == json.dumps(doc, sort_keys=True)
    assert cells_without_folders(env) == cells_without_folders(job.envelope)
    assert open(files["png"], "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    rows = open(files["csv"]).read().strip().splitlines()
    assert len(rows) == 1 + len(env.cells)
    assert open(files["rrd"], "rb").read(4) == b"RRF2"


def test_a_stricter_spec_moves_the_boundary_down(tmp_path):
    """The same flights against another spec: completeness >= 0.97 fails the analytic evaluator's flights
    from U10 ~6 m/s up (completeness exp(-0.005 U))."""
    from tests.envelope.conftest import GRID, envelope_context
    from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
    from wrp_eval.config import ExperimentConfig
    from wrp_eval.envelope.jobs import envelope_job
    ctx = envelope_context(tmp_path)
    doc = ctx.config.model_dump(mode="json")
    doc["wrp"]["evaluate"]["spec_completeness"] = 0.97
    job = envelope_job(ctx.with_config(ExperimentConfig.model_validate(doc)), GRID, out_dir=tmp_path / "strict",
                       evaluator=ANALYTIC_EVALUATOR, evaluator_options={"fail_speed_m_s": FAIL_SPEED})
    bounds = [b.boundary_m_s for b in job.envelope.boundaries]
    assert all(b is not None and b < 9.0 for b in bounds)
    assert np.all(["completeness below spec" in b.limit for b in job.envelope.boundaries])


def test_ray_flies_the_same_envelope_as_local_processes(flown):
    """The cells on Ray (a local instance, 2 CPUs) give the same envelope as the in-process run."""
    import ray
    tmp, job = flown
    on_ray = fly(tmp, out="ray", backend="ray", workers=2)
    assert not ray.is_initialized()
    assert cells_without_folders(on_ray.envelope) == cells_without_folders(job.envelope)
