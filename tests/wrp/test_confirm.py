"""The oracle's confirmation of moves, against an oracle of known response (a test double of ScoredShip)."""

from types import SimpleNamespace

import numpy as np
import pytest

from wrp_eval.wrp.confirm import confirm_moves, neighbour_draws

from .conftest import helpers, wrp_params


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
    params = wrp_params("iswrp", 0.1, 1.0, np.full(5, 0.2))
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


def test_oracle_verdicts_need_a_gain_beyond_the_oracles_noise_and_count_failures():
    from wrp_eval.wrp.confirm import oracle_verdicts
    rng = np.random.default_rng(0)
    base = 0.03 + rng.normal(0, 0.002, 8)
    errors = np.stack([
        np.stack([base - 0.001, base]),                          # 1 mm better in every draw: confirmed
        np.stack([base - 0.002 * np.array([1, -1, 1, -1, 1, -1, 0.5, -0.3]), base]),   # +0.05 mm < 2 SE
        np.stack([base, np.r_[base[:7], np.nan]]),               # without it one draw fails: confirmed
        np.stack([np.r_[np.nan, base[1:]], base]),               # with it one draw fails: rejected
    ])
    gain, ok = oracle_verdicts(errors, wrp_params("iswrp", 0.1, 0.03, np.full(4, 0.2)))
    assert ok.tolist() == [True, False, True, False]
    assert gain[0] == pytest.approx(0.001) and gain[1] == pytest.approx(0.00005) and np.isnan(gain[2:]).all()
    swrp = wrp_params("swrp", 0.1, 0.03, np.full(4, 0.2), acceptance="validated", validated_error_m=1e-4)
    spread = np.stack([np.stack([np.full(8, 0.03), 0.03 + np.linspace(-0.003, 0.003, 8)])])
    g, ok = oracle_verdicts(spread, swrp)                       # the spread drops by ~2.2 mm > 2 x 0.1 mm
    assert ok.tolist() == [True] and g[0] > 2e-4


def test_revert_puts_rejected_views_back_and_keeps_the_rest():
    from wrp_eval.wrp.jobs import revert
    from wrp_eval.wrp.optimize import WrpResult

    from .conftest import small_surrogate
    s = small_surrogate(4, seed=0, error_std=1.0, gain=20.0)
    offsets = np.array([[0.5, 0, 0, 0.1], [0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, -1.0, 0]])
    moved = np.array([True, False, True, True])
    r = WrpResult(offsets, moved, np.array([3, -1, 5, 7]), np.array([1.0, np.nan, 2.0, 3.0]),
                  np.array([0.1, np.nan, 0.2, 0.3]), 0.0, 1.0, 1, 1, wrp_params("iswrp", 0.1, 1.0, np.full(4, 0.5)))
    out = revert(r, np.array([False, False, True, False]), s)
    assert out.moved.tolist() == [True, False, False, True]
    np.testing.assert_array_equal(out.offsets[2], 0.0)
    np.testing.assert_array_equal(out.offsets[[0, 3]], offsets[[0, 3]])
    assert out.accepted_iteration.tolist() == [3, -1, -1, 7] and np.isnan(out.stage1_error[2])
    assert out.predicted_error_m == pytest.approx(float(s.predict(out.offsets[None])[0]))
