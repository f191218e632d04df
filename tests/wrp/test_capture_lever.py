"""The per-view capture-mode lever: stops where the held-out flights' photos blur, its placebos, and its
evaluation flown beside the initial path without a surrogate."""

import json

import numpy as np
import pytest

from tests.surrogate import helpers
from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.wrp.capture_lever import blurred_views, capture_lever_paths, held_out_blur, legs_at, slow_leg_paths

FLY_THROUGH_CONFIG = {"sim": {"capture": {"mode": "fly-through"}}}


def test_a_view_stops_when_its_95th_percentile_blur_exceeds_the_limit():
    blur = np.zeros((20, 4))
    blur[:, 1] = 2.0             # always blurred
    blur[18:, 2] = 5.0           # two flights in twenty: its 95th percentile is 5 px
    blur[:, 3] = np.nan          # never taken
    blur[0, 0] = np.nan          # taken by the other flights
    np.testing.assert_array_equal(blurred_views(blur, 1.0), [False, True, True, False])
    np.testing.assert_array_equal(blurred_views(blur, 2.0), [False, False, True, False])
    np.testing.assert_array_equal(blurred_views(blur, 5.0), [False, False, False, False])


def test_the_stops_are_chosen_on_trials_the_evaluation_does_not_fly(tmp_path):
    blur = np.zeros((12, 5))
    blur[:6, 0] = 9.0           # blurred in the trials an evaluation of 6 flights flies: not seen
    blur[6:, 3] = 9.0
    path, *_ = helpers.make_campaign(tmp_path / "c", 12, 5, blur_px=blur, trial_config=FLY_THROUGH_CONFIG)
    held = held_out_blur(tmp_path / "c", 6, path)
    assert held.shape == (6, 5)
    np.testing.assert_array_equal(blurred_views(held, 1.0), [False, False, False, True, False])
    with pytest.raises(InputError, match="no trials beyond"):
        held_out_blur(tmp_path / "c", 12, path)
    with pytest.raises(InputError, match="another path"):
        held_out_blur(tmp_path / "c", 6, helpers.make_path(6))
    helpers.make_campaign(tmp_path / "none", 12, 5, trial_config=FLY_THROUGH_CONFIG)
    with pytest.raises(InputError, match="no blur"):
        held_out_blur(tmp_path / "none", 6, path)
    helpers.make_campaign(tmp_path / "stop", 12, 5, blur_px=blur)        # flown stop-and-shoot
    with pytest.raises(InputError, match="stop mode"):
        held_out_blur(tmp_path / "stop", 6, path)


def test_placebos_stop_at_as_many_random_views_and_are_seeded():
    path = helpers.make_path(30)
    stops = np.zeros(30, dtype=bool)
    stops[[3, 4, 5, 20]] = True
    lever, placebos = capture_lever_paths(path, stops, 5, np.random.default_rng(7))
    np.testing.assert_array_equal(lever.stops("fly-through"), stops)
    assert lever.metadata["capture_stops"] == 4
    masks = [p.stops("fly-through") for p in placebos.values()]
    assert all(m.sum() == 4 for m in masks) and len({tuple(np.flatnonzero(m)) for m in masks}) == 5
    assert all(p.metadata["placebo_of"] == "stops" for p in placebos.values())
    again = capture_lever_paths(path, stops, 5, np.random.default_rng(7))[1]
    assert [p.digest() for p in again.values()] == [p.digest() for p in placebos.values()]


def test_the_slow_legs_lever_slows_the_legs_at_the_views_and_its_placebos_as_many():
    path = helpers.make_path(10)
    views = np.zeros(10, dtype=bool)
    views[[0, 4, 5]] = True
    legs = legs_at(views)
    np.testing.assert_array_equal(np.flatnonzero(legs), [0, 3, 4, 5])
    lever, placebos = slow_leg_paths(path, views, 2.0, 40, np.random.default_rng(1))
    np.testing.assert_array_equal(lever.leg_speeds(), np.where(legs, 2.0, path.speed_m_s))
    assert list(placebos)[:2] == ["placebo-slow-legs-00", "placebo-slow-legs-01"]
    # the placebos slow the legs at three random views: 3 to 6 legs, as each view's arriving and leaving legs
    slowed = [int((p.leg_speeds() == 2.0).sum()) for p in placebos.values()]
    assert set(slowed) <= {3, 4, 5, 6} and len(set(slowed)) > 1


