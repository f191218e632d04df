"""The COLMAP sign check's bookkeeping (the COLMAP runs themselves are the slow validation command)."""

import pytest

from wrp_eval.errors import InputError
from wrp_eval.wrp.colmap_check import COLMAP_NOISE_M, _rows, _summary, common_winds


def test_rows_and_summary_count_sign_agreement_per_wrp():
    scores = {"initial": {1: (0.020, 0.030), 2: (0.022, 0.031)},
              "iswrp": {1: (0.021, 0.033), 2: (0.021, 0.0315)},      # +1 / -1 mm synthetic; +3 / +0.5 mm COLMAP
              "swrp": {}}
    rows = _rows(scores, {"iswrp": True, "swrp": False})
    assert [(r["wind"], r["signs_agree"], r["colmap_above_noise"]) for r in rows] == [(1, True, True),
                                                                                       (2, False, False)]
    s = _summary(rows, {"iswrp": True, "swrp": False})
    assert s["iswrp"]["sign_agreement"] == 0.5 and s["iswrp"]["winds_colmap_above_noise"] == 1
    assert s["iswrp"]["sign_agreement_above_noise"] == 1.0
    assert s["iswrp"]["synthetic_mean_diff_m"] == pytest.approx(0.0) and s["iswrp"]["colmap_mean_diff_m"] > 0
    assert s["swrp"]["moved"] is False and COLMAP_NOISE_M == pytest.approx(0.0012)
    scores["initial"][3], scores["iswrp"][3] = (0.02, 0.03), (0.021, float("nan"))    # COLMAP failed: no vote
    s = _summary(_rows(scores, {"iswrp": True, "swrp": False}), {"iswrp": True, "swrp": False})
    assert s["iswrp"]["winds"] == 2 and s["iswrp"]["winds_without_a_result"] == 1
    assert s["iswrp"]["sign_agreement"] == 0.5


def test_common_winds_needs_a_finished_evaluation(tmp_path):
    with pytest.raises(InputError, match="campaign-initial"):
        common_winds(tmp_path, 10, 0)
