"""The run summary's JSON document: the stages' keys in the order they ran, optional parts left out."""

import json

from wrp_eval.run_summary import CampaignRun, EnvelopeRun, RunSummary, SurrogateFit
from wrp_eval.wrp.evaluation import EvaluationResult, PathSummary


def _summary(envelope):
    row = PathSummary("initial", 4, 4, 0.0, None, 0.025, None, 0.001, None, 0.026, None)
    return RunSummary("c.yaml", 3, "logs/x", {"views": 17}, CampaignRun("logs/x/campaign", 12, 1, 30.0, None),
                      SurrogateFit.of({"r2": 0.9, "rmse": 1e-3, "mae": 8e-4, "n": 4, "failure_brier": 0.1},
                                      {"position": 0.95, "yaw": 0.9}),
                      EvaluationResult(0.95, 200, (row,), ()), envelope, {"initial": ["a.plan"]},
                      {"risk_m": [0.0]}, {"total": 1.0}, report="logs/x/report.md")


def test_the_document_keeps_the_stage_order_and_leaves_out_what_did_not_run():
    doc = _summary(None).to_json_dict()
    assert list(doc) == ["config", "seed", "out", "plan", "campaign", "surrogate", "evaluate", "missions",
                         "view_risk", "timings_s"]                # no envelope, and the report path is not in it
    assert list(doc["surrogate"]) == ["r2", "rmse", "mae", "n", "failure_brier", "physical_variance_share"]
    assert doc["evaluate"]["paths"][0]["path"] == "initial" and "spec_error_m" not in doc["evaluate"]["paths"][0]
    with_envelope = _summary(EnvelopeRun("initial", True, {"csv": "e.csv"}, {"bow": 11.0}, 96)).to_json_dict()
    assert list(with_envelope).index("envelope") == list(with_envelope).index("evaluate") + 1
    assert json.loads(json.dumps(with_envelope))["envelope"]["boundaries_m_s"] == {"bow": 11.0}
