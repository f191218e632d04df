"""For the kill -9 tests' subprocess scripts: kill the whole session the first time, pass every time after."""

from __future__ import annotations

import os
import signal


def kill_session_once(marker: str) -> None:
    """kill -9 this process's session (the run and its pool workers) unless ``marker`` exists; creates it first,
    so that the same command, run again, passes here (a resume)."""
    try:
        os.close(os.open(marker, os.O_CREAT | os.O_EXCL))
    except FileExistsError:
        return
    os.killpg(os.getpgid(0), signal.SIGKILL)
