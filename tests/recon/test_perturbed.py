"""Perturbed capture sets of one planned path (wrp_eval/recon/perturbed.py) and ``validate-oracle
--perturbed`` with reused COLMAP figures (no COLMAP run, no long flights)."""

from __future__ import annotations

import dataclasses
import json
import logging
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from wrp_eval.cli import main
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recon.perturbed import (
    BLUR_PX,
    BLUR_SHARES,
    HEADING_BIAS_DEG,
    NAV_DRIFT_RMS_M,
    drift_shape,
    flight_capture_sets,
    perturbed_capture_sets,
    recorded_blur_sets,
)
from wrp_eval.recon.scenarios import reference_capture_set


@pytest.fixture(scope="module")
def path() -> FlightPath:
    cs = reference_capture_set(30)
    n = len(cs)
    return FlightPath(cs.positions, cs.yaw, cs.pitch, np.zeros(n, int), np.zeros(n, int), np.zeros(n, int))


def _fake_flights(path: FlightPath, count: int = 8):
    return [(f"flight_fake_{k}", "flight", captures_from_path(path)) for k in range(count)]


def test_count_and_kinds(path):
    sets = perturbed_capture_sets(path, seed=0, flights=_fake_flights(path))
    assert sets[0][0] == "unperturbed" and sets[0][1] == "reference"
    kinds = Counter(kind for _, kind, _ in sets)
    assert kinds == {"reference": 1, "jitter": 3, "single_view": 6, "drop": 6, "nav_drift": 3, "heading_bias": 2,
                     "blur": 6, "flight": 8}
    assert len(sets) - 1 - kinds["jitter"] >= 24
    assert len({name for name, _, _ in sets}) == len(sets)  # names are unique (they name COLMAP work folders)
    assert len(perturbed_capture_sets(path, seed=0)) == 27  # no flights given


def _arrays(cs):
    return [cs.positions, cs.yaw, cs.pitch, cs.position_priors(), cs.blur()]


def test_deterministic_from_the_seed(path):
    a, b, c = (perturbed_capture_sets(path, seed=s) for s in (4, 4, 5))
    for (na, _, ca), (nb, _, cb) in zip(a, b, strict=True):
        assert na == nb
        for x, y in zip(_arrays(ca), _arrays(cb), strict=True):
            np.testing.assert_array_equal(x, y)
    moved_a = [cs.positions for _, kind, cs in a if kind in ("single_view", "nav_drift")]
    moved_c = [cs.positions for _, kind, cs in c if kind in ("single_view", "nav_drift")]
    assert not all(np.array_equal(x, y) for x, y in zip(moved_a, moved_c, strict=True))


def test_single_view_sets_move_exactly_one_view(path):
    sets = perturbed_capture_sets(path, seed=1)
    ref = sets[0][2]
    views = []
    for name, kind, cs in sets:
        if kind != "single_view":
            continue
        moved = np.flatnonzero(np.any(cs.positions != ref.positions, axis=1) | (cs.yaw != ref.yaw))
        assert len(moved) == 1 and name.endswith(f"{moved[0]:02d}")
        v = moved[0]
        assert 1.5 - 1e-9 <= np.linalg.norm(cs.positions[v] - ref.positions[v]) <= 2.0 + 1e-9
        assert 10.0 - 1e-9 <= abs(np.degrees(cs.yaw[v] - ref.yaw[v])) <= 20.0 + 1e-9
        np.testing.assert_array_equal(cs.pitch, ref.pitch)
        assert cs.prior_positions is None and cs.blur_px is None
        views.append(v)
    assert len(set(views)) == 6 and min(views) < len(ref) / 6 and max(views) >= 5 * len(ref) / 6  # spread


