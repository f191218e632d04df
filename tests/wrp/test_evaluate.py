import json

import numpy as np
import pytest

from wrp_eval.config import ExperimentConfig
from wrp_eval.wrp.evaluate import PathTrials, paired_difference, path_summary, summarise

from .conftest import helpers


def test_path_summary_hand_computed():
    p = PathTrials("a", np.arange(5), np.array([1.0, 2.0, 3.0, 4.0, 99.0]), np.array([0, 0, 0, 0, 1], bool))
    s = path_summary(p, np.random.default_rng(0), 200, 0.9)
    assert s["mean_error_m"] == pytest.approx(2.5)                       # the failed trial is left out
    assert s["std_error_m"] == pytest.approx(np.std([1, 2, 3, 4], ddof=1))
    assert s["p95_error_m"] == pytest.approx(np.percentile([1, 2, 3, 4], 95))
    assert s["failure_rate"] == pytest.approx(0.2) and s["succeeded"] == 4
    lo, hi = s["mean_error_m_ci"]
    assert 1.0 <= lo <= 2.5 <= hi <= 4.0


def test_paired_difference_uses_common_trials():
    base = PathTrials("initial", np.array([0, 1, 2, 3]), np.array([1.0, 1.0, 2.0, 5.0]), np.zeros(4, bool))
    other = PathTrials("iswrp", np.array([1, 2, 3, 4]), np.array([0.5, 1.0, 4.0, 0.0]),
                       np.array([0, 0, 1, 0], bool))
    d = paired_difference(base, other, np.random.default_rng(0), 200, 0.9)
    assert d["paired_trials"] == 3 and d["both_succeeded"] == 2          # ids 1, 2 (id 3 failed on iswrp)
    assert d["mean_error_diff_m"] == pytest.approx(((0.5 - 1.0) + (1.0 - 2.0)) / 2)
    assert d["failure_rate_diff"] == pytest.approx(1 / 3)
    assert d["wins"] == 2 and d["losses"] == 0


def test_evaluate_flies_all_paths_with_the_same_winds(tmp_path):
    """End to end with the campaign's analytic stand-in evaluator (no MuJoCo): three campaigns, same seed."""
    from wrp_eval.campaign.evaluators import ANALYTIC_EVALUATOR
    from wrp_eval.campaign.store import TrialStore
    from wrp_eval.surrogate.data import load_campaign_trials
    from wrp_eval.surrogate.config import SurrogateSection
    from wrp_eval.surrogate.train import train_surrogate
    from wrp_eval.experiment import ExperimentContext
    from wrp_eval.wrp.jobs import evaluate_job
    camp = tmp_path / "campaign"
    helpers.make_campaign(camp, 40, 5, seed=3)
    train_surrogate(load_campaign_trials(camp), SurrogateSection(epochs=2, channels=4), seed=0) \
        .surrogate.save(tmp_path / "s.pt")
    config = ExperimentConfig.model_validate({
        "run": {"seed": 2},
        "campaign": {"backend": {"workers": 0}, "batch_size": 4},
        "wrp": {"iterations": 16, "attitude_samples": 3, "neighbourhood_samples": 3, "block_iterations": 8,
                "oracle_error": False, "threshold_m": 0.2, "evaluate": {"n_trials": 6, "bootstrap": 200}}})
    doc = evaluate_job(ExperimentContext(config, tmp_path), tmp_path / "ev", checkpoint=str(tmp_path / "s.pt"), campaign=str(camp),
                       e_original=0.6, quiet=True, evaluator=ANALYTIC_EVALUATOR)
    assert [p["path"] for p in doc["paths"]] == ["initial", "iswrp", "swrp"]
    assert all(p["trials"] == 6 for p in doc["paths"])
    winds = [TrialStore(tmp_path / "ev" / f"campaign-{n}").read_table(["trial_id", "wind_seed",
                                                                        "wind_speed_10m_m_s"]).sort_by("trial_id")
             for n in ("initial", "iswrp", "swrp")]
    assert winds[0].equals(winds[1]) and winds[0].equals(winds[2])       # common random numbers
    assert json.loads((tmp_path / "ev" / "evaluate.json").read_text())["paired"][0]["paired_trials"] == 6
    assert (tmp_path / "ev" / "boxplot.png").stat().st_size > 0
    assert set(doc["wrp"]) == {"iswrp", "swrp"}


def test_summarise_is_seeded():
    p = [PathTrials(n, np.arange(30), np.random.default_rng(k).normal(1, 0.1, 30), np.zeros(30, bool))
         for k, n in enumerate(("initial", "iswrp"))]
    assert summarise(p, 1, 200, 0.95) == summarise(p, 1, 200, 0.95)
