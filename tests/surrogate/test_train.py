import dataclasses
import json

import numpy as np
import pytest
import torch

from wrp_eval.errors import InputError
from wrp_eval.surrogate.config import SurrogateSection
from wrp_eval.surrogate.data import TrialData, known_function, known_function_trials
from wrp_eval.surrogate.model import Surrogate
from wrp_eval.surrogate.train import cross_validate, regression_metrics, train_surrogate, write_outputs


def test_regression_metrics_hand_computed():
    m = regression_metrics(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 4.0]))
    assert m["r2"] == pytest.approx(1 - 1 / 2)
    assert m["rmse"] == pytest.approx(np.sqrt(1 / 3))
    assert m["mae"] == pytest.approx(1 / 3)
    assert m["n"] == 3


def test_learner_fits_known_function_on_held_out_trials(trained, known_data):
    data, params = known_data
    test = trained.metrics["test"]
    assert test["r2"] > 0.88, test   # noise ceiling of this data: ~0.99
    # and on fresh trials of the same function (noise-free truth)
    fresh, _ = known_function_trials(200, data.n_views, np.random.default_rng(7), noise_m=0.0)
    pred = trained.surrogate.predict(fresh.offsets)
    assert regression_metrics(known_function(fresh.offsets, params), pred)["r2"] > 0.88


def test_split_is_by_trial_and_disjoint(trained, known_data):
    data, _ = known_data
    sets = [set(trained.split[k]) for k in ("train", "val", "test")]
    assert not (sets[0] & sets[1] or sets[0] & sets[2] or sets[1] & sets[2])
    assert len(sets[0] | sets[1] | sets[2]) == data.n_trials
    assert trained.metrics["test"]["n"] == len(sets[2])


def test_same_seed_same_weights_other_seed_differs(known_data):
    data, _ = known_data
    section = SurrogateSection(epochs=3, patience=3, batch_size=64, channels=8)
    a = train_surrogate(data, section, seed=5)
    b = train_surrogate(data, section, seed=5)
    c = train_surrogate(data, section, seed=6)
    for k, v in a.surrogate.net.state_dict().items():
        assert (v == b.surrogate.net.state_dict()[k]).all()
    assert a.split == b.split and a.split != c.split
    x = data.offsets[:4]
    assert not np.allclose(a.surrogate.predict(x), c.surrogate.predict(x))


def test_early_stopping_stops_patience_epochs_after_the_best_and_returns_the_best_model(known_data):
    data, _ = known_data
    # lr 3e-2 on this data: a noisy validation curve whose best (epoch 12 of 15) is neither first nor last
    section = SurrogateSection(epochs=40, patience=3, lr=3e-2, channels=4)
    r = train_surrogate(data, section, seed=0)
    val = np.asarray(r.history["val_loss"])
    best = r.metrics["best_epoch"]
    assert best == int(np.argmin(val)) + 1
    # stopped early, exactly `patience` epochs after the best validation epoch
    assert r.metrics["epochs_run"] == val.size == best + section.patience < section.epochs
    assert np.all(val[best:] > val[best - 1])
    # the returned weights are those after epoch `best`: the same seeded run stopped there ends with them
    upto = train_surrogate(data, SurrogateSection(epochs=best, patience=section.epochs, lr=3e-2, channels=4), seed=0)
    assert upto.history["val_loss"] == r.history["val_loss"][:best]
    final = upto.surrogate.net.state_dict()
    assert all(torch.equal(v, final[k]) for k, v in r.surrogate.net.state_dict().items())
    # ... and so the returned model's validation loss (standardised MSE) is the best epoch's, not the last's
    val_mse = r.metrics["val"]["rmse"] ** 2 / r.surrogate.meta.error_std ** 2
    assert val_mse == pytest.approx(val[best - 1], rel=1e-4)
    assert val_mse != pytest.approx(val[-1], rel=1e-2)


