"""The rerun recording helper: what is logged is in the saved file (read back with rerun's own reader) under
the given recording id; an error inside the block leaves an existing recording as it was."""

from __future__ import annotations

import numpy as np
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from wrp_eval.atomic import temporaries
from wrp_eval.recording import APPLICATION_ID, merge_recordings, recording


def _points(file) -> tuple[set[tuple[str, str]], np.ndarray]:
    """(application id, recording id) pairs and the Points3D positions logged at /pts in an .rrd file."""
    reader = RrdReader(str(file))
    ids = {(store.application_id, store.recording_id) for store in reader.recordings()}
    rows = []
    for chunk in RrdReader(str(file)).stream():
        if chunk.entity_path == "/pts":
            batch = chunk.to_record_batch()
            name = next(n for n in batch.schema.names if n.endswith("Points3D:positions"))
            rows.extend(batch.column(name).to_pylist())
    return ids, np.asarray([p for row in rows for p in row])


def test_logged_data_and_recording_id_are_in_the_file(tmp_path):
    target = tmp_path / "sub" / "run.rrd"
    with recording(target, recording_id="campaign-abc") as rec:
        assert isinstance(rec, rr.RecordingStream)
        rec.log("pts", rr.Points3D([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]), static=True)
        assert not target.exists()          # only a complete recording appears under the name
    ids, points = _points(target)
    assert ids == {(APPLICATION_ID, "campaign-abc")}
    np.testing.assert_allclose(points, [[1, 2, 3], [4, 5, 6]])
    assert temporaries(target.parent) == []


def test_an_error_inside_keeps_the_previous_recording(tmp_path):
    target = tmp_path / "run.rrd"
    with recording(target, recording_id="first") as rec:
        rec.log("pts", rr.Points3D([[0.0, 0.0, 1.0]]), static=True)
    before = target.read_bytes()
    with pytest.raises(ValueError, match="stage failed"):
        with recording(target, recording_id="second") as rec:
            rec.log("pts", rr.Points3D([[9.0, 9.0, 9.0]]), static=True)
            raise ValueError("stage failed")
    assert target.read_bytes() == before
    assert _points(target)[0] == {(APPLICATION_ID, "first")}
    assert sorted(tmp_path.iterdir()) == [target]


def test_merged_stage_recordings_with_one_id_are_one_recording(tmp_path):
    for stage, xyz in (("ship", [1.0, 0.0, 0.0]), ("plan", [0.0, 1.0, 0.0])):
        with recording(tmp_path / f"{stage}.rrd", recording_id="run-1") as rec:
            rec.log(f"{stage}/pts", rr.Points3D([xyz]), static=True)
    with recording(tmp_path / "other.rrd", recording_id="run-2") as rec:
        rec.log("pts", rr.Points3D([[0.0, 0.0, 1.0]]), static=True)
    target = merge_recordings([tmp_path / "ship.rrd", tmp_path / "plan.rrd", tmp_path / "other.rrd"],
                              tmp_path / "run.rrd")
    reader = RrdReader(str(target))
    stores = {store.recording_id: store for store in reader.recordings()}
    assert set(stores) == {"run-1", "run-2"}
    assert {"/ship/pts", "/plan/pts"} <= {chunk.entity_path for chunk in reader.stream(store=stores["run-1"])}
    assert temporaries(tmp_path) == []
