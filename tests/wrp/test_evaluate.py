import json

import numpy as np
import pytest

from wrp_eval.config import ExperimentConfig
from wrp_eval.planning.path import FlightPath
from wrp_eval.wrp.evaluate import (
    PathTrials,
    paired_difference,
    path_summary,
    robustness_gains,
    robustness_verdict,
    summarise,
)
from wrp_eval.wrp.evaluation import EvaluationResult

from .conftest import helpers


def test_path_summary_hand_computed():
    p = PathTrials("a", np.arange(5), np.array([1.0, 2.0, 3.0, 4.0, 99.0]), np.array([0, 0, 0, 0, 1], bool))
    s = path_summary(p, np.random.default_rng(0), 200, 0.9)
    assert s.mean_error_m == pytest.approx(2.5)                       # the failed trial is left out
    assert s.std_error_m == pytest.approx(np.std([1, 2, 3, 4], ddof=1))
    assert s.p95_error_m == pytest.approx(np.percentile([1, 2, 3, 4], 95))
    assert s.failure_rate == pytest.approx(0.2) and s.succeeded == 4
    lo, hi = s.mean_error_m_ci
    assert 1.0 <= lo <= 2.5 <= hi <= 4.0


def test_paired_difference_uses_common_trials():
    base = PathTrials("initial", np.array([0, 1, 2, 3]), np.array([1.0, 1.0, 2.0, 5.0]), np.zeros(4, bool))
    other = PathTrials("iswrp", np.array([1, 2, 3, 4]), np.array([0.5, 1.0, 4.0, 0.0]),
                       np.array([0, 0, 1, 0], bool))
    d = paired_difference(base, other, np.random.default_rng(0), 200, 0.9)
    assert d.paired_trials == 3 and d.both_succeeded == 2          # ids 1, 2 (id 3 failed on iswrp)
    assert d.mean_error_diff_m == pytest.approx(((0.5 - 1.0) + (1.0 - 2.0)) / 2)
    assert d.failure_rate_diff == pytest.approx(1 / 3)
    assert d.wins == 2 and d.losses == 0