def _config(mode: str) -> ExperimentConfig:
    return ExperimentConfig.model_validate({
        "run": {"seed": 2}, "sim": {"capture": {"mode": mode}},
        "campaign": {"backend": {"workers": 0}, "batch_size": 4},
        "wrp": {"evaluate": {"n_trials": 6, "bootstrap": 200, "placebos": 2, "forecast_trials": 0, "kinds": [],
                             "capture_stops": True, "slow_legs": True}}})


def test_the_capture_lever_is_evaluated_beside_the_initial_path_without_a_surrogate(tmp_path):
    from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
    from wrp_eval.experiment import ExperimentContext
    from wrp_eval.wrp.jobs import evaluate_job

    blur = np.zeros((14, 8))
    blur[6:, 2] = 4.0           # blurred in the held-out flights (the evaluation flies trials 0 .. 5)
    blur[:6, 5] = 4.0           # blurred in the flights the evaluation flies: not a stop
    helpers.make_campaign(tmp_path / "campaign", 14, 8, blur_px=blur, trial_config=FLY_THROUGH_CONFIG)
    ctx = ExperimentContext(_config("fly-through"), tmp_path)
    result = evaluate_job(ctx, tmp_path / "ev", campaign=str(tmp_path / "campaign"), e_original=1.45,
                          evaluator=ANALYTIC_EVALUATOR)
    doc = json.loads((tmp_path / "ev" / "evaluate.json").read_text())
    assert [p.path for p in result.paths] == ["initial", "stops", "slow-legs"] and doc["wrp"] == {}
    stops = FlightPath.load(tmp_path / "ev" / "wrp-stops" / "path.json")
    np.testing.assert_array_equal(np.flatnonzero(stops.stops("fly-through")), [2])
    flown = FlightPath.load(tmp_path / "ev" / "campaign-stops" / "path.json")
    assert flown.capture == stops.capture                # the campaign flies the per-view modes
    assert doc["robustness"]["stops"]["placebos_flown"] == 2
    placebo = FlightPath.load(tmp_path / "ev" / "campaign-placebo-stops-01" / "path.json")
    assert placebo.stops("fly-through").sum() == 1
    slow = FlightPath.load(tmp_path / "ev" / "campaign-slow-legs" / "path.json")
    np.testing.assert_array_equal(np.flatnonzero(slow.leg_speeds() == 2.5), [1, 2])     # the legs at view 2
    assert doc["robustness"]["slow-legs"]["placebos_flown"] == 2
    # with every campaign trial flown by the evaluation none is left to choose the stops on: refused at once
    with pytest.raises(InputError, match="no trials beyond"):
        evaluate_job(ctx, tmp_path / "ev3", n_trials=14, campaign=str(tmp_path / "campaign"), e_original=1.45,
                     evaluator=ANALYTIC_EVALUATOR)
    # nothing blurs beyond the limit: the levers would change nothing, and are not flown
    sharp = ExperimentConfig.model_validate({**ctx.config.model_dump(), "wrp": {"evaluate": {
        **ctx.config.wrp.evaluate.model_dump(), "capture_blur_limit_px": 10.0}}})
    none = evaluate_job(ExperimentContext(sharp, tmp_path), tmp_path / "ev4", campaign=str(tmp_path / "campaign"),
                        e_original=1.45, evaluator=ANALYTIC_EVALUATOR)
    assert [p.path for p in none.paths] == ["initial"]
    assert set(none.placebos.not_flown_for) == {"stops", "slow-legs"}
    with pytest.raises(InputError, match="fly-through"):
        evaluate_job(ExperimentContext(_config("stop"), tmp_path), tmp_path / "ev2",
                     campaign=str(tmp_path / "campaign"), e_original=1.45, evaluator=ANALYTIC_EVALUATOR)
