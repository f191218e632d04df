"""The R^2 ceiling: the oracle re-scored at jittered flown poses of a real (tiny) MuJoCo campaign."""

import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.surrogate.diagnostics import oracle_roughness

CONFIG = """
run: {name: ceiling-test, seed: 2}
ship: {type: stylized}
wind: {speed_10m_m_s: 5.0, turbulence: {severity: light}}
campaign:
  n_trials: 4
  batch_size: 4
  wind: {speed_10m_m_s: {dist: uniform, low: 3.0, high: 6.0}, turbulence: {severity: light}}
  perturbation: {design: common, position_half_width_m: 1.0, yaw_half_width_deg: 5.0}
  backend: {kind: local, workers: 0}
  outputs: {rerun: false}
"""


@pytest.fixture(scope="module")
def campaign_dir(tmp_path_factory):
    from wrp_eval.campaign.jobs import campaign_job
    from wrp_eval.experiment import ExperimentContext
    folder = tmp_path_factory.mktemp("ceiling")
    cfg = folder / "c.yaml"
    cfg.write_text(CONFIG)
    summary = campaign_job(ExperimentContext.load(cfg), out_dir=folder / "campaign")
    assert summary.done == 4 and summary.failed < 4
    return folder / "campaign"


@pytest.mark.slow
def test_ceiling_is_one_without_jitter_and_below_one_with_it(campaign_dir):
    # the oracle is deterministic for given poses and seed: no jitter, no within-trial variance
    exact = oracle_roughness(campaign_dir, n_trials=2, repeats=2, position_jitter_m=0.0, yaw_jitter_rad=0.0)
    assert exact["noise_var_m2"] == 0.0 and exact["r2_ceiling"] == 1.0 and exact["n_trials"] == 2
    rough = oracle_roughness(campaign_dir, n_trials=2, repeats=3, position_jitter_m=0.05, yaw_jitter_rad=0.005)
    assert rough["noise_var_m2"] > 0.0 and rough["total_var_m2"] > 0.0
    assert rough["r2_ceiling"] == pytest.approx(1 - rough["noise_var_m2"] / rough["total_var_m2"])
    assert np.sqrt(rough["noise_var_m2"]) < 0.01    # mm-scale roughness, not a different reconstruction
    again = oracle_roughness(campaign_dir, n_trials=2, repeats=3, position_jitter_m=0.05, yaw_jitter_rad=0.005)
    assert again == rough


def test_stored_trials_rescore_to_their_stored_error(campaign_dir):
    # the stored flown offsets, achieved pitch, roll, blur, navigation estimate and the oracle seed are the whole
    # input of the stored error
    from wrp_eval.campaign.records import column_array
    from wrp_eval.surrogate.diagnostics import campaign_oracle
    scorer, store = campaign_oracle(campaign_dir)
    table = store.read_table(["n_views", "flown_offsets", "camera_pitch", "camera_roll", "blur_px",
                              "estimated_offsets", "error_m", "oracle_seed"])
    flown, pitch = column_array(table, "flown_offsets"), column_array(table, "camera_pitch")
    roll = column_array(table, "camera_roll")
    blur, estimated = column_array(table, "blur_px"), column_array(table, "estimated_offsets")
    error = table.column("error_m").to_numpy(zero_copy_only=False)
    seeds = table.column("oracle_seed").to_pylist()
    complete = np.flatnonzero(np.all(np.isfinite(flown), axis=(1, 2)) & np.isfinite(error))
    assert complete.size >= 2 and np.all(np.isfinite(pitch[complete])) and np.all(np.isfinite(roll[complete]))
    assert np.abs(roll[complete]).max() > 0.0                      # a real residual roll, which the oracle sees
    for trial in complete:
        assert scorer.error(flown[trial], seeds[trial], pitch[trial], roll[trial], blur[trial],
                            estimated[trial]) == error[trial]
    assert np.nanmax(blur[complete]) > 0.0                         # blur recorded, and it counts:
    trial = complete[0]
    assert scorer.error(flown[trial], seeds[trial], pitch[trial], roll[trial], 10 * blur[trial],
                        estimated[trial]) > error[trial]


