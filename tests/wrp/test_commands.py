import json

import numpy as np
import pytest

from wrp_eval.cli import main
from wrp_eval.planning.path import FlightPath

from .conftest import helpers

CONFIG = """
run: {name: t, seed: 3}
surrogate: {epochs: 4, patience: 2, channels: 8, hidden: 16, batch_size: 32}
wrp: {iterations: 24, attitude_samples: 5, neighbourhood_samples: 4, block_iterations: 8,
      e_original_m: 0.6, oracle_error: false}
"""


@pytest.fixture(scope="module")
def trained_campaign(tmp_path_factory):
    root = tmp_path_factory.mktemp("cli")
    campaign = root / "campaign"
    helpers.make_campaign(campaign, 60, 6, seed=1)
    cfg = root / "cfg.yaml"
    cfg.write_text(CONFIG)
    assert main(["train", str(cfg), "--campaign", str(campaign), "--out", str(root / "sur"), "--quiet"]) == 0
    return root, cfg, campaign


def test_train_writes_checkpoint_metrics_and_plot(trained_campaign):
    root, _, _ = trained_campaign
    doc = json.loads((root / "sur" / "metrics.json").read_text())
    assert doc["n_views"] == 6 and doc["test"]["n"] >= 1 and doc["path_digest"]
    assert (root / "sur" / "parity.png").stat().st_size > 0 and (root / "sur" / "surrogate.pt").is_file()


def test_train_cv_writes_fold_figures(trained_campaign, tmp_path, capsys):
    root, cfg, campaign = trained_campaign
    assert main(["train", str(cfg), "--campaign", str(campaign), "--out", str(tmp_path), "--cv", "3",
                 "--workers", "2", "--quiet"]) == 0
    doc = json.loads((tmp_path / "cv.json").read_text())
    assert doc["folds"] == 3 and len(doc["per_fold"]) == 3 and doc["pooled"]["n"] == 60 and doc["workers"] == 2
    assert "cross-validation" in capsys.readouterr().out and (tmp_path / "surrogate.pt").is_file()
    # the model trained beside the folds in another process is the one plain `train` gives
    alone, beside = (json.loads((d / "metrics.json").read_text()) for d in (root / "sur", tmp_path))
    assert beside["test"] == alone["test"] and beside["split"] == alone["split"]
    assert beside["history"] == alone["history"]
    assert main(["train", str(cfg), "--campaign", str(campaign), "--out", str(tmp_path / "bad"), "--cv", "3",
                 "--workers", "0", "--quiet"]) == 2
    assert "--workers" in capsys.readouterr().err and not (tmp_path / "bad").exists()   # refused before training


@pytest.mark.parametrize("kind", ["iswrp", "swrp"])
def test_optimize_writes_wrp_path_and_table3(trained_campaign, kind):
    root, cfg, campaign = trained_campaign
    out = root / f"wrp-{kind}"
    rc = main(["optimize", str(cfg), "--kind", kind, "--threshold", "0.5", "--out", str(out), "--campaign",
               str(campaign), "--checkpoint", str(root / "sur" / "surrogate.pt"), "--quiet"])
    assert rc == 0
    doc = json.loads((out / "wrp_metrics.json").read_text())
    t = doc["table3"]
    assert {"offset_rate_pct", "position_offset_m", "rotation_offset_deg", "time_s", "oracle_error_m"} <= set(t)
    assert t["kind"] == kind and t["threshold_m"] == 0.5 and t["e_original_m"] == 0.6
    assert doc["sample_radius_source"].startswith("campaign")
    # r_s = 0.95 quantile of |N(0, 0.3^2 I_3)| = 0.3 sqrt(chi2_3(0.95)) = 0.84 m (60 trials: loose)
    assert np.allclose(doc["sample_radius_m"], 0.84, atol=0.25)
    original = FlightPath.load(campaign / "path.json")
    wrp = FlightPath.load(out / "path.json")
    moved = np.array([v["moved"] for v in doc["viewpoints"]])
    delta = wrp.positions - original.positions
    assert np.allclose(np.abs(delta).sum(1) > 0, moved)
    assert t["position_offset_m"] == pytest.approx(np.linalg.norm(delta, axis=1).sum(), rel=1e-9)


