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