def test_ceiling_refuses_a_folder_that_is_not_a_campaign(tmp_path):
    with pytest.raises(InputError, match="not a campaign folder"):
        oracle_roughness(tmp_path)


def test_ceiling_needs_two_repeats(campaign_dir):
    with pytest.raises(InputError, match="repeats"):
        oracle_roughness(campaign_dir, repeats=1)


@pytest.mark.slow
def test_single_view_agreement_scores_one_viewpoint_moves_with_both(campaign_dir):
    from wrp_eval.surrogate.diagnostics import campaign_oracle, single_view_agreement, targeted_single_view_moves

    from .conftest import random_surrogate
    scorer, _ = campaign_oracle(campaign_dir)
    n = len(scorer.planned)
    surrogate = random_surrogate(n, seed=4)
    doc = single_view_agreement(surrogate, campaign_dir, n_moves=10, jitters=2, seed=2)
    assert doc["n_moves"] == 10 and -1.0 <= doc["spearman"] <= 1.0 and doc["jitters"] == 2
    assert doc["surrogate_change_std_m"] > 0.0 and doc["oracle_change_std_m"] >= 0.0
    # the moves at the campaign's targeted scale, and the oracle's jitter-averaged changes recomputed by hand
    views, moves = targeted_single_view_moves(campaign_dir, n, 10, 2, np.asarray(surrogate.meta.offset_low),
                                     np.asarray(surrogate.meta.offset_high))
    assert np.all(moves >= surrogate.meta.offset_low) and np.all(moves <= surrogate.meta.offset_high)
    rng = np.random.default_rng(np.random.SeedSequence(2, spawn_key=(1,)))
    jit = np.concatenate([rng.normal(0, 0.02, (2, n, 3)), rng.normal(0, 0.002, (2, n, 1))], axis=2)
    changes, predicted = [], []
    for view, move in zip(views, moves, strict=True):
        offsets = np.zeros((n, 4))
        offsets[view] = move
        changes.append(np.mean([scorer.error(offsets + j, 0) - scorer.error(j, 0) for j in jit]))
        predicted.append(surrogate.predict(offsets[None])[0] - surrogate.predict(np.zeros((1, n, 4)))[0])
    changes, predicted = np.array(changes), np.array(predicted)
    k = int(np.argmax(np.abs(changes)))
    assert doc["largest"][0][:2] == [int(views[k]), pytest.approx(changes[k], abs=1e-12)]
    assert doc["oracle_change_std_m"] == pytest.approx(np.std(changes), abs=1e-12)
    assert doc["rmse_m"] == pytest.approx(np.sqrt(np.mean((changes - predicted) ** 2)), rel=1e-5)
    top = int(np.argmax(np.abs(predicted)))         # 10 moves: the top decile is the one largest prediction
    assert doc["sign_top_decile"] == float(np.sign(predicted[top]) == np.sign(changes[top]))
    with pytest.raises(InputError, match="viewpoints"):
        single_view_agreement(random_surrogate(n + 1), campaign_dir, n_moves=2)


def test_mean_offset_baseline_fits_a_function_of_the_mean_and_misses_a_per_view_one():
    from wrp_eval.surrogate.data import TrialData
    from wrp_eval.surrogate.diagnostics import mean_offset_baseline
    rng = np.random.default_rng(0)
    offsets = rng.normal(0, 1, (400, 6, 4))
    split = {"train": list(range(0, 300)), "val": list(range(300, 340)), "test": list(range(340, 400))}
    mean = offsets.mean(axis=1)
    of_mean = TrialData(offsets, 0.02 + 0.01 * mean[:, 3] ** 2 - 0.004 * mean[:, 0], np.zeros(400, bool))
    assert mean_offset_baseline(of_mean, split)["r2"] > 0.999
    per_view = TrialData(offsets, offsets[:, 2, 0] ** 2 - offsets[:, 4, 1], np.zeros(400, bool))
    doc = mean_offset_baseline(per_view, split)
    assert doc["r2"] < 0.3 and doc["n"] == 60
    assert doc["degree"] == 2          # 340 fitted trials: 15 terms x 10 fit, a cubic's 35 would not
    assert mean_offset_baseline(per_view, split, trials_per_term=1)["degree"] == 4


