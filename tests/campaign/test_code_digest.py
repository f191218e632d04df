"""The code digest in a campaign's fingerprint: which sources it covers and that an edit of one changes it."""

from __future__ import annotations

import subprocess
import sys

import pytest

from wrp_eval.campaign.code_digest import module_closure, trial_code_digest
from wrp_eval.campaign.evaluators import DEFAULT_EVALUATOR, RENAMED_EVALUATORS
from wrp_eval.errors import InputError


def test_the_closure_holds_every_wrp_eval_module_a_flight_trial_imports():
    """A fresh interpreter importing the flight evaluator loads no wrp_eval module the digest does not cover."""
    module = DEFAULT_EVALUATOR.partition(":")[0]
    listing = f"import sys, {module}; print(' '.join(m for m in sys.modules if m.startswith('wrp_eval')))"
    loaded = subprocess.run([sys.executable, "-c", listing], check=True, capture_output=True, text=True).stdout.split()
    closure = module_closure(module)
    assert module in closure and "wrp_eval.sim.flight" in closure and "wrp_eval.recon.synthetic" in closure
    assert set(loaded) <= set(closure)
    assert not any(name.startswith(("wrp_eval.cli", "wrp_eval.surrogate", "wrp_eval.wrp")) for name in closure)


def _write(root, files: dict[str, str]) -> None:
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)


def test_an_edit_of_an_imported_source_changes_the_digest_and_others_do_not(tmp_path, monkeypatch):
    _write(tmp_path, {"plug/__init__.py": "", "plug/evaluator.py": "from .helper import gain\n\ndef make(ctx): ...\n",
                      "plug/helper.py": "gain = 1.0\n", "plug/unused.py": "x = 1\n"})
    monkeypatch.syspath_prepend(str(tmp_path))
    assert set(module_closure("plug.evaluator")) >= {"plug", "plug.evaluator", "plug.helper"}
    assert "plug.unused" not in module_closure("plug.evaluator")

    def digest() -> str:
        trial_code_digest.cache_clear()
        return trial_code_digest("plug.evaluator:make")

    before = digest()
    _write(tmp_path, {"plug/unused.py": "x = 2\n"})
    assert digest() == before
    _write(tmp_path, {"plug/helper.py": "gain = 2.0\n"})
    assert digest() != before


def test_a_renamed_evaluator_digests_todays_module_and_one_without_source_is_refused():
    (old_name,) = [old for old, new in RENAMED_EVALUATORS.items() if new == DEFAULT_EVALUATOR]
    assert trial_code_digest(old_name) == trial_code_digest(DEFAULT_EVALUATOR)
    with pytest.raises(InputError, match="no Python source"):
        trial_code_digest("wrp_eval.no_such_module:factory")
