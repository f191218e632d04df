"""kill -9 mid-campaign loses at most the chunk in flight; re-running completes the campaign without duplicates
(a campaign run in a subprocess with the analytic stand-in evaluator, which kill -9s it at a set trial)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from wrp_eval.atomic import temporaries
from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
from wrp_eval.campaign.jobs import campaign_job
from wrp_eval.campaign.rerun_log import read_trial_ids
from wrp_eval.campaign.store import TrialStore
from wrp_eval.experiment import ExperimentContext

N_TRIALS, KILL_AT, CHUNK_TRIALS = 60, 30, 4
REPO = Path(__file__).resolve().parents[2]

SCRIPT = textwrap.dedent("""
    import sys

    from tests.kill_once import kill_session_once
    from wrp_eval.campaign.evaluators import make_analytic_evaluator


    class KillingEvaluator:
        # The analytic evaluator, except that the first process to reach trial `kill_at` kill -9s its whole
        # session (the campaign and its pool workers) right there: a kill mid-campaign at a set trial, not after
        # a guessed time. The marker file makes the same command, run again, pass that trial (same evaluator
        # and options, so the same fingerprint: a resume).
        def __init__(self, context, kill_at, marker, **options):
            self.inner = make_analytic_evaluator(context, **options)
            self.kill_at, self.marker = kill_at, marker

        def evaluate(self, batch):
            if any(t.trial_id >= self.kill_at for t in batch):
                kill_session_once(self.marker)
            return self.inner.evaluate(batch)


    if __name__ == "__main__":  # spawned pool workers re-import this script: only the class above for them
        from wrp_eval.campaign.jobs import campaign_job
        from wrp_eval.config import ExperimentConfig
        from wrp_eval.experiment import ExperimentContext
        path, out, workers, n_trials, kill_at, chunk_trials, marker = sys.argv[1:]
        config = ExperimentConfig.model_validate({"campaign": {
            "path": path, "n_trials": int(n_trials), "batch_size": 2, "seed": 3,
            "backend": {"workers": int(workers)}, "outputs": {"rerun": True, "chunk_trials": int(chunk_trials)}}})
        campaign_job(ExperimentContext(config), out_dir=out, evaluator="__main__:KillingEvaluator",
                     evaluator_options={"kill_at": int(kill_at), "marker": marker})
""")


def _run(tmp_path, path_file, workers) -> int:
    """Run the campaign script to its end (or its kill); returns its exit status (-9: killed)."""
    script = tmp_path / "campaign_script.py"
    script.write_text(SCRIPT)
    proc = subprocess.Popen([sys.executable, str(script), str(path_file), str(tmp_path / "c"), str(workers),
                             str(N_TRIALS), str(KILL_AT), str(CHUNK_TRIALS), str(tmp_path / "killed.marker")],
                            start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            env={**os.environ, "PYTHONPATH": str(REPO)})   # the script imports tests.kill_once
    try:
        _, err = proc.communicate(timeout=180)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)   # its own session: the campaign and its pool workers
        raise
    assert proc.returncode in (0, -signal.SIGKILL), err.decode()[-2000:]
    return proc.returncode


def test_kill_9_mid_campaign_then_rerun_completes_without_duplicates(tmp_path, path_file, comparable,
                                                                     make_config):
    assert _run(tmp_path, path_file, workers=0) == -signal.SIGKILL   # kill -9 while evaluating trial KILL_AT
    store = TrialStore(tmp_path / "c")
    partial = store.stored_ids()
    # one trial after another: whole chunks of the trials before the kill; the chunk in flight is all it lost
    assert KILL_AT - CHUNK_TRIALS < partial.size <= KILL_AT
    np.testing.assert_array_equal(partial, np.arange(partial.size))

    assert _run(tmp_path, path_file, workers=0) == 0   # the same command again resumes
    np.testing.assert_array_equal(store.stored_ids(), np.arange(N_TRIALS))   # complete and unique
    # the resumed campaign's records equal those of an uninterrupted one
    config = make_config(path_file, n_trials=N_TRIALS, batch_size=2, seed=3)
    fresh = campaign_job(ExperimentContext(config), out_dir=tmp_path / "fresh", evaluator=ANALYTIC_EVALUATOR)
    assert comparable(store.read_table()) == comparable(TrialStore(fresh.out_dir).read_table())
    np.testing.assert_array_equal(read_trial_ids(tmp_path / "c" / "campaign.rrd"), np.arange(N_TRIALS))
    assert temporaries(tmp_path / "c") == [] and temporaries(store.trials_dir) == []


@pytest.mark.slow
def test_kill_9_of_a_process_pool_campaign(tmp_path, path_file):
    assert _run(tmp_path, path_file, workers=2) == -signal.SIGKILL
    store = TrialStore(tmp_path / "c")
    partial = store.stored_ids()
    assert partial.size < N_TRIALS and np.unique(partial).size == partial.size   # the batch of KILL_AT is lost
    assert _run(tmp_path, path_file, workers=2) == 0
    np.testing.assert_array_equal(store.stored_ids(), np.arange(N_TRIALS))