def test_nav_drift_flies_off_the_plan_and_records_the_plan(path):
    drift = [(name, cs) for name, kind, cs in perturbed_capture_sets(path, seed=2) if kind == "nav_drift"]
    assert len(drift) == len(NAV_DRIFT_RMS_M)
    shapes = []
    for (_name, cs), rms in zip(drift, NAV_DRIFT_RMS_M, strict=True):
        np.testing.assert_array_equal(cs.prior_positions, path.positions)  # what the GNSS believed: the plan
        d = cs.positions - path.positions
        assert np.all(np.linalg.norm(d, axis=1) > 0)
        assert np.sqrt(np.mean(np.sum(d ** 2, axis=1))) == pytest.approx(rms, rel=1e-6)
        np.testing.assert_array_equal(cs.yaw, path.yaw)
        shapes.append(d / rms)
    np.testing.assert_allclose(shapes[0], shapes[2], atol=1e-9)  # one drift shape, three doses
    # smooth along the path: neighbouring views drift alike
    walk = drift_shape(2000, np.random.default_rng(0))
    assert np.corrcoef(walk[:-1, 0], walk[1:, 0])[0, 1] > 0.85
    assert walk[:, 0].std() == pytest.approx(1.0, abs=0.15) and walk[:, 2].std() == pytest.approx(0.5, abs=0.1)


def test_heading_bias_and_blur_sets(path):
    sets = {name: (kind, cs) for name, kind, cs in perturbed_capture_sets(path, seed=0)}
    for bias in HEADING_BIAS_DEG:
        _, cs = sets[f"heading_bias_{bias:g}deg"]
        np.testing.assert_allclose(np.degrees(cs.yaw - path.yaw), bias)
        np.testing.assert_array_equal(cs.positions, path.positions)
    for share in BLUR_SHARES:
        blurred = [sets[f"blur_{px:g}px_{100 * share:g}pct"][1] for px in BLUR_PX]
        chosen = blurred[0].blur() > 0
        assert chosen.sum() == round(share * len(path))  # the share of the views, the same views at every length
        for px, cs in zip(BLUR_PX, blurred, strict=True):
            np.testing.assert_array_equal(cs.blur(), np.where(chosen, px, 0.0))
            np.testing.assert_array_equal(cs.positions, path.positions)


def test_drop_sets_leave_out_exactly_one_view_each(path):
    drops = [cs for _, kind, cs in perturbed_capture_sets(path, seed=0) if kind == "drop"]
    missing = [sorted(set(range(len(path))) - set(cs.planned_index.tolist())) for cs in drops]
    assert all(len(m) == 1 for m in missing) and len({m[0] for m in missing}) == len(drops) == 6
    for cs, (view,) in zip(drops, missing, strict=True):
        keep = np.arange(len(path)) != view
        np.testing.assert_array_equal(cs.positions, path.positions[keep])


def test_recorded_blur_puts_a_fly_through_flights_blur_on_the_planned_poses(path):
    flown = captures_from_path(path, offsets=np.full((len(path), 4), 0.3), blur_px=np.arange(len(path), dtype=float))
    partial = flown.subset(np.arange(len(path)) % 3 != 0)
    flights = [("flight_fly-through_u8_1", "flight", partial), ("flight_stop_u8_1", "flight", flown),
               ("flight_fly-through_u0_1", "flight", flown)]
    (name, kind, cs), = recorded_blur_sets(path, flights)
    assert (name, kind) == ("recorded_blur_u8_1", "recorded_blur")
    np.testing.assert_array_equal(cs.positions, path.positions)  # the flight's pose errors are not carried
    np.testing.assert_array_equal(cs.blur(), np.where(np.arange(len(path)) % 3 != 0, np.arange(len(path)), 0.0))


