"""The campaign's folder: a Parquet dataset of trial records in atomic chunks, the resolved config, a lock.

Layout of ``<out>/``::

    campaign.json        resolved config, fingerprint, root seed, path digest, versions (written atomically)
    path.json            the path flown (a copy, so the folder is self-contained)
    trials/chunk-*.parquet   trial records; each chunk written to trials/.tmp-* then os.replace'd
    campaign.rrd         the rerun recording (see rerun_log.py)
    .lock                held (flock) by the one process writing the folder

Crash safety: a chunk becomes visible only by ``os.replace`` of a complete, fsync'ed file
(:func:`wrp_eval.atomic.atomic_path`), so a kill -9 at any moment leaves whole chunks plus at most a stray
``.tmp-*`` file (ignored, removed on the next open).
Records leave the writer's buffer only once their chunk is in place, so nothing is ever written twice.
"""

from __future__ import annotations

import fcntl
import json
import uuid
from pathlib import Path
from typing import TextIO

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from wrp_eval.atomic import atomic_path, temporaries, write_bytes_atomic
from wrp_eval.campaign.records import SCHEMA, records_to_table
from wrp_eval.errors import InputError

META_NAME = "campaign.json"
TRIALS_DIR = "trials"


class TrialStore:
    """Reader/writer of one campaign folder. Writing needs :meth:`acquire` (one writer at a time)."""

    def __init__(self, out_dir: str | Path):
        self.out_dir = Path(out_dir)
        self.trials_dir = self.out_dir / TRIALS_DIR
        self._lock_fh: TextIO | None = None
        self._next_seq: int | None = None

    # -- writer side ------------------------------------------------------------------------------------
    def acquire(self) -> None:
        """Create the folder, take the writer lock, drop leftovers of an interrupted chunk write."""
        self.trials_dir.mkdir(parents=True, exist_ok=True)
        self._lock_fh = open(self.out_dir / ".lock", "a+")
        try:
            fcntl.flock(self._lock_fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._lock_fh.close()
            self._lock_fh = None
            raise InputError(self.out_dir, "another campaign process is writing to this folder") from None
        # only the lock holder writes these, so any temporary of them is a killed writer's leftover
        owned = [*temporaries(self.trials_dir), *(t for name in (META_NAME, "path.json", "campaign.rrd")
                                                  for t in temporaries(self.out_dir, name))]
        for stray in owned:
            stray.unlink(missing_ok=True)
        seqs = [int(p.name.split("-")[1]) for p in self.chunk_files()]
        self._next_seq = max(seqs, default=-1) + 1

    def release(self) -> None:
        if self._lock_fh is not None:
            fcntl.flock(self._lock_fh.fileno(), fcntl.LOCK_UN)
            self._lock_fh.close()
            self._lock_fh = None

    def __enter__(self) -> "TrialStore":
        self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def write_meta(self, meta: dict, path_json: dict) -> None:
        write_bytes_atomic(self.out_dir / META_NAME, json.dumps(meta, indent=1, sort_keys=True).encode())
        write_bytes_atomic(self.out_dir / "path.json", json.dumps(path_json, indent=1).encode())

    def append(self, records: list[dict]) -> Path | None:
        """Write ``records`` as one new chunk (atomically). Returns the chunk's path."""
        if not records:
            return None
        if self._lock_fh is None or self._next_seq is None:
            raise RuntimeError("TrialStore.append needs acquire() first")
        table = records_to_table(records)
        target = self.trials_dir / f"chunk-{self._next_seq:06d}-{uuid.uuid4().hex[:8]}.parquet"
        with atomic_path(target) as tmp, open(tmp, "wb") as fh:
            pq.write_table(table, fh, compression="zstd")
        self._next_seq += 1
        return target

    # -- reader side ------------------------------------------------------------------------------------
    def read_meta(self) -> dict | None:
        try:
            return json.loads((self.out_dir / META_NAME).read_text())
        except FileNotFoundError:
            return None
        except (OSError, json.JSONDecodeError) as err:
            raise InputError(self.out_dir / META_NAME, f"unreadable campaign metadata: {err}") from None

    def chunk_files(self) -> list[Path]:
        return sorted(self.trials_dir.glob("chunk-*.parquet"))

    def read_table(self, columns: list[str] | None = None) -> pa.Table:
        """All stored records (every chunk), in chunk order."""
        files = self.chunk_files()
        if not files:
            return SCHEMA.empty_table() if columns is None else SCHEMA.empty_table().select(columns)
        tables = []
        for f in files:
            try:
                tables.append(pq.read_table(f, columns=columns, schema=SCHEMA))
            except (OSError, pa.ArrowInvalid) as err:
                raise InputError(f, f"unreadable trial chunk: {err}") from None
        return pa.concat_tables(tables)

    def stored_ids(self) -> np.ndarray:
        """Sorted trial ids already stored (int64)."""
        return np.sort(self.read_table(["trial_id"]).column("trial_id").to_numpy())
