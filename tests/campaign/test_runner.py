"""Running and resuming campaigns with the analytic stand-in evaluator (tests of the campaign machinery)."""

from __future__ import annotations

import json
import os
import signal
import time

import numpy as np
import pytest

from wrp_eval.campaign.records import column_array
from wrp_eval.campaign.runner import campaign_status
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError


def test_resume_skips_stored_trials_and_never_duplicates(tmp_path, path_file, make_config, comparable, run_analytic,
                                                         tiny_path):
    first = run_analytic(make_config(path_file, n_trials=6), tmp_path / "c")
    assert (first.done, first.ran) == (6, 6)
    again = run_analytic(make_config(path_file, n_trials=6), tmp_path / "c")
    assert again.ran == 0 and again.done == 6
    extended = run_analytic(make_config(path_file, n_trials=6), tmp_path / "c", overrides={"n_trials": 14})
    assert extended.ran == 8
    ids = TrialStore(tmp_path / "c").stored_ids()
    np.testing.assert_array_equal(ids, np.arange(14))
    # the whole campaign in one go gives the same records as 6 + 8
    whole = run_analytic(make_config(path_file, n_trials=14), tmp_path / "whole")
    assert comparable(TrialStore(whole.out_dir).read_table()) == comparable(TrialStore(tmp_path / "c").read_table())


def test_results_do_not_depend_on_batching(tmp_path, path_file, make_config, comparable, run_analytic, tiny_path):
    a = run_analytic(make_config(path_file, batch_size=1), tmp_path / "a")
    b = run_analytic(make_config(path_file, batch_size=5), tmp_path / "b")
    assert comparable(TrialStore(a.out_dir).read_table()) == comparable(TrialStore(b.out_dir).read_table())


def test_a_raising_trial_is_recorded_failed_with_its_error_and_the_rest_goes_on(tmp_path, path_file, make_config,
                                                                                comparable, run_analytic, tiny_path):
    config = make_config(path_file, n_trials=9, batch_size=3, backend={"max_attempts": 3})
    summary = run_analytic(config, tmp_path / "c", fail_trial_ids=[4])
    assert (summary.done, summary.failed, summary.errors) == (9, 1, 1)
    table = TrialStore(tmp_path / "c").read_table().sort_by("trial_id")
    rows = table.to_pylist()
    assert rows[4]["failed"] and "told to fail trial 4" in rows[4]["error"] and rows[4]["attempts"] == 3
    assert all(r["error"] is None and not r["failed"] and r["attempts"] == 1 for r in rows if r["trial_id"] != 4)
    assert np.isnan(rows[4]["error_m"]) and np.all(np.isnan(column_array(table, "flown_offsets")[4]))


def test_flight_failures_are_results_not_errors(tmp_path, path_file, make_config, comparable, run_analytic, tiny_path):
    config = make_config(path_file, wind={"speed_10m_m_s": {"dist": "uniform", "low": 0, "high": 10}})
    summary = run_analytic(config, tmp_path / "c", fail_speed_m_s=5.0)
    table = TrialStore(tmp_path / "c").read_table()
    speed = table.column("wind_speed_10m_m_s").to_numpy()
    np.testing.assert_array_equal(table.column("failed").to_numpy(zero_copy_only=False), speed > 5.0)
    assert summary.errors == 0 and 0 < summary.failed < summary.done


def test_common_random_numbers_across_paths(tmp_path, path_file, make_config, comparable, run_analytic, tiny_path):
    other = tmp_path / "other.json"
    tiny_path(9).save(other)
    a = TrialStore(run_analytic(make_config(path_file), tmp_path / "a").out_dir).read_table().sort_by("trial_id")
    b = TrialStore(run_analytic(make_config(other), tmp_path / "b").out_dir).read_table().sort_by("trial_id")
    for col in ("wind_speed_10m_m_s", "wind_direction_deg", "turbulence_severity", "wind_seed"):
        assert a.column(col).to_pylist() == b.column(col).to_pylist()
    assert a.column("path_digest")[0] != b.column("path_digest")[0]