def test_failed_trials_are_left_out_of_the_error_fit(known_data):
    data, _ = known_data
    failed = np.zeros(data.n_trials, bool)
    failed[::3] = True
    error = data.error.copy()
    error[::3] = np.nan
    d2 = TrialData(data.offsets, error, failed, data.planned_pose, views=data.views)
    r = train_surrogate(d2, SurrogateSection(epochs=2, channels=4), seed=0)
    assert r.metrics["n_used"] == data.n_trials - failed.sum()
    r2 = train_surrogate(d2, SurrogateSection(epochs=2, channels=4, predict_failure=True), seed=0)
    assert 0 <= r2.metrics["test"]["failure_brier"] <= 1
    assert r2.surrogate.predict_failure(data.offsets[:3]).shape == (3,)


def test_too_few_trials_is_input_error(known_data):
    data, _ = known_data
    with pytest.raises(InputError, match="usable trials"):
        train_surrogate(TrialData(data.offsets[:5], data.error[:5], data.failed[:5], data.planned_pose))


def test_write_outputs(trained, tmp_path):
    files = write_outputs(trained, tmp_path)
    doc = json.loads((tmp_path / "metrics.json").read_text())
    assert {"r2", "rmse", "mae", "n"} <= set(doc["test"])
    assert (tmp_path / "parity.png").read_bytes()[:4] == b"\x89PNG"
    s = Surrogate.load(files["checkpoint"], n_views=trained.surrogate.n_views)
    assert s.meta.metrics["test"]["r2"] == trained.metrics["test"]["r2"]


def test_log_target_predicts_in_metres_and_survives_the_checkpoint(known_data, tmp_path):
    data, params = known_data
    section = SurrogateSection(epochs=60, patience=60, batch_size=64, target="log_error")
    result = train_surrogate(data, section, seed=0)
    s = result.surrogate
    assert s.meta.target == "log_error"
    # the standardisation is of log(error): its mean is the log of the typical error (~0.5-0.7 m here)
    assert s.meta.error_mean == pytest.approx(np.log(np.median(data.error)), abs=0.3)
    pred = s.predict(data.offsets[:50])
    assert np.all(pred > 0)
    assert regression_metrics(known_function(data.offsets[:50], params), pred)["r2"] > 0.5
    s.save(tmp_path / "s.pt")
    again = Surrogate.load(tmp_path / "s.pt")
    assert again.meta.target == "log_error"
    np.testing.assert_allclose(again.predict(data.offsets[:50]), pred, rtol=1e-6)


def test_log_target_refuses_non_positive_errors(known_data):
    data, _ = known_data
    bad = dataclasses.replace(data, error=np.where(np.arange(data.n_trials) == 3, -0.1, data.error))
    with pytest.raises(InputError, match="log_error needs errors > 0"):
        train_surrogate(bad, SurrogateSection(epochs=2, target="log_error"), seed=0)


def test_cross_validation_tests_every_usable_trial_exactly_once(known_data):
    data, _ = known_data
    failed = np.zeros(data.n_trials, bool)
    failed[::10] = True                       # failed trials are not fitted, so never tested either
    data = dataclasses.replace(data, failed=failed)
    section = SurrogateSection(epochs=60, patience=20, batch_size=32, lr=3e-3, channels=16)
    cv = cross_validate(data, section, seed=1, folds=3)
    tested = np.concatenate([f["test_trials"] for f in cv["per_fold"]])
    assert sorted(tested.tolist()) == np.flatnonzero(~failed).tolist()
    assert cv["pooled"]["n"] == (~failed).sum() == sum(f["n"] for f in cv["per_fold"])
    r2 = [f["r2"] for f in cv["per_fold"]]
    assert cv["r2_min"] == min(r2) <= cv["r2_mean"] <= cv["r2_max"] == max(r2)
    assert cv["r2_min"] > 0.5, cv["per_fold"]     # the known function is learnable in every fold
    # folds trained in two spawned processes: the same folds, the same seeded trainings, the same figures
    parallel = cross_validate(data, section, seed=1, folds=3, workers=2)
    assert parallel["workers"] == 2 and cv["workers"] == 1
    assert [f["test_trials"] for f in parallel["per_fold"]] == [f["test_trials"] for f in cv["per_fold"]]
    assert [f["r2"] for f in parallel["per_fold"]] == r2
    assert parallel["pooled"] == cv["pooled"]
    with pytest.raises(InputError, match="folds"):
        cross_validate(data, section, folds=1)
    with pytest.raises(InputError, match="workers"):
        cross_validate(data, section, folds=3, workers=0)


