"""kill -9 in the middle of an envelope: re-running the same command finishes it without flying a stored flight
again, and gives the envelope of an uninterrupted run (the analytic stand-in evaluator in a subprocess, which
kill -9s it when it first meets a 12 m/s flight)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

from tests.envelope.conftest import cells_without_folders, fly
from wrp_eval.envelope.result import Envelope

SCRIPT = textwrap.dedent("""
    import sys

    from tests.kill_once import kill_session_once
    from wrp_eval.campaign.evaluators import make_analytic_evaluator


    class KillingEvaluator:
        # the analytic evaluator, except that the first batch holding a 12 m/s flight kill -9s the session
        def __init__(self, context, marker, **options):
            self.inner = make_analytic_evaluator(context, **options)
            self.marker = marker

        def evaluate(self, batch):
            if any(t.wind.speed_10m_m_s == 12.0 for t in batch):
                kill_session_once(self.marker)
            return self.inner.evaluate(batch)


    if __name__ == "__main__":
        from pathlib import Path
        from tests.envelope.conftest import FAIL_SPEED, GRID, envelope_context
        from wrp_eval.envelope.jobs import envelope_job
        tmp, marker = Path(sys.argv[1]), sys.argv[2]
        job = envelope_job(envelope_context(tmp), GRID, out_dir=tmp / "env", evaluator="__main__:KillingEvaluator",
                           evaluator_options={"marker": marker, "fail_speed_m_s": FAIL_SPEED})
        print(job.envelope.flights_flown)
""")


def _run(tmp_path) -> tuple[int, str]:
    script = tmp_path / "envelope_script.py"
    script.write_text(SCRIPT)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    proc = subprocess.Popen([sys.executable, str(script), str(tmp_path), str(tmp_path / "killed.marker")],
                            start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    try:
        out, err = proc.communicate(timeout=180)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        raise
    assert proc.returncode in (0, -signal.SIGKILL), err.decode()[-2000:]
    return proc.returncode, out.decode()


def test_a_killed_envelope_resumes_to_the_uninterrupted_result(tmp_path):
    code, _ = _run(tmp_path)
    assert code == -signal.SIGKILL
    stored_before = sum(1 for _ in (tmp_path / "env" / "cells").rglob("*.parquet"))
    assert stored_before > 0                                   # some looks were stored before the kill
    code, out = _run(tmp_path)
    assert code == 0
    resumed = Envelope.from_json_dict(json.loads((tmp_path / "env" / "envelope.json").read_text()))
    whole = fly(tmp_path, out="uninterrupted")
    assert cells_without_folders(resumed) == cells_without_folders(whole.envelope)
    # the resumed run flew fewer flights than the whole envelope holds: the stored looks were not flown again
    assert 0 < int(out.strip().splitlines()[-1]) < whole.envelope.flights_total
