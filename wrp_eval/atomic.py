"""Atomic file writes: the caller writes a temporary file in the target's folder, which is then fsync'ed and
renamed over the target, so a reader (or a resumed run) never sees half a file and an interrupted or failed
write loses nothing that was there before.

:func:`atomic_path` is the one mechanism; :func:`write_bytes_atomic`, :func:`write_text_atomic` and
:func:`write_json_atomic` are built on it, and any writer that wants a file name (``np.savez``,
``matplotlib.savefig``, ``pyarrow.parquet.write_table``, ``rerun.RecordingStream.save``) writes the path it
yields.

Why each step (POSIX semantics, IEEE Std 1003.1-2017 ``rename()`` and Linux ``fsync(2)``):
  - same folder: ``rename``/``os.replace`` is atomic only within one file system;
  - fsync of the file before the rename: otherwise a power loss after the rename can leave the new name
    pointing at a file whose data never reached the disk (an empty or truncated target);
  - fsync of the folder after the rename: ``fsync(2)`` "does not necessarily ensure that the entry in the
    directory containing the file has also reached disk. For that an explicit fsync() on a file descriptor
    for the directory is also needed."
"""

from __future__ import annotations

import json
import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

TMP_PREFIX = ".tmp-"  # temporaries are hidden files ``.tmp-<uuid>-<target name>``; see :func:`temporaries`


def _fsync(path: Path, flags: int) -> None:
    fd = os.open(path, flags)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target`` (its folder is created) for the caller to write; when the
    ``with`` block ends normally, fsync that file, ``os.replace`` it onto ``target`` and fsync the folder.

    If the block raises (or writes nothing), the temporary is removed, ``target`` is left as it was and the
    exception propagates. The temporary's name is ``.tmp-<32 hex>-<target name>``: unique per call (two
    processes writing the same target never share one), hidden, and it ends with the target's own suffix, so
    writers that pick the format from the extension (``savefig``) or append one when it is missing
    (``np.savez`` adds ``.npz``) write the same file they would write to ``target``."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f"{TMP_PREFIX}{uuid.uuid4().hex}-{target.name}")
    try:
        yield tmp
        if not tmp.is_file():
            raise FileNotFoundError(f"nothing was written to {tmp} (the temporary of {target})")
        # O_RDWR, not O_RDONLY: Windows' fsync (_commit) needs a handle with write access
        _fsync(tmp, os.O_RDWR)
        os.replace(tmp, target)
    except BaseException:  # also KeyboardInterrupt / GeneratorExit: never leave the temporary behind
        tmp.unlink(missing_ok=True)
        raise
    if os.name == "posix":  # a folder cannot be opened for fsync on Windows, where NTFS journals the rename
        _fsync(target.parent, os.O_RDONLY)


def temporaries(folder: str | Path, name: str = "*") -> list[Path]:
    """Temporaries of :func:`atomic_path` left in ``folder`` (only a killed process leaves any), sorted;
    ``name``: only those of targets matching this glob pattern (e.g. ``"campaign.rrd"``)."""
    return sorted(Path(folder).glob(f"{TMP_PREFIX}*" if name == "*" else f"{TMP_PREFIX}*-{name}"))


def write_bytes_atomic(target: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``target`` atomically (creating its folder); returns the path."""
    target = Path(target)
    with atomic_path(target) as tmp:
        tmp.write_bytes(data)
    return target


def write_text_atomic(target: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``target`` atomically (creating its folder); returns the path."""
    return write_bytes_atomic(target, text.encode("utf-8"))


def write_json_atomic(target: str | Path, doc: object) -> Path:
    """``doc`` as indented JSON (numpy scalars as floats), atomically; returns the path."""
    return write_text_atomic(target, json.dumps(doc, indent=1, default=float))