def test_flight_sets_carry_the_flight_errors():
    ctx = ExperimentContext.load(Path(__file__).resolve().parents[2]
                                 / "experiments" / "quickstart.yaml")
    full = ctx.plan_with("ours").path
    keep = slice(0, 5)
    short = dataclasses.replace(full, positions=full.positions[keep], yaw=full.yaw[keep], pitch=full.pitch[keep],
                                face_id=full.face_id[keep], kind=full.kind[keep], sortie=full.sortie[keep])
    sets = flight_capture_sets(ctx, short, seed=0, speeds=(0.0, 8.0), per_speed=1)
    assert [kind for _, kind, _ in sets] == ["flight", "flight"]
    assert sets[0][0].startswith("flight_u0_1") and sets[1][0].startswith("flight_u8_1")
    # the same random numbers in both capture modes: the stop flight hovers for its photos, the fly-through
    # one shoots on the move (more blur); an ideal navigation's photo tags sit closer to the true positions than
    # a consumer GNSS's (both still differ from the ship-frame truth by the ship's motion)
    stop, = flight_capture_sets(ctx, short, seed=0, speeds=(8.0,), per_speed=1, mode="stop")
    through, = flight_capture_sets(ctx, short, seed=0, speeds=(8.0,), per_speed=1, mode="fly-through")
    assert np.median(through[2].blur()) > 2 * np.median(stop[2].blur())
    ideal, = flight_capture_sets(ctx, short, seed=0, speeds=(8.0,), per_speed=1, preset="ideal", prefix="nav_ideal")
    assert ideal[0].startswith("nav_ideal_u8_1")
    consumer, = flight_capture_sets(ctx, short, seed=0, speeds=(8.0,), per_speed=1, preset="consumer")

    def tag_error(cs):
        return np.sqrt(np.mean(np.sum((cs.prior_positions - cs.positions) ** 2, axis=1)))
    assert tag_error(ideal[2]) < 0.5 * tag_error(consumer[2])
    for name, _, cs in sets:
        assert 0 < len(cs) <= len(short) and ("_partial" in name) == (len(cs) < len(short))
        off = np.linalg.norm(cs.positions - short.positions[cs.planned_index], axis=1)
        assert np.all(off < 5.0) and np.any(off > 0.0)
        assert cs.prior_positions is not None and cs.roll is not None and cs.blur_px is not None
    assert flight_capture_sets(ctx, short, seed=0, per_speed=0) == []


# -- validate-oracle --perturbed --reuse-colmap, end to end ----------------------------------------------------

@pytest.fixture
def config_file(tmp_path):
    file = tmp_path / "cfg.yaml"
    file.write_text("run:\n  seed: 3\noracle:\n  synthetic:\n    rays_x: 32\n    rays_y: 22\n")
    return file


def _colmap_row(name: str, error: float, completeness: float) -> dict:
    return {"name": name, "colmap_error_m": error, "colmap_completeness": completeness, "colmap_failed": False,
            "colmap_registered_views": 40, "colmap_time_s": 60.0, "colmap_reason": ""}


def test_perturbed_with_reused_colmap_rows(config_file, tmp_path, capsys):
    ctx = ExperimentContext.load(config_file)
    names = [name for name, kind, _ in perturbed_capture_sets(ctx.plan_with("ours").path, ctx.run_seed)
             if kind == "single_view"]
    errors = {"unperturbed": 0.10, names[0]: 0.12, names[1]: 0.09, "nav_drift_3m": 0.30, "heading_bias_5deg": 0.11}
    rows = [_colmap_row(n, e, 0.8 - e) for n, e in errors.items()]
    rows.append(_colmap_row("not_a_set_of_this_run", 1.0, 0.1))
    prev = tmp_path / "prev" / "perturbed_summary.json"
    prev.parent.mkdir()
    prev.write_text(json.dumps({"rows": rows}))
    out = tmp_path / "out"
    assert main(["validate-oracle", str(config_file), "--out", str(out), "--perturbed", "--flights", "0",
                 "--reuse-colmap", str(prev)]) == 0
    summary = json.loads((out / "perturbed_summary.json").read_text())
    assert (out / "perturbed_table.csv").is_file() and (out / "perturbed_scatter.png").is_file()
    assert summary["perturbed_sets"] == 4 and summary["error_m"]["pairs"] == 4
    by_name = {r["name"]: r for r in summary["rows"]}
    assert list(by_name) == list(errors)  # only the sets the summary has, in the run's order
    assert by_name["nav_drift_3m"]["colmap_delta_error_m"] == pytest.approx(0.20)
    assert by_name["nav_drift_3m"]["kind"] == "nav_drift"
    assert by_name["unperturbed"]["synthetic_delta_error_m"] == 0.0
    assert "synthetic_hole_part_m" in by_name["unperturbed"]
    assert np.isfinite(summary["error_m"]["spearman_rho"]) and 0 <= summary["error_m"]["sign_agreement"] <= 1
    assert summary["reuse_mismatched_sets"] == []
    assert '"spearman_rho"' in capsys.readouterr().out