def test_a_folder_of_another_campaign_is_refused(tmp_path, path_file, make_config, comparable, run_analytic, tiny_path):
    run_analytic(make_config(path_file, n_trials=3), tmp_path / "c")
    with pytest.raises(InputError, match="different config"):
        run_analytic(make_config(path_file, n_trials=3, seed=8), tmp_path / "c")


def test_settings_outside_the_flight_do_not_orphan_stored_trials(tmp_path, path_file, make_config, run_analytic):
    """Retuning the surrogate or the optimiser keeps the campaign; so does a folder written before a setting
    with an old-behaviour default was added (its stored config is validated again by today's model)."""
    import json

    from wrp_eval.config import ExperimentConfig
    out = tmp_path / "c"
    first = run_analytic(make_config(path_file, n_trials=3), out)
    doc = make_config(path_file, n_trials=5).model_dump(mode="json")
    doc["surrogate"]["epochs"], doc["wrp"]["iterations"] = 7, 9
    second = run_analytic(ExperimentConfig.model_validate(doc), out)
    assert first.ran == 3 and second.ran == 2 and second.done == 5
    # an older campaign.json: no `solo_views` in its config, and a fingerprint computed another way
    meta_file = out / "campaign.json"
    meta = json.loads(meta_file.read_text())
    del meta["config"]["campaign"]["perturbation"]["solo_views"]
    meta["fingerprint"] = "0123456789abcdef"
    meta_file.write_text(json.dumps(meta))
    assert run_analytic(make_config(path_file, n_trials=6), out).ran == 1
    # a setting a flight does read still refuses the folder
    with pytest.raises(InputError, match="different config"):
        run_analytic(make_config(path_file, n_trials=6, perturbation={"design": "box"}), out)
    # a folder flown before sim.mission (issue 26: other rules end a flight) is not extended by today's flights
    meta = json.loads(meta_file.read_text())
    del meta["config"]["sim"]["mission"]
    meta["config"]["sim"]["wind_limit_m_s"] = 10.0
    meta["fingerprint"] = "0123456789abcdef"          # computed by the code of its day
    meta_file.write_text(json.dumps(meta))
    with pytest.raises(InputError, match="different config"):
        run_analytic(make_config(path_file, n_trials=7), out)


def test_a_store_flown_by_other_code_is_never_extended_and_a_complete_one_is_used_as_it_is(
        tmp_path, path_file, make_config, run_analytic, caplog):
    """Trials flown by another version of the flight / oracle code are never extended by today's (the config alone
    does not decide a trial); a store without a recorded code digest counts as other code. A complete one is read
    as it is (nothing flown, a warning), so re-running a finished job still works."""
    out = tmp_path / "c"
    assert run_analytic(make_config(path_file, n_trials=3), out).ran == 3
    meta_file = out / "campaign.json"
    meta = json.loads(meta_file.read_text())
    assert meta["code_digest"] and len(meta["code_digest"]) == 16
    assert run_analytic(make_config(path_file, n_trials=4), out).ran == 1       # same code: resumed
    for stored in ("0123456789abcdef", None):
        changed = {**json.loads(meta_file.read_text()), "fingerprint": "0123456789abcdef", "code_digest": stored}
        meta_file.write_text(json.dumps(changed))
        with pytest.raises(InputError, match="other flight / oracle code .* trials still to fly"):
            run_analytic(make_config(path_file, n_trials=5), out)
        assert campaign_status(out)["done"] == 4                                  # nothing lost, still readable
        with caplog.at_level("WARNING"):
            assert run_analytic(make_config(path_file, n_trials=4), out).ran == 0
        assert "every trial stored" in caplog.text
        assert json.loads(meta_file.read_text())["code_digest"] == stored         # the store still says whose
    with pytest.raises(InputError, match="different config"):                     # another config: refused
        run_analytic(make_config(path_file, n_trials=4, perturbation={"design": "box"}), out)


