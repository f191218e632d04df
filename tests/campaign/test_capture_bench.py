"""The capture bench's lag correlation: pairs of views of one flight less than 30 s apart."""

import numpy as np

from wrp_eval.campaign.capture_bench import lag_correlation


def _offsets(per_view: np.ndarray) -> np.ndarray:
    out = np.zeros(per_view.shape[:2] + (4,))
    out[..., :2] = per_view
    return out


def test_errors_shared_within_a_flight_correlate_fully_and_independent_ones_do_not():
    rng = np.random.default_rng(0)
    times = np.tile(np.arange(20) * 5.0, (300, 1))                     # a view every 5 s
    shared = np.repeat(rng.normal(size=(300, 1, 2)), 20, axis=1)        # one offset per flight
    assert lag_correlation(_offsets(shared), times) > 0.999
    independent = rng.normal(size=(300, 20, 2))
    assert abs(lag_correlation(_offsets(independent), times)) < 0.05


def test_only_pairs_closer_than_the_lag_count_and_views_not_taken_are_left_out():
    rng = np.random.default_rng(1)
    # views 0-9 share one offset, views 10-19 another; the halves are 100 s apart, so only within-half pairs
    halves = rng.normal(size=(200, 2, 2))
    per_view = np.concatenate([np.repeat(halves[:, :1], 10, axis=1), np.repeat(halves[:, 1:], 10, axis=1)], axis=1)
    times = np.concatenate([np.arange(10) * 2.0, 100.0 + np.arange(10) * 2.0])
    times = np.tile(times, (200, 1))
    times[:, 5] = np.nan                                               # a view not taken
    assert lag_correlation(_offsets(per_view), times, lag_s=30.0) > 0.999
    # every pair counts now: 81 within-half pairs correlate fully, 90 cross-half pairs not at all -> ~81/171
    assert 0.35 < lag_correlation(_offsets(per_view), times, lag_s=200.0) < 0.6
