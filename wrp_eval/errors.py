"""The one error type for bad user input.

Every bad input (config, AIS sentence, mesh, netCDF, checkpoint, path file) raises
:class:`InputError`; the CLI prints it as one line and exits with status 2.
"""

from __future__ import annotations

from pathlib import Path


class InputError(Exception):
    """Bad user input. ``str(err)`` is one line: ``<source>: <problem>``."""

    def __init__(self, source: str | Path, problem: str) -> None:
        self.source = str(source)
        self.problem = " ".join(str(problem).split())  # always one line
        super().__init__(f"{self.source}: {self.problem}")

    def __reduce__(self) -> tuple[type[InputError], tuple[str, str]]:
        # survive pickling between worker processes (the default would call __init__ with one argument)
        return (InputError, (self.source, self.problem))
