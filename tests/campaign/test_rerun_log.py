"""The campaign recording: every trial is on the trial timeline (read back with rerun's own reader), also
after a resume; frusta geometry is right; logging time is accounted."""

from __future__ import annotations

import numpy as np

from wrp_eval.atomic import temporaries
from wrp_eval.campaign.rerun_log import frustum_strips, read_trial_ids


def test_every_trial_is_in_the_recording_after_a_resume(tmp_path, path_file, make_config, run_analytic):
    config = make_config(path_file, n_trials=5, outputs={"rerun": True})
    run_analytic(config, tmp_path / "c")
    np.testing.assert_array_equal(read_trial_ids(tmp_path / "c" / "campaign.rrd"), np.arange(5))
    bigger = make_config(path_file, n_trials=9, outputs={"rerun": True})
    summary = run_analytic(bigger, tmp_path / "c")
    assert summary.rerun_s > 0
    np.testing.assert_array_equal(read_trial_ids(tmp_path / "c" / "campaign.rrd"), np.arange(9))
    assert temporaries(tmp_path / "c") == []   # the recording's temporary was renamed onto campaign.rrd


def test_frustum_points_along_the_optical_axis():
    # a camera at the origin looking along +y (yaw 90 deg), level: the four corners lie at y = depth
    strips = frustum_strips(np.zeros((1, 3)), np.array([np.pi / 2]), np.array([0.0]), 0.3, 0.2, depth=2.0)
    corners = strips[0, [1, 2, 4, 5]]
    np.testing.assert_allclose(corners[:, 1], 2.0, atol=1e-12)
    np.testing.assert_allclose(np.sort(np.abs(corners[:, 0])), [2 * np.tan(0.3)] * 4, atol=1e-12)
    np.testing.assert_allclose(np.abs(corners[:, 2]), 2 * np.tan(0.2), atol=1e-12)
    np.testing.assert_allclose(strips[0, [0, 3, 6]], 0.0)


def test_the_capture_realism_of_a_trial_is_in_the_recording(tmp_path):
    # a flight record with the navigation's positions, blur and an early return: its entities and scalars
    from rerun.chunk import RrdReader

    from wrp_eval.campaign.rerun_log import CampaignRecorder
    from wrp_eval.planning.path import FlightPath
    planned = np.array([[0.0, 30.0, 20.0], [10.0, 30.0, 20.0], [20.0, 30.0, 20.0]])
    path = FlightPath(planned, np.full(3, -np.pi / 2), np.full(3, -0.17), np.zeros(3, int), np.zeros(3, int),
                      np.zeros(3, int))
    path_doc = {**path.to_json_dict(), "digest": "t"}
    flown = [[0.5, -0.2, 0.1, 0.01], [0.4, -0.1, 0.0, 0.0], [float("nan")] * 4]
    record = {"trial_id": 7, "trajectory": planned.tolist(), "flown_offsets": flown, "failed": False,
              "camera_pitch": [-0.17, -0.17, float("nan")], "wind_at_views": [[1.0, 0.0, 0.0]] * 3,
              "estimated_offsets": [[1.5, 0.2, 0.1, 0.02], [1.4, 0.3, 0.0, 0.01], [float("nan")] * 4],
              "blur_px": [2.0, 4.0, float("nan")], "flight_outcome": "returned home: battery at its reserve"}
    recorder = CampaignRecorder(tmp_path, path_doc)
    recorder.log_trial(record)
    file = recorder.close()
    values = {}
    for chunk in RrdReader(str(file)).stream():
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            if name in ("Scalars:scalars", "Points3D:positions"):
                values[chunk.entity_path] = batch.column(name).to_pylist()
    assert np.allclose(np.asarray(values["/world/trial/recorded_positions"][0]), planned[:2] + [[1.5, 0.2, 0.1],
                                                                                               [1.4, 0.3, 0.0]])
    assert np.ravel(values["/metrics/views_taken_fraction"])[0] == 2 / 3
    assert np.ravel(values["/metrics/blur_px_p95"])[0] == np.percentile([2.0, 4.0], 95)
    assert np.ravel(values["/metrics/returned_home"])[0] == 1.0