def test_mean_offset_baseline_without_enough_trials_gives_nan_not_an_error():
    from wrp_eval.surrogate.data import TrialData
    from wrp_eval.surrogate.diagnostics import mean_offset_baseline
    offsets = np.random.default_rng(1).normal(0, 1, (10, 3, 4))
    failed = np.ones(10, bool)                         # every flight failed: nothing the default counts
    data = TrialData(offsets, np.full(10, 0.03), failed)
    split = {"train": list(range(6)), "val": [6, 7], "test": [8, 9]}
    assert np.isnan(mean_offset_baseline(data, split)["r2"])
    with_failed = mean_offset_baseline(data, split, usable=np.ones(10, bool))   # use_failed_trials: they count
    assert with_failed["n"] == 2 and with_failed["degree"] == 1 and np.isnan(with_failed["r2"])   # constant error


def test_the_scarce_input_set_trains_on_the_campaigns_ship_and_its_checkpoint_needs_it(campaign_dir, tmp_path):
    import dataclasses

    from wrp_eval.surrogate.config import SurrogateSection
    from wrp_eval.surrogate.data import load_campaign_trials
    from wrp_eval.surrogate.model import Surrogate, ViewQuery
    from wrp_eval.surrogate.train import train_surrogate
    data = load_campaign_trials(campaign_dir, scarce=True)
    assert data.scarce is not None and len(data.scarce) == data.n_views
    assert load_campaign_trials(campaign_dir).scarce is None          # only on request (~1 s per 46 views)
    rng = np.random.default_rng(0)
    offsets = rng.uniform(-1, 1, (40, data.n_views, 4)) * [2.0, 2.0, 2.0, 0.2]
    lost = data.scarce.lost_views(offsets)
    error = 0.02 + 1e-4 * lost.sum(axis=1)
    trials = dataclasses.replace(data, offsets=offsets, error=error, failed=np.zeros(40, bool), trial_id=None,
                                 deviation=None, conditions=None, registered=None)
    section = SurrogateSection(inputs="scarce", epochs=5, patience=5, validation_moves=0)
    result = train_surrogate(trials, section, seed=0)
    s = result.surrogate
    assert s.meta.scarce_digest == data.scarce.digest and s.meta.architecture["in_channels"] == 4 + 4 + 5 + 2 + 7
    # the training statistics standardise the same channel the queries compute (the 4th moving one)
    train = np.asarray(result.split["train"])
    assert s.meta.feature_mean[3] == pytest.approx(lost[train].mean(), rel=1e-9)
    assert s.meta.feature_std[3] == pytest.approx(lost[train].std(), rel=1e-6)
    s.save(tmp_path / "s.pt")
    again = Surrogate.load(tmp_path / "s.pt", inputs="scarce", scarce=load_campaign_trials(campaign_dir, scarce=True)
                           .scarce)
    np.testing.assert_array_equal(again.predict(offsets[:3]), s.predict(offsets[:3]))
    query = ViewQuery(again, offsets[0])
    full = np.repeat(offsets[:1], 2, axis=0)
    full[:, 5] = offsets[1:3, 5]
    np.testing.assert_allclose(query.errors(5, offsets[1:3, 5]), s.predict(full), atol=2e-5)
    with pytest.raises(InputError, match="no scarce coverage"):
        train_surrogate(dataclasses.replace(trials, scarce=None), section, seed=0)