def test_optimize_refuses_a_checkpoint_of_another_path(trained_campaign, tmp_path, capsys):
    root, cfg, _ = trained_campaign
    other = tmp_path / "other"
    helpers.make_campaign(other, 12, 5, seed=2)
    rc = main(["optimize", str(cfg), "--out", str(tmp_path / "o"), "--campaign", str(other),
               "--checkpoint", str(root / "sur" / "surrogate.pt"), "--quiet"])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert "6 viewpoints" in err and "\n" not in err


def test_optimize_refuses_a_negative_threshold(trained_campaign, capsys):
    root, cfg, campaign = trained_campaign
    assert main(["optimize", str(cfg), "--threshold", "-1", "--campaign", str(campaign), "--quiet"]) == 2


def test_optimize_e_original_from_the_surrogate(trained_campaign, tmp_path):
    root, _, campaign = trained_campaign
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(CONFIG.replace("e_original_m: 0.6,", "e_original_source: surrogate,"))
    out = tmp_path / "o"
    assert main(["optimize", str(cfg), "--out", str(out), "--campaign", str(campaign), "--checkpoint",
                 str(root / "sur" / "surrogate.pt"), "--quiet"]) == 0
    doc = json.loads((out / "wrp_metrics.json").read_text())
    from wrp_eval.surrogate.model import Surrogate
    s = Surrogate.load(root / "sur" / "surrogate.pt")
    assert doc["table3"]["e_original_m"] == pytest.approx(s.predict(np.zeros((1, 6, 4)))[0])
    assert doc["e_original_source"] == "surrogate at zero offsets"
    # default threshold: 0.08 x E_original
    assert doc["table3"]["threshold_m"] == pytest.approx(0.08 * doc["table3"]["e_original_m"])


