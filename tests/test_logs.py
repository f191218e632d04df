"""The jobs take no quiet / progress flag: the command line decides through the wrp_eval.progress logger."""

import logging

from wrp_eval.cli import main
from wrp_eval.logs import progress_log, progress_shown


def test_quiet_silences_the_progress_logger_and_a_plain_command_shows_it(tmp_path):
    # --cv 1 is refused before anything runs: only the logging set-up of main() takes effect
    assert main(["train", str(tmp_path / "x.yaml"), "--cv", "1", "--quiet"]) == 2
    assert progress_log.getEffectiveLevel() == logging.WARNING and not progress_shown()
    assert main(["train", str(tmp_path / "x.yaml"), "--cv", "1"]) == 2
    assert progress_shown() and logging.getLogger("wrp_eval").isEnabledFor(logging.INFO)


def test_run_shows_progress_only_when_asked(tmp_path):
    missing = str(tmp_path / "missing.yaml")
    assert main(["run", missing]) == 2
    assert not progress_shown()
    assert main(["run", missing, "--progress"]) == 2
    assert progress_shown()
