"""The trial store: atomic chunks, one writer at a time, nested per-viewpoint columns read back as arrays."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.campaign.config import CampaignSection
from wrp_eval.campaign.records import TrialOutcome, column_array, make_record
from wrp_eval.campaign.sampling import trial_inputs
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError


def records(ids, n_views=3, raised=()):
    section = CampaignSection.model_validate({"perturbation": {"design": "box"}})
    out = []
    for k in ids:
        inp = trial_inputs(section, 1, k, n_views)
        outcome = None if k in raised else TrialOutcome(
            flown_offsets=inp.commanded_offsets + k, metrics={"error_m": 0.1 * k}, trajectory=np.zeros((5, 3)),
            wind_at_views=np.ones((n_views, 3)), camera_pitch=-0.5 - 0.01 * k + np.zeros(n_views))
        out.append(make_record(inp, outcome, root_seed=1, path_digest="p", n_views=n_views, attempts=1,
                               trial_s=0.0, worker="w", finished_unix=0.0, error="boom" if k in raised else None))
    return out


def test_chunks_round_trip_and_stray_temporaries_are_dropped(tmp_path):
    with TrialStore(tmp_path) as store:
        store.append(records([0, 1]))
        (store.trials_dir / ".tmp-deadbeef.parquet").write_bytes(b"half a parquet file")
        store.append(records([2, 3, 4], raised=(3,)))
    reopened = TrialStore(tmp_path)
    np.testing.assert_array_equal(reopened.stored_ids(), [0, 1, 2, 3, 4])   # the stray file is not read
    table = reopened.read_table()
    flown = column_array(table, "flown_offsets")
    commanded = column_array(table, "commanded_offsets")
    assert flown.shape == (5, 3, 4)
    np.testing.assert_allclose(flown[[0, 1, 2, 4]], commanded[[0, 1, 2, 4]] + np.array([0, 1, 2, 4])[:, None, None])
    assert np.all(np.isnan(flown[3])) and table.column("error").to_pylist()[3] == "boom"
    assert np.all(np.isnan(column_array(table, "wind_at_views")[3]))
    with reopened:  # acquiring again removes the stray temporary
        assert not list(reopened.trials_dir.glob(".tmp-*"))


def test_a_second_writer_is_refused(tmp_path):
    with TrialStore(tmp_path):
        with pytest.raises(InputError, match="another campaign process"):
            TrialStore(tmp_path).acquire()
    with TrialStore(tmp_path):  # released: fine again
        pass


def test_achieved_pitch_round_trips_and_old_chunks_read_as_nan(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    with TrialStore(tmp_path) as store:
        store.append(records([0, 1, 2], raised=(1,)))
    # a chunk written before the camera_pitch column existed (earlier campaigns): same store, column absent
    old = store.read_table().drop_columns(["camera_pitch"])
    old = old.set_column(0, "trial_id", pa.array([5, 6, 7], pa.int64()))
    pq.write_table(old, store.trials_dir / "chunk-99999999.parquet")
    table = TrialStore(tmp_path).read_table()
    pitch = column_array(table, "camera_pitch")
    assert pitch.shape == (6, 3)
    np.testing.assert_allclose(pitch[[0, 2]], [[-0.5] * 3, [-0.52] * 3])
    assert np.all(np.isnan(pitch[1])) and np.all(np.isnan(pitch[3:]))    # raised trial; chunk without the column