@pytest.mark.parametrize("acceptance", ["paper", "validated"])
def test_evaluate_flies_all_paths_with_the_same_winds(tmp_path, acceptance):
    """End to end with the campaign's analytic stand-in evaluator (no MuJoCo): three campaigns, same seed. With
    acceptance validated and a surrogate that was never validated nothing moves: no placebos are flown and
    the WRPs are not recommended for that reason."""
    from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
    from wrp_eval.campaign.store import TrialStore
    from wrp_eval.experiment import ExperimentContext
    from wrp_eval.surrogate.config import SurrogateSection
    from wrp_eval.surrogate.data import load_campaign_trials
    from wrp_eval.surrogate.train import train_surrogate
    from wrp_eval.wrp.jobs import evaluate_job
    camp = tmp_path / "campaign"
    helpers.make_campaign(camp, 40, 5, seed=3)
    train_surrogate(load_campaign_trials(camp), SurrogateSection(epochs=2, channels=4), seed=0) \
        .surrogate.save(tmp_path / "s.pt")
    config = ExperimentConfig.model_validate({
        "run": {"seed": 2},
        "campaign": {"backend": {"workers": 0}, "batch_size": 4},
        "wrp": {"iterations": 16, "attitude_samples": 3, "neighbourhood_samples": 3, "block_iterations": 8,
                "oracle_error": False, "threshold_m": 0.2, "acceptance": acceptance,
                "evaluate": {"n_trials": 6, "bootstrap": 200, "placebos": 2, "forecast_trials": 4,
                             "robust": acceptance == "paper", "direction": acceptance == "validated"},
                "robust": {"risk_flights": 8, "screen_flights": 4, "placebos": 2}}})
    result = evaluate_job(ExperimentContext(config, tmp_path), tmp_path / "ev", checkpoint=str(tmp_path / "s.pt"),
                       campaign=str(camp),
                       e_original=1.45, evaluator=ANALYTIC_EVALUATOR)   # the known function's scale
    written = json.loads((tmp_path / "ev" / "evaluate.json").read_text())
    assert json.dumps(result.to_json_dict()) == json.dumps(written)      # the file is the typed result, key order too
    assert json.dumps(EvaluationResult.from_json_dict(written).to_json_dict()) == json.dumps(written)
    assert result.paths[0].path == "initial" and result.paths[0].trials == 6
    assert result.forecast.row.path == result.recommended_path
    doc = written
    assert [p["path"] for p in doc["paths"]] == (["initial", "iswrp", "swrp"] + ["robust"] * (acceptance == "paper")
                                                 + ["reversed"] * (acceptance == "validated"))
    if acceptance == "paper":   # the robust kind beside Alg. 3 as written
        levers = json.loads((tmp_path / "ev" / "wrp-robust" / "levers.json").read_text())
        if levers["moved"]:      # its placebos fly, the same levers elsewhere
            assert doc["robustness"]["robust"]["placebos_flown"] == 2
        else:
            assert "robust" in doc["placebos"]["not_flown_for"]
            assert "moved no viewpoint" in doc["robustness"]["robust"]["reason"]
    assert all(p["trials"] == 6 for p in doc["paths"])
    winds = [TrialStore(tmp_path / "ev" / f"campaign-{n}").read_table(["trial_id", "wind_seed",
                                                                        "wind_speed_10m_m_s"]).sort_by("trial_id")
             for n in ("initial", "iswrp", "swrp")]
    assert winds[0].equals(winds[1]) and winds[0].equals(winds[2])       # common random numbers
    assert json.loads((tmp_path / "ev" / "evaluate.json").read_text())["paired"][0]["paired_trials"] == 6
    assert doc["forecast"]["trials"] == 4 and isinstance(doc["forecast"]["go"], bool)
    assert doc["forecast"]["path"] == doc["recommended_path"]
    if acceptance == "validated":
        assert doc["wrp"]["iswrp"]["moved"] == 0 and doc["recommended_path"] == "initial"
        assert doc["placebos"]["not_flown_for"] == ["iswrp", "swrp"]
        assert not (tmp_path / "ev" / "campaign-placebo-iswrp-00").exists()
        assert all("moved no viewpoint" in doc["robustness"][k]["reason"] for k in ("iswrp", "swrp"))
        # the reversed tour: its viewpoints in the other order with their ids (also where a chosen WRP is read),
        # its placebos the initial tour with its flights' errors drawn again
        reversed_path = FlightPath.load(tmp_path / "ev" / "campaign-reversed" / "path.json")
        initial_path = FlightPath.load(tmp_path / "ev" / "campaign-initial" / "path.json")
        np.testing.assert_allclose(reversed_path.positions, initial_path.positions[::-1])
        np.testing.assert_array_equal(reversed_path.view_ids(), np.arange(len(initial_path))[::-1])
        assert (tmp_path / "ev" / "wrp-reversed" / "path.json").is_file()
        draws = [FlightPath.load(tmp_path / "ev" / f"campaign-placebo-reversed-{k:02d}" / "path.json").noise_draw
                 for k in range(2)]
        assert draws == [1, 2]
        assert doc["windfree_error_m"]["placebo-reversed-01"] == doc["windfree_error_m"]["initial"]
        assert doc["robustness"]["reversed"]["placebos_flown"] == 2
        return
    # the placebos of each WRP fly the same winds and enter its verdict
    placebo = TrialStore(tmp_path / "ev" / "campaign-placebo-iswrp-00").read_table(
        ["trial_id", "wind_seed", "wind_speed_10m_m_s"]).sort_by("trial_id")
    assert placebo.equals(winds[0])
    for kind in ("iswrp", "swrp"):
        verdict = doc["robustness"][kind]
        assert verdict["placebos_flown"] == 2 and 1 <= len(verdict["placebo_gains_m"]) <= 2   # gains: paired successes
        assert isinstance(verdict["recommended"], bool)
        assert verdict["recommended"] or verdict["reason"]
    assert doc["recommended_path"] in ("initial", "iswrp", "swrp")
    assert all("p_meets_spec" in p and "mean_views_not_taken" in p and p["expected_sorties"] >= 1.0
               for p in doc["paths"])
    assert (tmp_path / "ev" / "boxplot.png").stat().st_size > 0
    assert set(doc["wrp"]) == {"iswrp", "swrp"}


def test_summarise_is_seeded():
    """The same seed gives the same bootstrap intervals; another seed other intervals around the same point
    estimates."""
    p = [PathTrials(n, np.arange(30), np.random.default_rng(k).normal(1, 0.1, 30), np.zeros(30, bool))
         for k, n in enumerate(("initial", "iswrp"))]
    first, again, other = summarise(p, 1, 200, 0.95), summarise(p, 1, 200, 0.95), summarise(p, 2, 200, 0.95)
    assert first == again
    assert [r.mean_error_m for r in first.paths] == [r.mean_error_m for r in other.paths]
    assert first.paths[0].mean_error_m_ci != other.paths[0].mean_error_m_ci


