from dataclasses import replace

import numpy as np
import pytest

from wrp_eval.planning.path import FlightPath
from wrp_eval.wrp.optimize import (
    WrpParams,
    apply_offsets,
    interval_optimise,
    iteration_draws,
    neighbourhood_statistic,
    sample_radii,
)

from .conftest import params_for, small_surrogate, wrp_params


def reference_optimise(s, p: WrpParams, seed: int) -> np.ndarray:
    """Alg. 3 / 4 written as the paper's sequential loop, one iteration at a time, full forward passes,
    the last accepted iteration kept (line 16 overwrites)."""
    n = s.n_views
    offsets = np.zeros((n, 4))
    for i in range(n):
        kept = np.zeros(4)
        for j in range(p.iterations):
            d = iteration_draws(seed, i, j // p.block_iterations, p)
            r = j % p.block_iterations
            cand = offsets.copy()
            errs = []
            for a in d.yaw[r]:                                             # Alg. 4, one query at a time
                cand[i] = [*d.position[r], a]
                errs.append(s.predict(cand[None])[0])
            best = int(np.argmin(errs))
            e = errs[best]
            if abs(e - p.e_original_m) > p.threshold_m:
                continue
            sample_errors = []
            for k in range(p.neighbourhood_samples):
                centre = d.position[r] + d.neighbour_offset[r, k]
                ek = []
                for a in d.neighbour_yaw[r, k]:
                    cand[i] = [*centre, a]
                    ek.append(s.predict(cand[None])[0])
                sample_errors.append(min(ek))
            if neighbourhood_statistic(np.array(sample_errors), p) <= p.threshold_m:
                kept = np.array([*d.position[r], d.yaw[r, best]])
        offsets[i] = kept
    return offsets


@pytest.mark.parametrize("kind,threshold,gain,error_std,spread", [("iswrp", 0.002, 20.0, 1.0, "std"),
                                                                  ("swrp", 1e-5, 1.0, 0.05, "variance"),
                                                                  ("swrp", 1e-5, 1.0, 0.05, "std")])
def test_batched_scan_equals_the_sequential_algorithm(kind, threshold, gain, error_std, spread):
    s = small_surrogate(5, seed=1, gain=gain, error_std=error_std)
    p = params_for(s, kind, threshold, iterations=20, block_iterations=6, swrp_spread=spread)
    result = interval_optimise(s, p, seed=11)
    expect = reference_optimise(s, p, seed=11)
    np.testing.assert_allclose(result.offsets, expect, atol=1e-9)
    assert 0 < result.moved.sum() < 5                              # the case is not trivial
    assert np.any((result.accepted_iteration >= 0) & (result.accepted_iteration < p.iterations - 1))


@pytest.mark.parametrize("kind,threshold,spread", [("iswrp", 0.004, "std"), ("swrp", 1e-3, "variance"),
                                                   ("swrp", 0.03, "std")])
def test_accepted_moves_satisfy_the_criterion_and_bounds(kind, threshold, spread):
    surrogate = small_surrogate(6, seed=0, error_std=1.0, gain=20.0)
    p = params_for(surrogate, kind, threshold, swrp_spread=spread)
    r = interval_optimise(surrogate, p, seed=2)
    assert r.moved.any()
    assert np.all(np.abs(r.offsets[:, :3]) <= p.step_m)
    assert np.all(np.abs(r.offsets[:, 3]) <= p.yaw_range_rad)
    for i in np.flatnonzero(r.moved):
        context = r.offsets.copy()
        context[i + 1:] = 0.0                 # later viewpoints were still at their planned pose
        e = surrogate.predict(context[None])[0]
        assert e == pytest.approx(r.stage1_error[i], abs=2e-5)
        assert abs(e - p.e_original_m) <= p.threshold_m + 1e-9
        assert r.neighbourhood_stat[i] <= p.threshold_m
    assert np.all(r.offsets[~r.moved] == 0)
    assert r.predicted_error_m == pytest.approx(surrogate.predict(r.offsets[None])[0])


def test_moved_viewpoints_stay_above_the_minimum_altitude_and_out_of_the_no_fly_box():
    surrogate = small_surrogate(6, seed=0, error_std=1.0, gain=20.0)
    free = interval_optimise(surrogate, params_for(surrogate, "iswrp", 0.004), seed=2)
    assert free.moved.any()
    # planned viewpoints just above the minimum altitude, beside a no-fly box: many free moves break one
    base = np.column_stack([np.linspace(-10, 10, 6), np.full(6, 6.0), np.full(6, 5.5)])
    box = np.array([[-20.0, -20.0, 0.0], [20.0, 5.0, 30.0]])
    p = params_for(surrogate, "iswrp", 0.004)
    p = replace(p, base_positions=base, min_altitude_m=5.0, no_fly_bounds=box)
    assert not np.all(p.feasible(0, free.offsets[:, :3]))            # the case is not trivial
    r = interval_optimise(surrogate, p, seed=2)
    moved_to = base + r.offsets[:, :3]
    assert np.all(moved_to[:, 2] >= 5.0)
    assert not np.any(np.all((moved_to >= box[0]) & (moved_to <= box[1]), axis=1))


def test_threshold_zero_moves_nothing_and_scores_every_iteration_once_per_block(surrogate):
    p = params_for(surrogate, "iswrp", 0.0)
    r = interval_optimise(surrogate, p, seed=0)
    assert not r.moved.any() and np.all(r.offsets == 0)
    blocks = -(-p.iterations // p.block_iterations)
    # one batched forward pass per block of iterations (every attitude sample of the block together)
    assert r.forward_calls == surrogate.n_views * blocks
    assert r.queries == surrogate.n_views * p.iterations * p.attitude_samples
    assert r.iterations_scored == surrogate.n_views * p.iterations


def test_forward_pass_count_with_stage_two(surrogate):
    p = params_for(surrogate, "swrp", 1.0, stage2_batch=100)          # everything passes at once
    r = interval_optimise(surrogate, p, seed=0)
    assert r.moved.all()
    # per viewpoint: one stage-1 pass over the last block, one stage-2 pass over all its survivors
    assert r.forward_calls == 2 * surrogate.n_views
    assert np.all(r.accepted_iteration == p.iterations - 1)           # the last iteration wins


def test_same_seed_same_result_and_batching_does_not_matter(surrogate):
    p = params_for(surrogate, "iswrp", 0.01)
    a = interval_optimise(surrogate, p, seed=4)
    b = interval_optimise(surrogate, p, seed=4)
    c = interval_optimise(surrogate, replace(p, stage2_batch=1), seed=4)
    d = interval_optimise(surrogate, p, seed=5)
    np.testing.assert_array_equal(a.offsets, b.offsets)
    np.testing.assert_array_equal(a.offsets, c.offsets)
    assert not np.array_equal(a.offsets, d.offsets)


def test_neighbourhood_statistic_hand_computed():
    e = np.array([[1.0, 2.0, 3.0]])
    p = wrp_params("iswrp", 0.1, 1.5, np.ones(1))
    assert neighbourhood_statistic(e, p)[0] == pytest.approx(0.5)
    assert neighbourhood_statistic(e, wrp_params("swrp", 0.1, 1.5, np.ones(1), swrp_spread="variance"))[0] == \
        pytest.approx(2 / 3)
    # the default: the standard deviation, in the unit of t (issue 18)
    assert neighbourhood_statistic(e, wrp_params("swrp", 0.1, 1.5, np.ones(1)))[0] == pytest.approx(np.sqrt(2 / 3))


def test_draws_respect_radii_and_ranges():
    p = wrp_params("iswrp", 0.1, 1.0, np.array([0.3, 2.0]), attitude_samples=7, neighbourhood_samples=50,
                  step_m=1.2, block_iterations=30)
    for view, radius in ((0, 0.3), (1, 2.0)):
        d = iteration_draws(1, view, 0, p)
        assert np.all(np.linalg.norm(d.neighbour_offset, axis=-1) <= radius + 1e-12)
        assert np.linalg.norm(d.neighbour_offset, axis=-1).max() > 0.8 * radius
        assert np.all(np.abs(d.position) <= 1.2) and np.all(np.abs(d.yaw) <= p.yaw_range_rad)
        assert d.yaw.shape == (30, 7) and d.neighbour_yaw.shape == (30, 50, 7)



def test_draws_are_the_stream_in_its_documented_order():
    """neighbour_yaw is drawn on first use: the same numbers as one eager pass over the block's stream."""
    p = wrp_params("iswrp", 0.1, 1.0, np.array([0.3, 2.0]), attitude_samples=7, neighbourhood_samples=5,
                   step_m=1.2, block_iterations=4)
    d = iteration_draws(3, 1, 2, p)
    rng = np.random.default_rng(np.random.SeedSequence(3, spawn_key=(1, 2)))
    y = p.yaw_range_rad
    position, yaw = rng.uniform(-1.2, 1.2, size=(4, 3)), rng.uniform(-y, y, size=(4, 7))
    rng.normal(size=(4, 5, 3))
    rng.uniform(size=(4, 5, 1))                                   # the ball's radii
    neighbour_yaw = rng.uniform(-y, y, size=(4, 5, 7))
    np.testing.assert_array_equal(d.position, position)
    np.testing.assert_array_equal(d.yaw, yaw)
    np.testing.assert_array_equal(d.neighbour_yaw, neighbour_yaw)
    assert d.neighbour_yaw is d.neighbour_yaw                      # drawn once

def test_sample_radii_quantile():
    dev = np.zeros((5, 2, 4))
    dev[:, 0, 0] = [0.1, 0.2, 0.3, 0.4, 0.5]
    dev[:, 1, 1] = [1, 1, 1, 1, np.nan]
    np.testing.assert_allclose(sample_radii(dev, 0.5), [0.3, 1.0])


def test_apply_offsets_moves_positions_and_wraps_yaw():
    n = 3
    path = FlightPath(np.zeros((n, 3)), np.array([3.0, 0.0, -3.0]), np.full(n, -0.2), np.zeros(n, int),
                      np.zeros(n, int), np.zeros(n, int))
    off = np.array([[1, 0, 0, 0.3], [0, 2, 0, 0.0], [0, 0, -1, -0.3]])
    wrp = apply_offsets(path, off, {"wrp": {"kind": "iswrp"}})
    np.testing.assert_allclose(wrp.positions, off[:, :3])
    np.testing.assert_allclose(wrp.yaw, [3.3 - 2 * np.pi, 0.0, -3.3 + 2 * np.pi])
    assert wrp.metadata["wrp"]["kind"] == "iswrp" and np.all(wrp.pitch == path.pitch)


@pytest.mark.parametrize("kind, threshold, margin", [("iswrp", 0.5, 0.1), ("swrp", 0.05, 0.0)])
def test_improve_acceptance_moves_only_to_a_better_neighbourhood(kind, threshold, margin):
    from wrp_eval.wrp.optimize import ViewQuery, best_attitude, iteration_draws, neighbourhood_score
    surrogate = small_surrogate(6, seed=0, error_std=1.0, gain=20.0)
    p = params_for(surrogate, kind, threshold, acceptance="improve", min_improvement_fraction=margin)
    r = interval_optimise(surrogate, p, seed=2)
    paper = interval_optimise(surrogate, params_for(surrogate, kind, threshold), seed=2)
    assert r.moved.sum() <= paper.moved.sum() and r.moved.any()
    n_blocks = -(-p.iterations // p.block_iterations)
    for i in range(surrogate.n_views):
        context = r.offsets.copy()
        context[i:] = 0.0                      # the base this viewpoint was optimised against
        query = ViewQuery(surrogate, context)
        home = iteration_draws(2, i, n_blocks, p)
        _, e_home = best_attitude(query, i, home.neighbour_offset[:1], home.neighbour_yaw[:1])
        home_score = neighbourhood_score(e_home, p)[0]
        if r.moved[i]:
            assert r.neighbourhood_stat[i] <= p.threshold_m
            # its score beats the unmoved viewpoint's by the margin: recompute it from the kept draw
            j = r.accepted_iteration[i]
            d = iteration_draws(2, i, j // p.block_iterations, p)
            k = j % p.block_iterations
            centres = r.offsets[i, :3][None, None, :] + d.neighbour_offset[k:k + 1]
            _, ek = best_attitude(query, i, centres, d.neighbour_yaw[k:k + 1])
            assert neighbourhood_score(ek, p)[0] < home_score - margin * p.threshold_m
        else:
            assert np.all(r.offsets[i] == 0)


def test_improve_acceptance_keeps_a_flat_surrogate_path_unmoved():
    # gain 0: the offsets do not reach the output, every candidate scores like the planned viewpoint
    surrogate = small_surrogate(6, seed=0, error_std=1.0, gain=0.0)
    r = interval_optimise(surrogate, params_for(surrogate, "iswrp", 0.5, acceptance="improve"), seed=1)
    assert not r.moved.any()
    paper = interval_optimise(surrogate, params_for(surrogate, "iswrp", 0.5), seed=1)
    assert paper.moved.all()                  # Alg. 3 as written moves every viewpoint of a flat surrogate


def test_measured_neighbourhood_follows_the_campaigns_offset_covariance():
    from wrp_eval.wrp.optimize import iteration_draws, offset_cholesky
    rng = np.random.default_rng(5)
    cov = np.array([[4.0, 1.2, 0.0], [1.2, 1.0, 0.0], [0.0, 0.0, 0.04]])      # anisotropic and correlated
    dev = np.zeros((4000, 2, 4))
    dev[:, 0, :3] = rng.multivariate_normal([0.3, 0.0, 0.0], cov, 4000)
    dev[:, 1, :3] = rng.normal(0.0, 0.1, (4000, 3))
    dev[::7, 0] = np.nan                                                    # views not taken are left out
    chol = offset_cholesky(dev)
    np.testing.assert_allclose(chol[0] @ chol[0].T, cov, atol=0.15)
    p = wrp_params("swrp", 0.01, 1.0, np.full(2, 0.5), block_iterations=500, neighbourhood_samples=8,
                  neighbour_cholesky=chol)
    draws = iteration_draws(0, 0, 0, p).neighbour_offset.reshape(-1, 3)
    np.testing.assert_allclose(np.cov(draws.T), cov, atol=0.25)             # about the candidate, not a ball
    ball = iteration_draws(0, 0, 0, wrp_params("swrp", 0.01, 1.0, np.full(2, 0.5), block_iterations=500,
                                              neighbourhood_samples=8)).neighbour_offset.reshape(-1, 3)
    assert np.linalg.norm(ball, axis=1).max() <= 0.5 + 1e-12


def test_validated_acceptance_needs_a_validated_error_and_beats_staying_by_twice_it():
    surrogate = small_surrogate(6, seed=0, error_std=1.0, gain=20.0)
    unvalidated = interval_optimise(surrogate, params_for(surrogate, "iswrp", 0.5, acceptance="validated"), seed=2)
    assert not unvalidated.moved.any() and unvalidated.iterations_scored > 0     # searched, nothing justified
    t = 0.5
    small = interval_optimise(surrogate, params_for(surrogate, "iswrp", t, acceptance="validated",
                                                    validated_error_m=0.01 * t), seed=2)
    same = interval_optimise(surrogate, params_for(surrogate, "iswrp", t, acceptance="improve",
                                                   min_improvement_fraction=0.02), seed=2)
    np.testing.assert_array_equal(small.offsets, same.offsets)        # margin 2 x 0.01 t = 0.02 t
    huge = interval_optimise(surrogate, params_for(surrogate, "iswrp", t, acceptance="validated",
                                                   validated_error_m=100.0), seed=2)
    assert small.moved.any() and not huge.moved.any()


def test_cvar_is_the_mean_of_the_worst_tail():
    from wrp_eval.wrp.optimize import cvar, neighbourhood_score
    e = np.array([[1.0, 5.0, 2.0, 4.0, 3.0], [0.0, 0.0, 0.0, 0.0, 10.0]])
    np.testing.assert_allclose(cvar(e, 0.6), [4.5, 5.0])                  # the worst 2 of 5
    np.testing.assert_allclose(cvar(e, 0.0), e.mean(axis=1))
    p = wrp_params("iswrp", 0.1, 1.0, np.full(2, 0.5), risk_measure="cvar", cvar_alpha=0.8)
    np.testing.assert_allclose(neighbourhood_score(e, p), [5.0, 10.0])
    with pytest.raises(ValueError):
        wrp_params("iswrp", 0.1, 1.0, np.full(2, 0.5), risk_measure="var")


def test_the_table3_row_is_typed_and_round_trips_as_stored(surrogate):
    from wrp_eval.wrp.optimize import Table3Row

    r = interval_optimise(surrogate, params_for(surrogate, "iswrp", 0.004), seed=2)
    row = r.table3()
    assert isinstance(row, Table3Row) and row.viewpoints == surrogate.n_views
    assert row.moved == int(r.moved.sum()) and row.offset_rate_pct == pytest.approx(100.0 * r.moved.mean())
    doc = row.to_json_dict()
    assert "oracle" not in doc and "oracle_confirm_s" not in doc and doc["oracle_error_m"] is None
    assert Table3Row.from_json_dict(doc) == row
    scored = replace(row, oracle_error_m=0.02, oracle={"error_m": 0.02}, oracle_confirm_s=1.5)
    assert Table3Row.from_json_dict(scored.to_json_dict()) == scored
