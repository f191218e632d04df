"""The sim bench's ratio records (wrp_eval/sim/bench.py): sim.ratio divides the best run of each side; the paired
median takes each round's closed run against the raw run beside it."""

import pytest

from wrp_eval.sim.bench import _ratio_records


def _ratios(raw, closed):
    runs = {"raw": [(r, r) for r in raw], "closed": [(c, c) for c in closed], "bare": [(2.0, 2.0)] * len(raw)}
    records = {r.name: r.value for r in _ratio_records(64, runs, 2, "")}
    return records["sim.ratio_batch64"], records["sim.ratio_paired_median_batch64"]


def test_the_paired_median_keeps_a_spell_that_slowed_only_the_raw_runs_out_of_the_ratio():
    # a steady machine: both say 0.55
    assert _ratios([1.0, 1.0, 1.0], [0.55, 0.56, 0.55]) == pytest.approx((0.56, 0.55))
    # every raw run fell on a slow spell and one closed run did not: the best-of ratio reads 0.93, two of the three
    # rounds still say 0.55
    best, paired = _ratios([0.6, 0.6, 0.6], [0.56, 0.33, 0.33])
    assert best == pytest.approx(0.56 / 0.6) and paired == pytest.approx(0.55)
    # a machine that slows between rounds moves neither
    assert _ratios([1.0, 0.6, 0.6], [0.56, 0.33, 0.33]) == pytest.approx((0.56, 0.55))
