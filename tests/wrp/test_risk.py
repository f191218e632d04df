"""Per-view risk: the error spread a viewpoint adds when the flights miss it."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.experiment import ExperimentContext
from wrp_eval.wrp.risk import view_risk


def test_risk_is_the_cost_of_missing_a_view_times_its_miss_spread():
    ctx = ExperimentContext.load("experiments/quickstart.yaml")
    path = ctx.plan_with("ours").path
    n = len(path)
    offsets = np.zeros((8, n, 4))
    offsets[:4, 3] = np.nan              # view 3 missed in half of the flights
    offsets[:, 7] = np.nan               # view 7 missed in every flight: no spread from it
    risk = view_risk(ctx.scored_ship, path, offsets)
    assert risk.p_missed[3] == 0.5 and risk.p_missed[7] == 1.0 and risk.p_missed[0] == 0.0
    assert risk.risk_m[3] == pytest.approx(0.5 * abs(risk.loss_m[3]))
    assert risk.risk_m[7] == 0.0 and np.count_nonzero(risk.risk_m) <= 1
    assert np.all(np.isfinite(risk.loss_m)) and risk.base_error_m > 0
    assert np.any(risk.loss_m > 0)       # some views carry coverage no other view has