def test_status_counts(tmp_path, path_file, make_config, comparable, run_analytic, tiny_path):
    run_analytic(make_config(path_file, n_trials=5), tmp_path / "c", fail_trial_ids=[1])
    status = campaign_status(tmp_path / "c")
    assert status["done"] == 5 and status["errors"] == 1 and status["failed"] == 1 and status["remaining"] == 0
    assert status["duplicates"] == 0
    with pytest.raises(InputError, match="not a campaign folder"):
        campaign_status(tmp_path / "nothing")


def test_local_process_pool_matches_in_process(tmp_path, path_file, make_config, comparable, run_analytic, tiny_path):
    serial = run_analytic(make_config(path_file, n_trials=8), tmp_path / "s")
    pooled = run_analytic(make_config(path_file, n_trials=8, backend={"workers": 2}), tmp_path / "p")
    assert pooled.done == 8
    workers = set(TrialStore(pooled.out_dir).read_table().column("worker").to_pylist())
    assert len(workers) >= 1 and all(":" in w for w in workers)
    assert comparable(TrialStore(serial.out_dir).read_table()) == comparable(TrialStore(pooled.out_dir).read_table())


def _workers_of(summary) -> set[str]:
    return set(TrialStore(summary.out_dir).read_table().column("worker").to_pylist())


def test_campaigns_inside_shared_process_pools_reuse_the_worker_processes(tmp_path, path_file, make_config,
                                                                         comparable, run_analytic):
    """Inside the block two campaigns run in the same worker process (host:pid), with the numbers a fresh pool
    gives; a campaign aborted in its worker (here the evaluator's set-up fails there) discards the shared pool,
    and the next one starts a fresh one; outside the block every campaign has its own process."""
    from wrp_eval.campaign.backends import shared_process_pools
    pooled = make_config(path_file, n_trials=4, backend={"workers": 1})
    with shared_process_pools():
        first = run_analytic(pooled, tmp_path / "a")
        second = run_analytic(make_config(path_file, n_trials=4, seed=8, backend={"workers": 1}), tmp_path / "b")
        assert _workers_of(first) == _workers_of(second) and len(_workers_of(first)) == 1
        # the shared worker dies while idle: the next campaign flies every trial on a fresh pool
        os.kill(int(next(iter(_workers_of(second))).rsplit(":", 1)[1]), signal.SIGKILL)
        time.sleep(0.5)
        revived = run_analytic(make_config(path_file, n_trials=4, seed=9, backend={"workers": 1}), tmp_path / "r")
        assert revived.done == 4 and _workers_of(revived) != _workers_of(first)
        with pytest.raises(RuntimeError, match="worker set-up failed"):
            run_analytic(pooled, tmp_path / "bad", no_such_option=1)
        after = run_analytic(pooled, tmp_path / "c")
        assert _workers_of(after) != _workers_of(first)
    alone = run_analytic(pooled, tmp_path / "d")
    assert _workers_of(alone) not in (_workers_of(first), _workers_of(after))
    assert comparable(TrialStore(first.out_dir).read_table()) == comparable(TrialStore(alone.out_dir).read_table())


