"""The layered import contract (.importlinter): stages in pipeline order, the CLI on top, no circle."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")


def _lint(cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(cwd)}
    return subprocess.run([str(LINT), "--no-cache"], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def test_the_package_keeps_its_import_contract():
    done = _lint(ROOT)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "0 broken" in done.stdout


def test_an_upward_import_breaks_the_contract(tmp_path):
    """The contract is not vacuous: a stage importing a later stage (here ship -> wrp) is refused."""
    shutil.copytree(ROOT / "wrp_eval", tmp_path / "wrp_eval", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / ".importlinter", tmp_path / ".importlinter")
    init = tmp_path / "wrp_eval" / "ship" / "__init__.py"
    init.write_text(init.read_text() + "\nimport wrp_eval.wrp.jobs  # an upward import\n")
    done = _lint(tmp_path)
    assert done.returncode != 0
    assert "wrp_eval.ship is not allowed to import wrp_eval.wrp" in done.stdout