def test_perturbed_bad_input_exits_2(config_file, tmp_path, capsys):
    base = ["validate-oracle", str(config_file), "--out", str(tmp_path / "o"), "--perturbed", "--flights", "0"]
    assert main(base + ["--reuse-colmap", str(tmp_path / "missing.json")]) == 2
    assert "no such summary file" in capsys.readouterr().err
    garbled = tmp_path / "garbled.json"
    garbled.write_text("{not json")
    assert main(base + ["--reuse-colmap", str(garbled)]) == 2
    assert "not a validate-oracle summary.json" in capsys.readouterr().err
    other = tmp_path / "summary.json"  # a summary without the unperturbed row (e.g. the 10-set validation's)
    other.write_text(json.dumps({"rows": [_colmap_row("good_2rings", 0.5, 0.5)]}))
    assert main(base + ["--reuse-colmap", str(other)]) == 2
    assert "'unperturbed'" in capsys.readouterr().err
    assert main(["validate-oracle", str(config_file), "--out", str(tmp_path / "o"), "--flights", "1"]) == 2
    assert "--flights" in capsys.readouterr().err


def test_an_oracle_that_raises_leaves_a_row_without_figures(caplog):
    from wrp_eval.recon.validate import _evaluate_or_error, perturbed_row

    class Broken:
        def evaluate(self, cs, mesh, seed=0):
            raise ValueError("no keypoints")

    errors = []
    cs = reference_capture_set(6)
    with caplog.at_level(logging.INFO, logger="wrp_eval"):
        res = _evaluate_or_error(Broken(), cs, None, 0, "x: synthetic", errors)
    row = perturbed_row("x", "blur", cs, res, None)
    assert row["synthetic_error_m"] is None and row["synthetic_hole_part_m"] is None
    assert row["synthetic_reason"] == "oracle error: ValueError: no keypoints"
    assert errors == ["x: synthetic: oracle error: ValueError: no keypoints"]
    assert "no keypoints" in caplog.text


def test_jitter_rows_set_the_noise_floor_not_the_agreement():
    from wrp_eval.recon.validate import add_deltas, summarize_perturbed

    def row(name, kind, syn, col):
        return {"name": name, "kind": kind, "synthetic_error_m": syn, "colmap_error_m": col,
                "synthetic_completeness": 0.9, "colmap_completeness": 0.8, "colmap_failed": False}
    rows = [row("unperturbed", "reference", 0.100, 0.50), row("jitter_1", "jitter", 0.1001, 0.52),
            row("jitter_2", "jitter", 0.0999, 0.48), row("a", "single_view", 0.105, 0.60),
            row("b", "single_view", 0.1002, 0.49), row("c", "heading_bias", 0.110, 0.70)]
    add_deltas(rows)
    summary = summarize_perturbed(rows)["error_m"]
    assert summary["pairs"] == 3                                   # jitter rows are not perturbations
    assert summary["jitter_noise_colmap"] == pytest.approx(np.std([0.50, 0.52, 0.48], ddof=1))
    assert summary["noise_colmap"] == summary["jitter_noise_colmap"]   # the larger of seed and jitter noise
    assert summary["repeat_noise_colmap"] is None                       # no seed repeats in these rows
    assert summary["below_noise_sets"] == 1 and summary["pairs_above_noise"] == 2   # "b": COLMAP's -0.01 is noise
    assert summary["sign_agreement_above_noise"] == 1.0
