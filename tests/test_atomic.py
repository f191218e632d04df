"""Atomic writes: the target is replaced only by a complete file; a failure mid-write leaves the old file and
no temporary behind."""

from __future__ import annotations

import json

import numpy as np
import pytest

from wrp_eval.atomic import (
    TMP_PREFIX,
    atomic_path,
    temporaries,
    write_bytes_atomic,
    write_json_atomic,
    write_text_atomic,
)


def test_writes_create_the_folder_and_leave_no_temporary(tmp_path):
    target = tmp_path / "a" / "b" / "doc.json"
    assert write_json_atomic(target, {"x": np.float64(1.5), "n": [1, 2]}) == target
    assert json.loads(target.read_text()) == {"x": 1.5, "n": [1, 2]}
    write_text_atomic(target, "é\n")
    assert target.read_bytes() == "é\n".encode("utf-8")
    write_bytes_atomic(target, b"\x00\x01")
    assert target.read_bytes() == b"\x00\x01"
    assert sorted(p.name for p in target.parent.iterdir()) == ["doc.json"]


def test_failure_mid_write_keeps_the_old_file_and_removes_the_temporary(tmp_path):
    target = tmp_path / "data.bin"
    target.write_bytes(b"old content")
    with pytest.raises(RuntimeError, match="disk on fire"):
        with atomic_path(target) as tmp:
            with open(tmp, "wb") as fh:
                fh.write(b"half of the new")
            assert tmp.exists() and tmp.parent == tmp_path
            raise RuntimeError("disk on fire")
    assert target.read_bytes() == b"old content"
    assert temporaries(tmp_path) == [] and sorted(tmp_path.iterdir()) == [target]


def test_a_writer_that_writes_nothing_is_an_error_and_replaces_nothing(tmp_path):
    target = tmp_path / "data.bin"
    target.write_bytes(b"old")
    with pytest.raises(FileNotFoundError, match="nothing was written"):
        with atomic_path(target):
            pass
    assert target.read_bytes() == b"old"


def test_temporary_is_unique_hidden_and_keeps_the_suffix(tmp_path):
    target = tmp_path / "mesh.npz"
    with atomic_path(target) as first, atomic_path(target) as second:
        assert first != second
        assert first.name.startswith(TMP_PREFIX) and first.name.endswith("-mesh.npz")
        # np.savez appends .npz to a name without it: the temporary's suffix keeps it writing this very file
        np.savez_compressed(first, v=np.arange(3.0))
        second.write_bytes(b"never read")
        assert temporaries(tmp_path) == sorted([first, second])
        assert temporaries(tmp_path, "mesh.npz") == sorted([first, second])
        assert temporaries(tmp_path, "other.npz") == []
    # the outer block ends last, so its (complete) file is what remains
    with np.load(target) as data:
        np.testing.assert_array_equal(data["v"], np.arange(3.0))
    assert sorted(tmp_path.iterdir()) == [target]