def test_learning_rate_is_reduced_on_a_plateau_only_when_enabled(known_data):
    data, _ = known_data
    base = dict(epochs=40, patience=40, batch_size=64, lr=3e-2, channels=8)
    decayed = train_surrogate(data, SurrogateSection(**base, lr_decay_patience=1), seed=0)
    constant = train_surrogate(data, SurrogateSection(**base, lr_decay_patience=0), seed=0)
    assert constant.metrics["final_lr"] == pytest.approx(3e-2)
    assert decayed.metrics["final_lr"] < 3e-2 / 2 - 1e-12


def test_missing_views_are_dropped_or_taken_as_an_input(known_data):
    """Trials whose flight did not take every view: left out by default, kept with missing_views: input."""
    data, _ = known_data
    cond = np.zeros((data.n_trials, data.n_views, 5))
    cond[..., -1] = 1.0
    cond[::4, 2, -1] = 0.0                      # a quarter of the trials missed view 2
    partial = TrialData(data.offsets, data.error, data.failed, data.planned_pose, conditions=cond, views=data.views)
    assert partial.complete().sum() == data.n_trials - len(range(0, data.n_trials, 4))
    section = SurrogateSection(epochs=2, channels=4)
    dropped = train_surrogate(partial, section, seed=0)
    kept = train_surrogate(partial, section.model_copy(update={"missing_views": "input"}), seed=0)
    assert dropped.metrics["n_used"] == partial.complete().sum() and kept.metrics["n_used"] == data.n_trials


def _with_registration(data: TrialData) -> TrialData:
    """The known-function trials with a registration label that is a known function of each view's own offset:
    a view registers unless it moved more than 1.2 m sideways (|dx|)."""
    registered = (np.abs(data.offsets[..., 0]) < 1.2).astype(float)
    registered[::5, 3] = np.nan                 # views without a label (not taken) take no part in the loss
    return dataclasses.replace(data, registered=registered)


def test_registration_head_learns_which_views_register_and_leaves_the_error_output(known_data, tmp_path):
    data, _ = known_data
    labelled = _with_registration(data)
    section = SurrogateSection(epochs=60, patience=60, batch_size=32, lr=3e-3, channels=16, kernel=3, hidden=32,
                               registration_weight=1.0)
    r = train_surrogate(labelled, section, seed=0)
    reg = r.metrics["test"]["registration"]
    assert reg["n_views_labelled"] == len(r.split["test"]) * data.n_views - np.isin(
        r.split["test"], np.arange(0, data.n_trials, 5)).sum()
    base = max(reg["base_rate"], 1 - reg["base_rate"])
    assert reg["accuracy"] > base + 0.5 * (1 - base), reg    # most of the way from the base rate to perfect
    assert r.metrics["test"]["r2"] > 0.7
    # the head is part of the checkpoint; the loaded network predicts the same
    r.surrogate.save(tmp_path / "s.pt")
    loaded = Surrogate.load(tmp_path / "s.pt")
    np.testing.assert_array_equal(loaded.predict(data.offsets[:5]), r.surrogate.predict(data.offsets[:5]))
    # without the weight there is no head, and the default architecture is the one older checkpoints carry
    plain = train_surrogate(labelled, section.model_copy(update={"registration_weight": 0.0, "epochs": 2}), seed=0)
    assert "view_outputs" not in plain.surrogate.meta.architecture and plain.surrogate.net.view_head is None
    assert "registration" not in plain.metrics["test"]


