"""How the jobs report: every line through :mod:`logging` under ``wrp_eval``; what a user may silence (the
per-step lines and the progress bars) under the child logger ``wrp_eval.progress`` (:data:`PROGRESS`).

The command line shows wrp_eval's INFO on stderr and raises :data:`PROGRESS` to WARNING for ``--quiet``
(``wrp-eval run``: unless ``--progress``); a program that configures no logging sees neither, so no job takes a
``quiet`` or ``progress`` argument."""

from __future__ import annotations

import logging

PROGRESS = "wrp_eval.progress"
progress_log = logging.getLogger(PROGRESS)


def progress_shown() -> bool:
    """Whether progress bars are drawn: :data:`PROGRESS` is enabled for INFO."""
    return progress_log.isEnabledFor(logging.INFO)
