"""Validation capture sets and the agreement summary (the COLMAP runs themselves are not unit tests)."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.recon.scenarios import ship_like_mesh
from wrp_eval.recon.synthetic import SyntheticOracle
from wrp_eval.recon.validate import summarize, validation_capture_sets


def test_capture_sets_span_good_degraded_broken_and_rank_as_built():
    mesh = ship_like_mesh()
    sets = validation_capture_sets(mesh, seed=0)
    assert {c for _, c, _ in sets} == {"good", "degraded", "broken"}
    oracle = SyntheticOracle()
    results = {name: oracle.evaluate(cs, mesh, seed=0) for name, _, cs in sets
               if name in ("good_2rings", "thinned_half", "faces_no_transitions")}
    assert not results["good_2rings"].failed
    assert results["faces_no_transitions"].failed  # per-face groups with no transition views
    assert results["good_2rings"].error_m < results["thinned_half"].error_m


def _row(name, syn_err, col_err, syn_failed, col_failed, syn_comp=0.5, col_comp=0.5):
    return {"name": name, "synthetic_error_m": syn_err, "colmap_error_m": col_err,
            "synthetic_failed": syn_failed, "colmap_failed": col_failed,
            "synthetic_completeness": syn_comp, "colmap_completeness": col_comp}


def test_summary_rank_correlation_and_verdict_agreement():
    rows = [_row("a", 0.1, 1.0, False, False, 0.9, 0.6), _row("b", 0.2, 3.0, False, False, 0.8, 0.5),
            _row("c", 0.3, 2.0, False, True, 0.7, 0.4), _row("d", 0.4, 4.0, True, True, 0.1, 0.05)]
    s = summarize(rows)
    assert s["spearman_rho_error_m"] == pytest.approx(0.8)  # ranks 1,3,2,4 vs 1,2,3,4
    assert s["spearman_rho_completeness"] == pytest.approx(1.0)
    assert s["failed_verdict_agreement"] == pytest.approx(0.75) and s["disagreements"] == ["c"]
    assert np.isnan(summarize(rows[:2])["spearman_rho_error_m"])


def _prow(name, kind, syn_err, col_err, syn_comp=0.9, col_comp=0.6):
    return {"name": name, "kind": kind, "synthetic_error_m": syn_err, "colmap_error_m": col_err,
            "synthetic_completeness": syn_comp, "colmap_completeness": col_comp,
            "synthetic_failed": False, "colmap_failed": False}


def test_perturbed_deltas_spearman_sign_agreement_and_noise():
    from wrp_eval.recon.validate import add_deltas, summarize_perturbed

    rows = [_prow("unperturbed", "reference", 0.020, 0.100, 0.90, 0.60),
            _prow("a", "single_view", 0.021, 0.130, 0.89, 0.58),   # d syn +1e-3, d col +0.03
            _prow("b", "single_view", 0.019, 0.110, 0.91, 0.61),   # -1e-3, +0.01 (signs differ)
            _prow("c", "nav_drift", 0.025, 0.300, 0.85, 0.40),     # +5e-3, +0.2
            _prow("d", "blur", 0.023, 0.050, 0.88, 0.55),          # +3e-3, -0.05 (signs differ)
            _prow("e", "blur", None, 0.120),                       # no synthetic figure: left out
            _prow("unperturbed_repeat1", "repeat", 0.0202, 0.104, 0.90, 0.60),
            _prow("unperturbed_repeat2", "repeat", 0.0198, 0.096, 0.90, 0.60)]
    add_deltas(rows)
    assert rows[0]["synthetic_delta_error_m"] == 0.0 and rows[5]["synthetic_delta_error_m"] is None
    assert rows[3]["colmap_delta_error_m"] == pytest.approx(0.2)
    s = summarize_perturbed(rows)
    e = s["error_m"]
    assert s["perturbed_sets"] == 5 and e["pairs"] == 4
    # synthetic deltas +1, -1, +5, +3 (e-3) rank 2, 1, 4, 3; COLMAP +0.03, +0.01, +0.2, -0.05 rank 3, 2, 4, 1
    assert e["spearman_rho"] == pytest.approx(0.4)
    assert e["sign_agreement"] == pytest.approx(0.5)
    # repeat noise: std (ddof 1) over the reference and its two repeats
    assert e["repeat_noise_synthetic"] == pytest.approx(np.std([0.020, 0.0202, 0.0198], ddof=1))
    assert e["repeat_noise_colmap"] == pytest.approx(0.004)
    # |d syn| < 2e-4 nowhere, |d col| < 0.004 nowhere: no set within the noise
    assert e["below_noise_sets"] == 0 and e["sign_agreement_above_noise"] == pytest.approx(0.5)
    assert not s["spearman_target_met"]
    assert s["per_kind"]["single_view"]["sets"] == 2
    assert s["per_kind"]["single_view"]["colmap_median_delta_error_m"] == pytest.approx(0.02)
    assert s["per_kind"]["blur"]["sign_agreement_error_m"] == pytest.approx(0.0)
    c = s["completeness"]
    assert c["pairs"] == 5  # completeness is known for "e" as well
    assert c["sign_agreement"] == pytest.approx(1.0)  # a-d agree in sign; e: no change in either (0 == 0)
    # the same rows without repeats: no noise estimate, the counts are None
    s2 = summarize_perturbed(rows[:6])
    assert s2["error_m"]["repeat_noise_colmap"] is None and s2["error_m"]["below_noise_sets"] is None


def test_calibration_columns_put_colmap_beside_the_synthetic_oracle_under_its_conditions(box_on_water,
                                                                                        fast_section):
    from wrp_eval.recon.synthetic import SyntheticOracle
    from wrp_eval.recon.validate import add_calibration

    from .conftest import ring_views
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 16, target=(0, 0, 1.5))
    oracle = SyntheticOracle(fast_section)
    syn = oracle.evaluate(cs, box_on_water, seed=0)
    row = {"synthetic_error_m": syn.error_m, "colmap_error_m": 5 * syn.error_m, "colmap_n_points": 80}
    add_calibration(row, oracle, cs, box_on_water, 0, 800)
    assert row["error_ratio_colmap_to_synthetic"] == pytest.approx(5.0)
    assert syn.error_m < row["synthetic_width_error_m"] < row["synthetic_sparse_error_m"]
    assert row["error_ratio_colmap_to_sparse_equivalent"] == pytest.approx(
        row["colmap_error_m"] / row["synthetic_sparse_error_m"])
    assert row["error_ratio_colmap_to_width_equivalent"] == pytest.approx(
        row["colmap_error_m"] / row["synthetic_width_error_m"])
    bare = {"synthetic_error_m": syn.error_m, "colmap_error_m": None, "colmap_n_points": None}
    add_calibration(bare, oracle, cs, box_on_water, 0, 800)     # no COLMAP figures: no ratio, no thinning
    assert bare["error_ratio_colmap_to_synthetic"] is None and "synthetic_sparse_error_m" not in bare


def test_a_capture_sets_hash_counts_its_view_ids_only_where_set():
    import dataclasses

    from wrp_eval.recon.validate import capture_sha

    from .conftest import ring_views
    ring = ring_views((0, 0, 0), 22.0, (3.0,), 8)
    same_ids = dataclasses.replace(ring, view_id=np.arange(8))
    other_ids = dataclasses.replace(ring, view_id=np.arange(8)[::-1])
    assert capture_sha(dataclasses.replace(ring)) == capture_sha(ring)        # no ids: the hash it always had
    assert len({capture_sha(ring), capture_sha(same_ids), capture_sha(other_ids)}) == 3
