"""One way to write a rerun recording file (.rrd): open a stream with an id, log, save atomically.

Every stage that records (ship, plan, campaign, ...) writes through :func:`recording`, so each .rrd is
written the same way: a ``rerun.RecordingStream`` (rerun-sdk 0.41 API: ``RecordingStream(application_id,
recording_id=...)``, ``save(path, default_blueprint=...)``, ``flush()``, ``disconnect()``) whose file sink
is a temporary beside the target (:func:`wrp_eval.atomic.atomic_path`), flushed, closed, fsync'ed and
renamed onto the target only when the block ends normally. A failure, or a kill, leaves an existing
recording as it was.

Recordings of one run share :data:`APPLICATION_ID` and, where they should merge into one recording
(``rerun rrd merge``), a recording id.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import rerun as rr
import rerun.blueprint as rrb

from wrp_eval.atomic import atomic_path

APPLICATION_ID = "wrp-eval"  # one application for every stage's recording, so a run's recordings merge


@contextmanager
def recording(target: str | Path, *, recording_id: str | None = None, application_id: str = APPLICATION_ID,
              default_blueprint: rrb.BlueprintLike | None = None) -> Iterator[rr.RecordingStream]:
    """Yield a ``rerun.RecordingStream`` saving to a temporary beside ``target``; on a normal exit flush it,
    close the file and move it onto ``target`` (atomically, fsync'ed); on an exception close it, remove the
    temporary and re-raise.

    ``recording_id``: None gives rerun's random id (a recording of its own); the same id in several files
    makes them one recording once merged. ``default_blueprint``: a ``rerun.blueprint.Blueprint`` stored
    with the data (the viewer's default layout)."""
    with atomic_path(target) as tmp:
        stream = rr.RecordingStream(application_id, recording_id=recording_id)
        stream.save(tmp, default_blueprint=default_blueprint)
        try:
            yield stream
            stream.flush()  # everything logged reaches the file before it is closed and renamed
        finally:
            stream.disconnect()  # closes the file sink (also on an error, so the temporary can go)


def merge_recordings(parts: list[Path], target: Path) -> Path:
    """One .rrd of several recordings (a run's ship, plan and campaign; a study's variants), merged by rerun's
    own CLI (``rerun rrd merge``) into a temporary, moved onto ``target`` atomically."""
    with atomic_path(target) as tmp:
        cmd = [sys.executable, "-m", "rerun", "rrd", "merge", *map(str, parts), "-o", str(tmp)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0 or not Path(tmp).is_file():
            raise RuntimeError(f"rerun rrd merge failed: {done.stderr.strip()[-500:]}")
    return target
