"""The oracle's confirmation of moves, against an oracle of known response (a test double of ScoredShip)."""

from types import SimpleNamespace

import numpy as np

from wrp_eval.wrp.confirm import confirm_moves, neighbour_draws
from wrp_eval.wrp.optimize import WrpParams

from .conftest import helpers


class KnownOracle:
    """error = sum over views of |position - best_i|: moving view i toward best_i lowers it."""

    def __init__(self, best: np.ndarray):
        self.best, self.calls = best, 0

    def score(self, captures, seed=0):
        self.calls += 1
        return SimpleNamespace(error_m=float(np.linalg.norm(captures.positions - self.best, axis=1).sum()))


def test_confirmation_keeps_moves_the_oracle_agrees_with_and_reverts_the_others():
    path = helpers.make_path(5)
    planned = np.asarray(path.positions)
    best = planned.copy()
    best[1] += [3.0, 0.0, 0.0]
    best[3] += [0.0, 0.0, -3.0]
    offsets = np.zeros((5, 4))
    offsets[1, :3] = [2.0, 0.0, 0.0]           # toward view 1's best: confirmed
    offsets[3, :3] = [0.0, 0.0, 2.0]           # away from view 3's best: rejected
    offsets[4, 3] = 0.1                        # yaw only: the known oracle does not care, no gain: rejected
    moved = np.array([False, True, False, True, True])
    params = WrpParams("iswrp", 0.1, 1.0, np.full(5, 0.2))
    oracle = KnownOracle(best)
    c = confirm_moves(oracle, path, offsets, moved, params, seed=4, samples=6)
    assert c.confirmed.tolist() == [False, True, False, False, False]
    assert c.rejected.tolist() == [False, False, False, True, True]
    assert oracle.calls == c.oracle_calls == 3 * 2 * 6
    assert np.isnan(c.oracle_gain_m[[0, 2]]).all()
    assert 1.5 < c.oracle_gain_m[1] < 2.5 and -2.5 < c.oracle_gain_m[3] < -1.5
    again = confirm_moves(KnownOracle(best), path, offsets, moved, params, seed=4, samples=6)
    np.testing.assert_array_equal(again.oracle_gain_m, c.oracle_gain_m)           # seeded
    assert np.all(np.linalg.norm(neighbour_draws(params, 1, 50, 0), axis=1) <= 0.2 + 1e-12)   # the r_s ball
