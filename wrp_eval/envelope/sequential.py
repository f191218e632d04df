"""The sequential test of one envelope cell: stop flying when the confidence interval of P(meets spec) lies
wholly on one side of the threshold.

A cell is flown in looks of ``look_flights`` flights, at most ``looks`` = ceil(max_flights / look_flights) of
them. At every look the exact Clopper-Pearson interval (Clopper & Pearson 1934, Biometrika 26:404) of
P(meets spec) is computed at the confidence level ``1 - (1 - confidence) / looks``: by the Bonferroni
inequality the K intervals of a cell then hold the true probability together with at least the stated
confidence, however many looks stop early (repeated confidence intervals, Jennison & Turnbull 1989,
J. R. Stat. Soc. B 51:305; "Group Sequential Methods", 2000, ch. 9, of which this Bonferroni split is the
simple conservative case). The cell

* **meets** the threshold when the interval's lower bound reaches it,
* **fails** it when the upper bound falls below it,
* otherwise flies another look; after the last look it is **undecided** and is classified by its point
  estimate (P >= threshold counts as meeting; the report says "undecided").

So 0 failures in 24 flights decide "meets 0.8" at 95 % with 4 looks (0.00625^(1/n) >= 0.8 needs n >= 23), and
0 successes decide "fails" at the first look of 8.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

MEETS, FAILS, UNDECIDED, OPEN = "meets", "fails", "undecided", "open"


def planned_looks(max_flights: int, look_flights: int) -> int:
    """The number of looks of a cell flown to ``max_flights``."""
    return math.ceil(max_flights / look_flights)


def clopper_pearson(successes, trials, confidence: float) -> tuple[np.ndarray, np.ndarray]:
    """The exact two-sided interval (low, high) of a binomial proportion; arrays broadcast (trials >= 1)."""
    k, n = np.asarray(successes, float), np.asarray(trials, float)
    alpha = 1.0 - confidence
    with np.errstate(invalid="ignore"):
        low = np.where(k > 0, stats.beta.ppf(alpha / 2, k, n - k + 1), 0.0)
        high = np.where(k < n, stats.beta.ppf(1 - alpha / 2, k + 1, n - k), 1.0)
    return low, high


def repeated_interval(successes: int, trials: int, confidence: float, looks: int) -> tuple[float, float]:
    """The cell's interval at one of its ``looks`` looks: Clopper-Pearson at ``1 - (1 - confidence) / looks``."""
    low, high = clopper_pearson(successes, trials, 1.0 - (1.0 - confidence) / looks)
    return float(low), float(high)


def decide(successes: int, trials: int, threshold: float, confidence: float, looks: int, last: bool) -> str:
    """MEETS / FAILS when the repeated interval lies on one side of ``threshold``; else OPEN, or UNDECIDED at
    the ``last`` look."""
    low, high = repeated_interval(successes, trials, confidence, looks)
    if low >= threshold:
        return MEETS
    if high < threshold:
        return FAILS
    return UNDECIDED if last else OPEN


def counts_as_meeting(decision: str, p_hat: float, threshold: float) -> bool:
    """Whether a finished cell counts as meeting the threshold (an undecided one by its point estimate)."""
    return decision == MEETS or (decision == UNDECIDED and p_hat >= threshold)
