"""Progress of a campaign: a rich bar on a terminal, plain lines (every ``interval_s``) in CI logs."""

from __future__ import annotations

import os
import sys
import time

from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeRemainingColumn,
)


def _is_interactive(stream) -> bool:
    return bool(getattr(stream, "isatty", lambda: False)()) and not os.environ.get("CI")


class CampaignProgress:
    """Counts trials done and failed this session; shows trials/min and ETA. ``enabled=False`` is silent."""

    def __init__(self, total: int, already_done: int, *, enabled: bool = True, stream=None, interval_s: float = 10.0):
        self.total, self.done, self.failed = total, already_done, 0
        self.session_done = 0
        self.start = time.perf_counter()
        self.enabled = enabled
        self.stream = stream or sys.stderr
        self.interval_s = interval_s
        self._last_line = 0.0
        self._bar = None
        if enabled and _is_interactive(self.stream):
            self._bar = Progress(TextColumn("campaign"), BarColumn(), MofNCompleteColumn(),
                                 TextColumn("{task.fields[rate]:.1f} trials/min"), TimeRemainingColumn(),
                                 TextColumn("failed {task.fields[failed]}"), transient=False)
            self._task = self._bar.add_task("trials", total=total, completed=already_done, rate=0.0, failed=0)
            self._bar.start()

    @property
    def trials_per_min(self) -> float:
        elapsed = time.perf_counter() - self.start
        return 60.0 * self.session_done / elapsed if elapsed > 0 else 0.0

    def eta_s(self) -> float:
        rate = self.trials_per_min / 60.0
        return (self.total - self.done) / rate if rate > 0 else float("inf")

    def update(self, n_done: int, n_failed: int) -> None:
        self.done += n_done
        self.session_done += n_done
        self.failed += n_failed
        if not self.enabled:
            return
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done, rate=self.trials_per_min, failed=self.failed)
            return
        now = time.perf_counter()
        if now - self._last_line >= self.interval_s or self.done >= self.total:
            self._last_line = now
            eta = self.eta_s()
            eta_text = f"{eta / 60:.1f} min" if eta != float("inf") else "?"
            print(f"campaign: {self.done}/{self.total} trials, {self.trials_per_min:.1f} trials/min, "
                  f"ETA {eta_text}, failed {self.failed}", file=self.stream, flush=True)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