def test_registration_weight_without_labels_is_input_error(known_data):
    data, _ = known_data
    section = SurrogateSection(epochs=2, channels=4, registration_weight=0.5)
    with pytest.raises(InputError, match="registration_weight"):
        train_surrogate(data, section, seed=0)
    unlabelled = dataclasses.replace(data, registered=np.full(data.offsets.shape[:2], np.nan))
    with pytest.raises(InputError, match="records no registered views"):
        train_surrogate(unlabelled, section, seed=0)


def test_targeted_trials_are_the_ones_commanded_off_the_plan(known_data):
    data, _ = known_data
    deviation = data.offsets.copy()                 # flown = commanded + deviation: commanded 0 ...
    deviation[7, 2] -= [1.0, 0.0, 0.0, 0.0]         # ... except trial 7's view 2, commanded 1 m along x
    deviation[9, 0] = np.nan                        # a view not taken counts as not commanded
    flagged = dataclasses.replace(data, deviation=deviation).targeted()
    assert np.flatnonzero(flagged).tolist() == [7]
    assert not data.targeted().any()                # no commanded offsets recorded
    deviation[::3, 5, 1] -= 0.5                     # every third trial commanded too
    targeted = dataclasses.replace(data, deviation=deviation)
    r = train_surrogate(targeted, SurrogateSection(epochs=2, channels=4), seed=0)
    held_out = np.intersect1d(r.split["test"], np.flatnonzero(targeted.targeted()))
    assert r.metrics["test_targeted"]["n"] == held_out.size > 1
    np.testing.assert_allclose(r.metrics["test_targeted"]["rmse"], np.sqrt(np.mean(
        (r.surrogate.predict(data.offsets[held_out]) - data.error[held_out]) ** 2)), rtol=1e-6)


def test_registration_loss_counts_only_labelled_views_of_usable_trials(known_data):
    """The auxiliary loss ignores the labels of views without one (NaN) and of trials left out of the fit (failed);
    error_only is the error term alone."""
    from wrp_eval.surrogate.model import ViewSequenceCNN
    from wrp_eval.surrogate.train import _loss_function, _untrained_meta, usable_rows
    data, _ = known_data
    failed = data.failed.copy()
    failed[4] = True
    labelled = dataclasses.replace(_with_registration(data), failed=failed)
    section = SurrogateSection(channels=4, registration_weight=2.0)
    usable, rows = usable_rows(labelled, section)
    meta = _untrained_meta(labelled, section, labelled.offsets, labelled.error, usable, rows)
    torch.manual_seed(0)
    surrogate = Surrogate(ViewSequenceCNN(**meta.architecture), meta)
    idx = torch.arange(10)
    loss = _loss_function(surrogate.net, surrogate, labelled, section, labelled.offsets, labelled.error, usable)
    changed = labelled.registered.copy()
    changed[4] = 1.0 - np.nan_to_num(changed[4])     # the failed trial's labels
    changed[6, 3] = np.nan                           # one more view without a label
    other = _loss_function(surrogate.net, surrogate, dataclasses.replace(labelled, registered=changed), section,
                           labelled.offsets, labelled.error, usable)
    assert float(loss(idx)) != float(other(idx))     # trial 6's view 3 had a label: it counted
    changed[6, 3] = labelled.registered[6, 3]
    again = _loss_function(surrogate.net, surrogate, dataclasses.replace(labelled, registered=changed), section,
                           labelled.offsets, labelled.error, usable)
    assert float(loss(idx)) == float(again(idx))     # the failed trial's labels did not
    with torch.no_grad():
        out = surrogate.net(surrogate.input_tensor(labelled.offsets[:10]))[:, 0]
    y = torch.as_tensor((labelled.error[:10] - meta.error_mean) / meta.error_std, dtype=torch.float32)
    w = torch.as_tensor(usable[:10], dtype=torch.float32)
    torch.testing.assert_close(loss(idx, error_only=True), ((out - y) ** 2 * w).sum() / w.sum())