def test_robustness_gain_is_the_wind_loss_saved_against_the_same_winds():
    base = PathTrials("initial", np.arange(4), np.array([0.030, 0.034, 0.040, 0.050]), np.zeros(4, bool))
    wrp = PathTrials("iswrp", np.arange(4), np.array([0.031, 0.033, 0.036, 0.060]), np.array([0, 0, 0, 1], bool))
    gains = robustness_gains(base, wrp, windfree_base_m=0.025, windfree_other_m=0.027)
    # trial 3 failed on the WRP: left out; gain = (e_b - 0.025) - (e_w - 0.027)
    np.testing.assert_allclose(gains, [0.001, 0.003, 0.006])


def test_a_wrp_is_recommended_only_beyond_zero_and_beyond_its_placebos():
    rng = np.random.default_rng(0)
    strong = np.full(40, 0.004) + rng.normal(0, 0.001, 40)
    placebos = rng.normal(0.0, 0.001, 20)
    yes = robustness_verdict(strong, placebos, np.random.default_rng(1), 500, 0.95)
    assert yes.recommended and yes.gain_ci_m[0] > 0 and yes.gain_m > yes.placebo_gain_p95_m
    noisy = robustness_verdict(rng.normal(0.0, 0.002, 40), placebos, np.random.default_rng(1), 500, 0.95)
    assert not noisy.recommended and "does not exclude 0" in noisy.reason
    like_placebo = robustness_verdict(np.full(40, 0.002) + rng.normal(0, 1e-4, 40), np.linspace(0, 0.003, 20),
                                      np.random.default_rng(1), 500, 0.95)
    assert not like_placebo.recommended and "placebo 95th percentile" in like_placebo.reason
    alone = robustness_verdict(strong, np.array([]), np.random.default_rng(1), 500, 0.95)
    assert not alone.recommended and "no placebo" in alone.reason


def test_summary_recommends_nothing_when_no_wrp_beats_its_placebos():
    base = PathTrials("initial", np.arange(30), np.full(30, 0.03), np.zeros(30, bool))
    wrp = PathTrials("iswrp", np.arange(30), np.full(30, 0.03) + np.random.default_rng(2).normal(0, 1e-3, 30),
                     np.zeros(30, bool))
    placebo = [PathTrials(f"p{k}", np.arange(30), np.full(30, 0.03), np.zeros(30, bool)) for k in range(5)]
    doc = summarise([base, wrp], 0, 300, 0.9, (0.035, 0.9), {"initial": 0.025, "iswrp": 0.025,
                                                             **{f"p{k}": 0.025 for k in range(5)}},
                    {"iswrp": placebo})
    assert doc.recommended_path == "initial" and not doc.robustness["iswrp"].recommended
    assert doc.paths[0].p_meets_spec == 1.0      # no completeness recorded: the error alone decides


def test_expected_sorties_cover_the_views_flights_leave():
    p = PathTrials("a", np.arange(4), np.full(4, 0.03), np.zeros(4, bool), np.full(4, 0.97),
                   np.array([0.0, 10.0, 20.0, 10.0]), 40)
    s = path_summary(p, np.random.default_rng(0), 200, 0.9)
    assert s.mean_views_not_taken == 10.0
    assert s.expected_sorties == pytest.approx(40 / 30)      # a flight takes 30 of 40 views on average


def test_sorties_and_mission_time_are_those_of_the_completed_missions():
    # 6 missions: 3 completed (1, 1 and 2 sorties), 3 ended early on one short sortie (lost, home without
    # headway): those say nothing of what the mission needs and must not make a strong wind look cheap
    sorties = np.array([1.0, 1.0, 2.0, 1.0, 1.0, 1.0])
    time_s = np.array([360.0, 362.0, 800.0, 80.0, 95.0, 90.0])
    completed = np.array([True, True, True, False, False, False])
    p = PathTrials("a", np.arange(6), np.full(6, 0.03), ~completed, np.full(6, 0.97), np.zeros(6), 40, sorties,
                   time_s, completed)
    s = path_summary(p, np.random.default_rng(0), 200, 0.9)
    assert s.p_completed == 0.5 and s.p_one_sortie == pytest.approx(2 / 6)
    assert s.expected_sorties == pytest.approx(4 / 3) and s.mean_mission_time_s == pytest.approx(1522 / 3)
    assert s.p_one_sortie_ci[0] < 2 / 6 < s.p_one_sortie_ci[1]
    none_done = PathTrials("b", np.arange(3), np.full(3, np.nan), np.ones(3, bool), np.zeros(3), np.full(3, 30.0),
                           40, np.ones(3), np.full(3, 90.0), np.zeros(3, bool))
    s = path_summary(none_done, np.random.default_rng(0), 200, 0.9)
    assert s.p_completed == 0.0 and s.p_one_sortie == 0.0 and np.isnan(s.expected_sorties)


