"""kill -9 at any moment loses at most the chunk in flight; re-running completes the campaign without
duplicates (a campaign run in a subprocess with the analytic stand-in evaluator, a little work per trial)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
from wrp_eval.campaign.runner import run_campaign
from wrp_eval.campaign.store import TrialStore

SCRIPT = textwrap.dedent("""
    import sys
    if __name__ == "__main__":  # imports here: spawned pool workers re-import this script, keep them light
        from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
        from wrp_eval.campaign.runner import run_campaign
        from wrp_eval.config import ExperimentConfig
        config = ExperimentConfig.model_validate({"campaign": {
            "path": sys.argv[1], "n_trials": 60, "batch_size": 2, "seed": 3,
            "backend": {"workers": int(sys.argv[3])}, "outputs": {"rerun": True, "chunk_trials": 4}}})
        run_campaign(config, out_dir=sys.argv[2], evaluator=ANALYTIC_EVALUATOR,
                     evaluator_options={"sleep_s": float(sys.argv[4])}, progress=False)
""")


def _start(tmp_path, path_file, workers, sleep_s):
    script = tmp_path / "campaign_script.py"
    script.write_text(SCRIPT)
    return subprocess.Popen([sys.executable, str(script), str(path_file), str(tmp_path / "c"), str(workers),
                             str(sleep_s)], start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)


def _kill_group(proc):
    try:
        os.killpg(proc.pid, signal.SIGKILL)   # the campaign and its pool workers (its own session)
    except ProcessLookupError:
        pass
    proc.wait(timeout=10)


def test_kill_9_mid_campaign_then_rerun_completes_without_duplicates(tmp_path, path_file, comparable,
                                                                     make_config):
    proc = _start(tmp_path, path_file, workers=0, sleep_s=0.02)
    store = TrialStore(tmp_path / "c")
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (not store.trials_dir.exists() or len(store.chunk_files()) < 2):
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)   # kill -9 the campaign process itself, mid-way
    _kill_group(proc)
    partial = store.stored_ids()
    assert 8 <= partial.size < 60, f"killed too late or too early: {partial.size} trials stored"
    assert np.unique(partial).size == partial.size

    proc = _start(tmp_path, path_file, workers=0, sleep_s=0.02)   # the same command again resumes
    assert proc.wait(timeout=120) == 0, proc.stderr.read().decode()[-2000:]
    ids = store.stored_ids()
    np.testing.assert_array_equal(ids, np.arange(60))   # complete and unique
    # the resumed campaign's records equal those of an uninterrupted one
    config = make_config(path_file, n_trials=60, batch_size=2, seed=3)
    fresh = run_campaign(config, out_dir=tmp_path / "fresh", evaluator=ANALYTIC_EVALUATOR,
                         evaluator_options={"sleep_s": 0.02}, progress=False)
    assert comparable(store.read_table()) == comparable(TrialStore(fresh.out_dir).read_table())
    from wrp_eval.campaign.rerun_log import read_trial_ids
    np.testing.assert_array_equal(read_trial_ids(tmp_path / "c" / "campaign.rrd"), np.arange(60))


@pytest.mark.slow
def test_kill_9_of_a_process_pool_campaign(tmp_path, path_file):
    proc = _start(tmp_path, path_file, workers=2, sleep_s=0.02)
    store = TrialStore(tmp_path / "c")
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and (not store.trials_dir.exists() or len(store.chunk_files()) < 1):
        time.sleep(0.05)
    _kill_group(proc)
    assert store.stored_ids().size < 60
    proc = _start(tmp_path, path_file, workers=2, sleep_s=0.02)
    assert proc.wait(timeout=120) == 0, proc.stderr.read().decode()[-2000:]
    np.testing.assert_array_equal(store.stored_ids(), np.arange(60))
