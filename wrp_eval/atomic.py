"""Atomic file writes: a temporary name in the same folder, then a rename, so a reader (or a resumed run)
never sees half a file and an interrupted write loses nothing that was there before."""

from __future__ import annotations

import json
from pathlib import Path


def write_text_atomic(target: str | Path, text: str) -> Path:
    """Write ``text`` to ``target`` (creating its folder); returns the path."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(target.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(target)
    return target


def write_json_atomic(target: str | Path, doc) -> Path:
    """``doc`` as indented JSON (numpy scalars as floats)."""
    return write_text_atomic(target, json.dumps(doc, indent=1, default=float))
