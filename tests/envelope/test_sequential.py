"""The envelope's sequential test and boundary search, on their own (no flights)."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.envelope.search import BoundarySearch
from wrp_eval.envelope.sequential import FAILS, MEETS, OPEN, UNDECIDED, decide, planned_looks, repeated_interval


def test_all_successes_decide_meets_only_when_the_repeated_interval_clears_the_threshold():
    looks = planned_looks(32, 8)
    assert looks == 4
    # 0.00625 ** (1 / n) >= 0.8 needs n >= 23: 16 flights are not enough, 24 are
    assert decide(16, 16, 0.8, 0.95, looks, last=False) == OPEN
    assert decide(24, 24, 0.8, 0.95, looks, last=False) == MEETS
    assert decide(0, 8, 0.8, 0.95, looks, last=False) == FAILS
    assert decide(26, 32, 0.8, 0.95, looks, last=True) == UNDECIDED


def test_the_repeated_interval_is_wider_than_one_look():
    one = repeated_interval(20, 24, 0.95, 1)
    four = repeated_interval(20, 24, 0.95, 4)
    assert four[0] < one[0] and four[1] > one[1]


def _sequential(outcomes: np.ndarray, look: int, most: int, threshold: float) -> str:
    flights, decision = 0, OPEN
    while decision == OPEN:
        flights = min(most, flights + look)
        decision = decide(int(outcomes[:flights].sum()), flights, threshold, 0.95, planned_looks(most, look),
                          last=flights >= most)
    return decision


@pytest.mark.parametrize("p_true, wrong", [(0.75, MEETS), (0.85, FAILS)])
def test_the_whole_sequential_procedure_errs_rarely_on_either_side(p_true, wrong):
    """2000 seeded cells with the true probability on one side of 0.8: the test decides the wrong side in at
    most 2.5 % of them (the repeated intervals' one-sided level), looks and early stops included."""
    rng = np.random.default_rng(29)
    outcomes = rng.random((2000, 32)) < p_true
    decisions = [_sequential(row, 8, 32, 0.8) for row in outcomes]
    assert np.mean([d == wrong for d in decisions]) <= 0.025


def _search(boundary: float, speeds=(0, 2, 4, 6, 8, 10, 12, 14, 16), resolution=0.5):
    search, flown = BoundarySearch(tuple(float(s) for s in speeds), resolution), []
    while (speed := search.next_speed()) is not None:
        flown.append(speed)
        search.record(speed, speed <= boundary)
    return search, flown


@pytest.mark.parametrize("boundary", [0.0, 3.3, 7.9, 10.0, 11.2, 15.9])
def test_the_search_brackets_a_monotone_boundary_to_the_resolution(boundary):
    search, flown = _search(boundary)
    low, high = search.boundary_m_s, search.lowest_failing
    assert low <= boundary < high and high - low <= 0.5
    assert len(flown) == len(set(flown)) <= 6          # 9 grid speeds: 3-4 grid cells + 2 bisections


def test_the_search_reports_a_boundary_off_the_grid():
    above, _ = _search(99.0)
    assert above.above_grid and above.boundary_m_s == 16.0 and above.lowest_failing is None
    below, flown = _search(-1.0, speeds=(2, 4, 6))
    assert below.boundary_m_s is None and below.lowest_failing == 2.0 and flown == [4.0, 2.0]


def test_one_failure_in_32_never_proves_the_threshold_with_four_looks():
    """With at most 32 flights in 4 looks only a cell without a miss is proved (the README says so): the
    repeated lower bound of 31 of 32 stays below 0.8, and such a cell ends undecided."""
    assert repeated_interval(31, 32, 0.95, 4)[0] < 0.8
    assert decide(31, 32, 0.8, 0.95, 4, last=True) == UNDECIDED