def test_a_shared_pool_closed_while_a_run_of_it_is_still_open_is_shut_down(path_file, make_config):
    """A caller that stops reading a run (a break out of its loop) may leave batches in the shared pool: closing
    the TrialPool then shuts that pool down and unshares it, so the next campaign gets a fresh pool rather than
    one still busy with (and later torn down by) the abandoned run; a run read to its end leaves it shared."""
    from wrp_eval.campaign import backends
    from wrp_eval.campaign.config import TrialConfig
    from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
    from wrp_eval.campaign.runner import worker_spec
    from wrp_eval.planning.path import FlightPath
    config = make_config(path_file, n_trials=6, backend={"workers": 1})
    spec = worker_spec(TrialConfig(campaign=config.campaign), FlightPath.load(path_file), key="open-run",
                       root_seed=0, config_dir=None, evaluator=ANALYTIC_EVALUATOR, evaluator_options={})
    tasks = [(spec, [trial]) for trial in range(6)]
    with backends.shared_process_pools():
        with backends.TrialPool("local", 1) as pool:
            assert len(list(pool.run(tasks))) == 6
            shared = pool._pool
        assert backends._SHARED_POOLS == {(1, 1): shared}          # read to its end: kept for the next run
        with backends.TrialPool("local", 1) as pool:
            stream = pool.run(tasks)
            next(stream)                                          # the caller reads one batch and stops
            assert pool._pool is shared
        assert backends._SHARED_POOLS == {}
        with pytest.raises(RuntimeError, match="after shutdown"):
            shared.submit(int)
        stream.close()
        with backends.TrialPool("local", 1) as pool:               # the next run: a fresh pool
            assert len(list(pool.run(tasks))) == 6 and pool._pool is not shared


def test_a_worker_set_up_error_stops_the_campaign_with_its_message(tmp_path, path_file, make_config):
    """A bad input (here: the ship mesh file) is the campaign's InputError, not a pile of crashed trials (the real
    evaluator, a process-pool campaign; the mesh is found missing when the campaign resolves its ship, before
    any worker starts)."""
    from wrp_eval.campaign.jobs import campaign_job
    from wrp_eval.config import ExperimentConfig
    from wrp_eval.experiment import ExperimentContext
    doc = make_config(path_file, backend={"workers": 1}).model_dump(mode="json")
    doc["ship"]["mesh"] = {"path": str(tmp_path / "no_such_ship.stl")}
    with pytest.raises(InputError, match="no_such_ship"):
        campaign_job(ExperimentContext(ExperimentConfig.model_validate(doc)), out_dir=tmp_path / "c")
    assert TrialStore(tmp_path / "c").stored_ids().size == 0


def test_active_time_is_the_union_of_busy_intervals():
    from wrp_eval.campaign.runner import active_seconds
    start, end = np.array([5.0, 0.0, 1.0, 1.5]), np.array([6.0, 2.0, 3.0, 2.5])
    assert active_seconds(start, end) == 4.0      # [0, 3] and [5, 6]
    assert active_seconds(np.array([]), np.array([])) == 0.0


def test_split_batches_keeps_every_worker_busy_and_caps_the_size():
    from wrp_eval.campaign.backends import split_batches

    small = split_batches(32, 64, 2)       # one batch of 32 would leave the second worker idle
    assert [len(b) for b in small] == [16, 16]
    large = split_batches(200, 64, 2)
    assert max(len(b) for b in large) <= 64 and len(large) == 4
    assert np.array_equal(np.concatenate(large), np.arange(200))
    assert [len(b) for b in split_batches(3, 64, 8)] == [1, 1, 1]
    assert split_batches(0, 64, 2) == []


def test_a_store_of_the_renamed_flight_evaluator_keeps_its_fingerprint(tmp_path, path_file, make_config, run_analytic):
    from wrp_eval.campaign.evaluators import DEFAULT_EVALUATOR, RENAMED_EVALUATORS, resolve_factory
    from wrp_eval.campaign.runner import fingerprint, stored_fingerprint

    run_analytic(make_config(path_file, n_trials=3), tmp_path / "c")
    meta = json.loads((tmp_path / "c" / "campaign.json").read_text())
    (old_name,) = [old for old, new in RENAMED_EVALUATORS.items() if new == DEFAULT_EVALUATOR]
    today = fingerprint(meta["config"], meta["path_digest"], meta["root_seed"], DEFAULT_EVALUATOR,
                        meta.get("evaluator_options") or {}, meta["code_digest"])
    assert stored_fingerprint({**meta, "evaluator": old_name}) == today          # resumable under today's name
    assert stored_fingerprint({**meta, "evaluator": "other:factory"}) != today
    assert resolve_factory(old_name) is resolve_factory(DEFAULT_EVALUATOR)
