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