def test_forecast_verdict_goes_only_when_the_ci_clears_the_bar():
    from types import SimpleNamespace

    from wrp_eval.wrp.config import EvaluateSection
    from wrp_eval.wrp.evaluate import forecast_verdict
    wind = SimpleNamespace(speed_10m_m_s=7.0, direction_deg=250.0)
    errors = np.r_[np.full(57, 0.02), np.full(3, 0.05)]               # 57 of 60 flights meet 0.03 m
    good = PathTrials("initial", np.arange(60), errors, np.zeros(60, bool), np.full(60, 0.99), np.zeros(60), 40)
    ev = EvaluateSection(go_probability=0.8, bootstrap=500)
    v = forecast_verdict(good, ev, (0.03, 0.95), 0, wind)
    assert v.row.p_meets_spec == pytest.approx(0.95) and v.row.p_meets_spec_ci[0] >= 0.8 and v.go
    assert "GO" in v.summary and v.wind_speed_10m_m_s == 7.0 and v.row.expected_sorties == 1.0
    marginal = PathTrials("initial", np.arange(60), np.r_[np.full(50, 0.02), np.full(10, 0.05)],
                          np.zeros(60, bool), np.full(60, 0.99), np.zeros(60), 40)
    m = forecast_verdict(marginal, ev, (0.03, 0.95), 0, wind)
    assert m.row.p_meets_spec == pytest.approx(50 / 60) and m.row.p_meets_spec_ci[0] < 0.8 and not m.go
    assert "NO-GO" in m.summary


def test_forecast_config_flies_every_trial_in_the_forecast_wind():
    from wrp_eval.campaign.config import TrialConfig
    from wrp_eval.wind.config import WindSection
    from wrp_eval.wrp.jobs import forecast_config
    cfg = forecast_config(TrialConfig(), WindSection(speed_10m_m_s=9.5, direction_deg=120.0), 12)
    assert cfg.campaign.n_trials == 12
    assert cfg.campaign.wind.speed_10m_m_s == 9.5 and cfg.campaign.wind.direction_deg == 120.0
    assert cfg.campaign.wind.turbulence == TrialConfig().campaign.wind.turbulence


def test_five_perfect_forecast_flights_are_not_enough_to_go():
    """An exact (Clopper-Pearson) interval: 5 of 5 flights in spec has a 95 % lower bound of 0.478, not 1."""
    from types import SimpleNamespace

    from wrp_eval.wrp.config import EvaluateSection
    from wrp_eval.wrp.evaluate import forecast_verdict, proportion_ci
    assert proportion_ci(5, 5, 0.95)[0] == pytest.approx(0.025 ** (1 / 5), abs=1e-9)   # the exact bound
    five = PathTrials("initial", np.arange(5), np.full(5, 0.02), np.zeros(5, bool), np.full(5, 0.99),
                      np.zeros(5), 40)
    v = forecast_verdict(five, EvaluateSection(go_probability=0.8), (0.03, 0.95), 0,
                         SimpleNamespace(speed_10m_m_s=6.0, direction_deg=270.0))
    assert v.row.p_meets_spec == 1.0 and not v.go


def test_a_paired_difference_from_before_the_p95_columns_still_loads_and_a_broken_one_does_not():
    from wrp_eval.wrp.evaluation import PairedDifference
    old = {"path": "iswrp", "versus": "initial", "paired_trials": 4, "both_succeeded": 4, "mean_error_diff_m": 0.1,
           "mean_error_diff_ci": None, "wins": 1, "losses": 3, "failure_rate_diff": 0.0, "failure_rate_diff_ci": None}
    loaded = PairedDifference.from_json_dict(old)
    assert loaded.p95_error_diff_m is None and loaded.p_meets_spec_diff_ci is None and loaded.wins == 1
    with pytest.raises(KeyError):
        PairedDifference.from_json_dict({k: v for k, v in old.items() if k != "wins"})