def test_optimize_robust_screens_each_lever_on_flights_apart_from_the_risk_map(trained_campaign, tmp_path):
    root, cfg, campaign = trained_campaign
    robust_cfg = tmp_path / "robust.yaml"
    robust_cfg.write_text(cfg.read_text().replace(
        "oracle_error: false}",
        "oracle_error: false, seed: 1, robust: {risk_flights: 8, screen_flights: 4, placebos: 3, "
        "views_fraction: 0.3}}"))      # seed 1 draws risk flights in which two views carry risk
    out = tmp_path / "wrp-robust"
    assert main(["optimize", str(robust_cfg), "--kind", "robust", "--out", str(out), "--campaign", str(campaign),
                 "--quiet"]) == 0
    doc = json.loads((out / "levers.json").read_text())
    assert len(doc["risk_flights"]) == 8 and len(doc["screen_flights"]) == 4
    assert not set(doc["risk_flights"]) & set(doc["screen_flights"])
    assert doc["risk_source"].startswith("re-scored 8 flights")       # the test store has no view_registered
    assert set(doc["levers"]) == {"redundant", "standoff"}
    for screen in doc["levers"].values():
        assert screen["flights"] == 4 and screen["views"] == doc["views"]
        assert screen["verdict"]["placebos_flown"] == 3 and len(screen["placebo_p95_gains_m"]) == 3
    assert 1 <= len(doc["views"]) <= 2 and all(0 <= v < 6 for v in doc["views"])   # ceil(0.3 x 6), positive risk
    original, robust = FlightPath.load(campaign / "path.json"), FlightPath.load(out / "path.json")
    added = len(doc["views"]) if "redundant" in doc["applied"] else 0
    assert len(robust) == len(original) + added
    if not doc["applied"]:
        assert np.array_equal(robust.positions, original.positions) and doc["moved"] is False
    # seed 0 draws risk flights in which no view carries risk: nothing to place, nothing screened, nothing moved
    robust_cfg.write_text(robust_cfg.read_text().replace("seed: 1,", "seed: 0,"))
    assert main(["optimize", str(robust_cfg), "--kind", "robust", "--out", str(tmp_path / "none"), "--campaign",
                 str(campaign), "--quiet"]) == 0
    none = json.loads((tmp_path / "none" / "levers.json").read_text())
    assert none["views"] == [] and none["levers"] == {} and none["moved"] is False
    assert set(none["error_sources"]) == {"flown", "blur", "heading", "attitude", "position", "all"}
    # per-face standoff does not need a view at risk: one lever per face of the path, each at that face's surface
    # views, applied whatever its verdict with apply: all (every view of the face moved back, none added)
    robust_cfg.write_text(robust_cfg.read_text().replace("views_fraction: 0.3}", "views_fraction: 0.3, levers: "
                                                         "[redundant, face_standoff], apply: all}"))
    assert main(["optimize", str(robust_cfg), "--kind", "robust", "--out", str(tmp_path / "faces"), "--campaign",
                 str(campaign), "--quiet"]) == 0
    faces = json.loads((tmp_path / "faces" / "levers.json").read_text())
    from wrp_eval.ship.proxy import FACE_NAMES
    from wrp_eval.wrp.levers import face_views
    expected = {f"standoff_face_{FACE_NAMES[f]}": at.tolist() for f, at in face_views(original).items()}
    assert expected and {k: v["views"] for k, v in faces["levers"].items()} == expected
    assert faces["views"] == [] and faces["applied"] == list(expected) and faces["moved"] is True
    moved_back = FlightPath.load(tmp_path / "faces" / "path.json")
    assert len(moved_back) == len(original)
    shift = np.linalg.norm(moved_back.positions - original.positions, axis=1)
    surface = np.concatenate(list(expected.values()))
    assert np.any(shift[surface] > 0) and np.all(np.delete(shift, surface) == 0)   # (a view whose axis misses
                                                                                  # the ship has no depth: stays)
    # a named lever is applied whatever its verdict; a name no lever has is refused before any screening
    first = next(iter(expected))
    robust_cfg.write_text(robust_cfg.read_text().replace("apply: all}", f"apply: [{first}]}}"))
    assert main(["optimize", str(robust_cfg), "--kind", "robust", "--out", str(tmp_path / "named"), "--campaign",
                 str(campaign), "--quiet"]) == 0
    named = json.loads((tmp_path / "named" / "levers.json").read_text())
    assert named["applied"] == [first] and named["apply"] == [first]
    robust_cfg.write_text(robust_cfg.read_text().replace(f"apply: [{first}]", "apply: [standoff_face_keel]"))
    assert main(["optimize", str(robust_cfg), "--kind", "robust", "--out", str(tmp_path / "keel"), "--campaign",
                 str(campaign), "--quiet"]) == 2
    assert not (tmp_path / "keel" / "levers.json").exists()


def test_campaign_error_sources_rescore_chosen_flights_without_each_capture_error(tmp_path):
    from wrp_eval.wrp.levers import CAPTURE_ERRORS
    from wrp_eval.wrp.robust import campaign_error_sources
    helpers.make_campaign(tmp_path / "campaign", 6, 6, seed=1, failed_trials=(2,))
    first = campaign_error_sources(tmp_path / "campaign", 3, seed=5)
    assert len(first["flights"]) == 3 and 2 not in first["flights"]
    assert set(first["sources"]) == {"flown", *CAPTURE_ERRORS}
    assert first == campaign_error_sources(tmp_path / "campaign", 3, seed=5)     # seeded: the same flights, numbers
    assert campaign_error_sources(tmp_path / "campaign", 100, seed=5)["flights"] == [0, 1, 3, 4, 5]   # all that flew
