import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.surrogate.data import TrialData, load_campaign_trials, planned_pose_features, split_indices

from .helpers import make_campaign


def test_load_campaign_trials_reads_the_store(tmp_path):
    path, digest, commanded, flown, error = make_campaign(tmp_path, 20, 5, nan_trials=(3,), failed_trials=(4,))
    data = load_campaign_trials(tmp_path)
    # trial 3 did not take view 0: kept, with offset 0 and the condition 'taken' 0 there
    assert data.n_trials == 20 and data.n_views == 5 and "1 of them with views not taken" in data.source
    expected = flown.copy()
    expected[3, 0] = 0.0
    np.testing.assert_allclose(data.offsets, expected)
    taken = data.conditions[..., -1]
    assert taken[3, 0] == 0.0 and taken.sum() == 20 * 5 - 1
    np.testing.assert_allclose(data.deviation[np.arange(20) != 3], (flown - commanded)[np.arange(20) != 3])
    assert np.isnan(data.error[4]) and data.failed[4]
    assert data.path_digest == digest
    np.testing.assert_allclose(data.planned_pose[:, :3], path.positions)
    assert list(data.trial_id) == list(range(20))
    assert data.views is not None and np.all(data.views.condition_reference[:, -1] == 1.0)


def test_load_campaign_trials_reads_which_views_registered(tmp_path):
    labels = {2: [1.0, 0.0, 1.0, np.nan, 1.0], 5: [0.0] * 5}
    make_campaign(tmp_path, 8, 5, registered=labels)
    data = load_campaign_trials(tmp_path)
    np.testing.assert_array_equal(data.registered[2], labels[2])
    np.testing.assert_array_equal(data.registered[5], labels[5])
    assert np.isnan(data.registered[[0, 1, 3, 4, 6, 7]]).all()        # trials stored without the column


def test_load_campaign_refuses_non_campaign(tmp_path):
    with pytest.raises(InputError, match="not a campaign folder"):
        load_campaign_trials(tmp_path)


def test_split_indices_partition():
    tr, va, te = split_indices(100, 0.1, 0.2, np.random.default_rng(0))
    assert len(va) == 10 and len(te) == 20 and len(tr) == 70
    assert sorted(np.concatenate([tr, va, te])) == list(range(100))
    with pytest.raises(InputError):
        split_indices(3, 0.3, 0.3, np.random.default_rng(0))


def test_trial_data_shape_checks():
    with pytest.raises(InputError, match="offsets"):
        TrialData(np.zeros((3, 4, 3)), np.zeros(3), np.zeros(3, bool))
    with pytest.raises(InputError, match="error"):
        TrialData(np.zeros((3, 4, 4)), np.zeros(2), np.zeros(3, bool))


def test_planned_pose_features_hand_computed():
    f = planned_pose_features(np.array([[1.0, 2, 3], [4, 5, 6]]), np.array([0.0, np.pi / 2]), np.array([-0.1, 0]))
    np.testing.assert_allclose(f, [[1, 2, 3, 1, 0, -0.1, 0], [4, 5, 6, 0, 1, 0, 1]], atol=1e-12)


def test_physical_share_is_the_flights_part_of_the_offset_variance():
    from wrp_eval.surrogate.data import physical_variance_share
    rng = np.random.default_rng(0)
    dev = rng.normal(0.0, 1.0, (500, 10, 4))
    commanded = np.zeros((500, 10, 4))
    commanded[:100, 2] = rng.normal(0.0, 1.0, (100, 4))            # one targeted view in a fifth of the trials
    data = TrialData(commanded + dev, np.zeros(500), np.zeros(500, bool), deviation=dev)
    share = physical_variance_share(data)
    expected = 1.0 / (1.0 + 0.2 * 0.1)                               # commanded variance: 1 in 2 % of the cells
    assert share["position"] == pytest.approx(expected, abs=0.02) and share["yaw"] == pytest.approx(expected, abs=0.03)
    assert physical_variance_share(TrialData(dev, np.zeros(500), np.zeros(500, bool))) is None
