"""Navigation estimate: GM closed forms, hold at the fix rate (raw-fix), the fused GNSS + IMU filter (Riccati
gains, matched covariance, smoothness, GM offset kept), latency, ideal == truth, near-hull taper, batch
independence, seeds, preset derivations (hover spec, PX4 plugin recursion) and config validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError
from scipy.signal import lfilter

from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model
from wrp_eval.sim.navigation import (
    EKF2_GPS_DELAY_S,
    FILTER_ACCEL_PSD,
    K95_1D,
    K95_2D,
    NavigationEstimator,
    NavigationSection,
    fusion_gain,
    hover_p95_spec_m,
    inertial_error_step,
    navigation_params,
    near_hull_taper,
    px4_plugin_gm,
)

DT = 0.05  # the simulator's control chunk (20 Hz)


def make(n: int, seed: int = 0, estimator: str = "raw-fix", **overrides) -> NavigationEstimator:
    """An estimator whose error terms are only ``overrides`` (on top of the all-zero ideal preset); raw fixes
    unless ``estimator`` says "fused" (the fix error model itself is what most tests here check)."""
    params = navigation_params(NavigationSection(preset="ideal", estimator=estimator, **overrides))
    return NavigationEstimator(params, seed, n, DT, block_steps=64)


def run(est: NavigationEstimator, steps: int, pos=None, vel=None, yaw=None, hull=None):
    """Errors of ``steps`` consecutive chunks: position (steps, n, 3), velocity (steps, n, 3), yaw (steps, n)."""
    n = est.n_flights
    pos = np.zeros((n, 3)) if pos is None else pos
    vel = np.zeros((n, 3)) if vel is None else vel
    yaw = np.zeros(n) if yaw is None else yaw
    out = [est.estimate(k * DT, pos + vel * k * DT, vel, yaw, hull) for k in range(steps)]
    return (np.stack([o.position_error for o in out]), np.stack([o.velocity - vel for o in out]),
            np.stack([o.yaw_error for o in out]))


def test_gm_stationary_variance_and_autocorrelation_match_closed_forms():
    # 3000 flights: the horizontal variance pools 6000 samples (rel. std of a variance sqrt(2/6000) = 1.8 %,
    # tolerance 8 %), the vertical 3000 (2.6 %, 10 %); a correlation of 6000 pairs has std <= 1/sqrt(6000)
    # = 0.013 (tolerance 0.05). Update every chunk so the sampled error is the GM state itself.
    sigma_h, sigma_v, tau = 1.0, 0.5, 1.0
    est = make(3000, seed=1, horizontal_sigma_m=sigma_h, vertical_sigma_m=sigma_v, correlation_time_s=tau,
               update_rate_hz=1 / DT)
    err, _, _ = run(est, 41)
    for k in (0, 40):   # the stationary initial draw, and after 40 exact steps
        assert np.var(err[k, :, :2]) == pytest.approx(sigma_h**2, rel=0.08)
        assert np.var(err[k, :, 2]) == pytest.approx(sigma_v**2, rel=0.10)
    for lag in (10, 20, 40):
        r = np.corrcoef(err[0, :, :2].ravel(), err[lag, :, :2].ravel())[0, 1]
        assert r == pytest.approx(math.exp(-lag * DT / tau), abs=0.05)


def test_error_is_held_between_fixes_while_the_estimate_follows_the_truth():
    est = make(5, seed=2, horizontal_sigma_m=1.0, white_noise_m=1.0, correlation_time_s=1.0, update_rate_hz=5.0)
    vel = np.random.default_rng(9).normal(0, 3, (5, 3))
    err, _, _ = run(est, 12, vel=vel)             # 5 Hz at 20 Hz chunks: a new fix every 4 chunks
    for start in (0, 4, 8):
        for k in range(start + 1, start + 4):
            np.testing.assert_array_equal(err[k], err[start])
    assert np.all(err[4, :, :2] != err[0, :, :2]) and np.all(err[8, :, :2] != err[4, :, :2])


def test_gm_path_does_not_depend_on_the_fix_rate():
    # The GM advances every chunk; the fix only samples it: at common fix steps both rates see the same state.
    fast = run(make(4, seed=3, horizontal_sigma_m=1.0, correlation_time_s=2.0, update_rate_hz=20.0), 9)[0]
    slow = run(make(4, seed=3, horizontal_sigma_m=1.0, correlation_time_s=2.0, update_rate_hz=5.0), 9)[0]
    for k in (0, 4, 8):
        np.testing.assert_array_equal(slow[k], fast[k])
    assert not np.array_equal(slow[5], fast[5])


def test_latency_makes_the_estimate_lag_by_velocity_times_delay():
    est = make(4, seed=4, latency_s=0.12)
    vel = np.array([[5.0, 0, 0], [0, -3.0, 1.0], [0, 0, 0], [2.0, 2.0, -1.0]])
    pos = np.arange(12.0).reshape(4, 3)
    out = est.estimate(0.0, pos, vel, np.zeros(4))
    np.testing.assert_allclose(out.position_error, -vel * 0.12, rtol=0, atol=1e-15)
    np.testing.assert_allclose(out.position, pos - vel * 0.12, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(out.velocity, vel)
    np.testing.assert_array_equal(out.yaw_error, 0.0)
    # the fused filter compensates EKF2_GPS_DELAY (0.11 s) of it: 10 ms are left
    fused = make(4, seed=4, estimator="fused", latency_s=0.12).estimate(0.0, pos, vel, np.zeros(4))
    np.testing.assert_allclose(fused.position_error, -vel * (0.12 - EKF2_GPS_DELAY_S), rtol=0, atol=1e-15)


def test_ideal_is_the_truth_bit_for_bit_and_draws_nothing():
    gens = [np.random.default_rng(i) for i in range(3)]
    before = [g.bit_generator.state for g in gens]
    est = NavigationEstimator(navigation_params(NavigationSection(preset="ideal")), gens, 3, DT)
    rng = np.random.default_rng(5)
    for k in range(5):
        pos, vel, yaw = rng.normal(size=(3, 3)), rng.normal(size=(3, 3)), rng.normal(size=3)
        out = est.estimate(k * DT, pos, vel, yaw, np.zeros(3))
        np.testing.assert_array_equal(out.position, pos)
        np.testing.assert_array_equal(out.velocity, vel)
        np.testing.assert_array_equal(out.yaw, yaw)
        assert not out.position_error.any() and not out.yaw_error.any()
    assert [g.bit_generator.state for g in gens] == before


def test_near_hull_bias_applies_only_within_the_distance():
    n, reach = 2000, 20.0
    est = make(n, seed=6, near_hull_bias_deg=10.0, near_hull_distance_m=reach)
    yaw = np.zeros(n)
    bias = est.estimate(0.0, np.zeros((n, 3)), np.zeros((n, 3)), yaw, np.zeros(n)).yaw_error   # at the hull
    # per-flight std: 2000 samples, rel. std of a std 1/sqrt(2*2000) = 1.6 %, tolerance 7 %
    assert np.std(bias) == pytest.approx(math.radians(10.0), rel=0.07)
    d = np.tile([0.0, 5.0, 10.0, 19.0, 20.0, 35.0, -1.0, 1000.0], n // 8)
    got = est.estimate(DT, np.zeros((n, 3)), np.zeros((n, 3)), yaw, d).yaw_error
    np.testing.assert_allclose(got, bias * np.clip(1 - np.clip(d, 0, None) / reach, 0, 1) ** 3, atol=1e-15)
    assert not got[d >= reach].any()
    assert not est.estimate(2 * DT, np.zeros((n, 3)), np.zeros((n, 3)), yaw, None).yaw_error.any()
    taper = near_hull_taper(np.linspace(0, reach, 50), reach)
    assert taper[0] == 1.0 and taper[-1] == 0.0 and np.all(np.diff(taper) < 0)


@pytest.mark.parametrize("estimator", ["fused", "raw-fix"])
def test_row_of_a_batch_equals_the_flight_alone(estimator):
    seeds = np.random.SeedSequence(11).spawn(3)
    params = navigation_params(NavigationSection(preset="consumer", update_rate_hz=5.0, latency_s=0.1,
                                                 estimator=estimator))
    batch = NavigationEstimator(params, [np.random.default_rng(s) for s in seeds], 3, DT, block_steps=16)
    alone = NavigationEstimator(params, [np.random.default_rng(seeds[1])], 1, DT, block_steps=7)
    rng = np.random.default_rng(12)
    for k in range(40):   # crosses several noise blocks of both (different) block sizes
        pos, vel, yaw, d = rng.normal(size=(3, 3)), rng.normal(size=(3, 3)), rng.normal(size=3), 30 * rng.random(3)
        a = batch.estimate(k * DT, pos, vel, yaw, d)
        b = alone.estimate(k * DT, pos[1:2], vel[1:2], yaw[1:2], d[1:2])
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x[1:2], y)


def test_white_noise_and_constant_heading_bias_statistics():
    # 3000 flights: rel. std of a std estimate 1/sqrt(2 N) = 1.3 % (N = 3000) or 0.9 % (6000): tolerance 6 %.
    n = 3000
    est = make(n, seed=7, white_noise_m=0.3, vertical_white_noise_m=0.6, velocity_noise_m_s=0.1,
               compass_bias_deg=2.0, compass_noise_deg=0.5, update_rate_hz=1 / DT)
    err, verr, yerr = run(est, 2)
    assert np.std(err[1, :, :2]) == pytest.approx(0.3, rel=0.06)
    assert np.std(err[1, :, 2]) == pytest.approx(0.6, rel=0.06)
    assert np.std(verr[1, :, :2]) == pytest.approx(0.1, rel=0.06)
    assert np.std(verr[1, :, 2]) == pytest.approx(0.2, rel=0.06)     # vertical velocity noise: twice
    assert abs(np.corrcoef(err[0, :, 0], err[1, :, 0])[0, 1]) < 0.08   # white: independent fixes (4.4 sigma)
    assert np.std(yerr[0]) == pytest.approx(math.radians(math.hypot(2.0, 0.5)), rel=0.06)
    # the bias is constant per flight: it cancels in a difference of two fixes, the noise does not
    assert np.std(yerr[1] - yerr[0]) == pytest.approx(math.radians(0.5) * math.sqrt(2), rel=0.06)


def test_fusion_gain_solves_its_riccati_equation():
    # P = F (P - P (P + R)^-1 P) F^T + Q and K = P (P + R)^-1 (H = I), for the consumer's horizontal filter
    interval, rp, rv = 0.1, 0.613, 0.3
    k, p = fusion_gain(FILTER_ACCEL_PSD, interval, rp, rv)
    f, q = inertial_error_step(FILTER_ACCEL_PSD, interval)
    r = np.diag([rp**2, rv**2])
    np.testing.assert_allclose(f @ (p - p @ np.linalg.solve(p + r, p)) @ f.T + q, p, rtol=1e-9)
    np.testing.assert_allclose(k, p @ np.linalg.inv(p + r), rtol=1e-12)
    assert np.all(np.abs(np.linalg.eigvals(f @ (np.eye(2) - k))) < 1)      # the error dynamics are stable
    assert 0 < k[0, 0] < 0.2 and 0 < k[1, 1] < 0.2                        # a fix moves the estimate a little
    # the estimator's gains are those of its preset's fix interval and EKF2's observation noise floors
    params = navigation_params(NavigationSection(preset="consumer"))
    est = NavigationEstimator(params, 0, 1, DT)
    h, v, vh, vv, _ = params.filter_noise
    assert (h, v, vh, vv) == pytest.approx((math.hypot(params.horizontal_sigma_m, params.white_noise_m), 0.75,
                                            0.3, 0.45))
    np.testing.assert_allclose(est.gains[0], fusion_gain(FILTER_ACCEL_PSD, 0.1, h, vh)[0], rtol=1e-12)
    np.testing.assert_allclose(est.gains[1], fusion_gain(FILTER_ACCEL_PSD, 0.1, v, vv)[0], rtol=1e-12)


def test_fused_error_covariance_is_the_filters_own_when_the_noises_match_its_model():
    # White fix errors equal to the filter's observation noise (0.5 m, 0.3 m/s), no GM, an IMU error equal to
    # its process noise: the simulated error after a fix has the Kalman posterior covariance (I - K) P.
    # 3000 flights x 2 axes: rel. std of a variance sqrt(2/6000) = 1.8 %, tolerance 8 %.
    n = 3000
    est = make(n, seed=21, estimator="fused", white_noise_m=0.5, velocity_noise_m_s=0.3, update_rate_hz=10.0,
               accel_noise_density=math.sqrt(FILTER_ACCEL_PSD))
    k, p = fusion_gain(FILTER_ACCEL_PSD, 0.1, 0.5, 0.3)
    post = (np.eye(2) - k) @ p
    err, verr, _ = run(est, 401)                  # 20 s: the filter's slowest mode has decayed (e^-8)
    pe, ve = err[400, :, :2].ravel(), verr[400, :, :2].ravel()     # step 400 brings a fix
    assert np.var(pe) == pytest.approx(post[0, 0], rel=0.08)
    assert np.var(ve) == pytest.approx(post[1, 1], rel=0.08)
    assert np.mean(pe * ve) == pytest.approx(post[0, 1], abs=0.1 * math.sqrt(post[0, 0] * post[1, 1]))
    assert math.sqrt(post[1, 1]) < 0.3 / 4                         # far below the 0.3 m/s per-fix noise


def test_fused_estimate_is_smooth_where_raw_fixes_step_and_keeps_the_gm_offset():
    # The consumer preset, 1000 flights, 40 s. Raw fixes: every fix steps the velocity error by ~sqrt(2) x
    # 0.05 m/s; fused: the IMU carries it between fixes, the fixes nudge it: chunk-to-chunk changes < 1/4.
    n, steps = 1000, 801
    raw = run(NavigationEstimator(navigation_params(NavigationSection(preset="consumer", estimator="raw-fix")),
                                  31, n, DT), steps)
    fused = run(NavigationEstimator(navigation_params(NavigationSection(preset="consumer")), 31, n, DT), steps)
    late = slice(steps // 2, None)
    jump_raw = np.std(np.diff(raw[1][late, :, :2], axis=0))
    jump_fused = np.std(np.diff(fused[1][late, :, :2], axis=0))
    assert jump_fused < 0.25 * jump_raw
    assert np.std(np.diff(fused[0][late, :, :2], axis=0)) < 0.25 * np.std(np.diff(raw[0][late, :, :2], axis=0))
    # the slow GM offset passes the filter: the position error's 95 % radius is still the spec (1.5 m; 1000
    # flights: the p95 of a Rayleigh radius has rel. std ~2.3 %, tolerance 10 %), and it is the raw one's
    radius = np.hypot(fused[0][-1, :, 0], fused[0][-1, :, 1])
    assert np.quantile(radius, 0.95) == pytest.approx(1.5, rel=0.10)
    assert np.corrcoef(fused[0][-1, :, 0], raw[0][-1, :, 0])[0, 1] > 0.99


def test_same_seed_same_numbers_other_seed_other_numbers():
    params = navigation_params(NavigationSection(preset="consumer"))
    a, b, c = (run(NavigationEstimator(params, s, 3, DT, block_steps=b), 30) for s, b in ((5, 8), (5, 64), (6, 8)))
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(a[0], c[0])


def test_baro_drift_alone_is_linear_in_time():
    est = make(500, seed=8, baro_drift_m_per_min=0.6)
    err = run(est, 41)[0][:, :, 2]
    np.testing.assert_allclose(err[40], 2 * err[20], rtol=1e-12)
    np.testing.assert_allclose(err[20], 10 * err[2], rtol=1e-12)
    assert np.std(err[20]) == pytest.approx(0.6 / 60 * 1.0, rel=0.1)   # drift after 1 s; 500 samples: 3.2 %


def test_consumer_and_rtk_presets_reproduce_their_hover_specs():
    consumer = navigation_params(NavigationSection(preset="consumer"))
    rtk = navigation_params(NavigationSection(preset="rtk"))
    assert hover_p95_spec_m(consumer) == pytest.approx(1.5, rel=0.01)
    assert hover_p95_spec_m(rtk) == pytest.approx(0.1, rel=0.01)
    assert K95_2D == pytest.approx(2.448, abs=1e-3) and K95_1D == pytest.approx(1.960, abs=1e-3)
    for p, vertical in ((consumer, 0.5), (rtk, 0.1)):
        assert K95_1D * math.hypot(p.vertical_sigma_m, p.vertical_white_noise_m) == pytest.approx(vertical, rel=0.01)
    # Monte Carlo hover: 4000 flights; the p95 of a Rayleigh radius from 4000 samples has rel. std ~1.2 %.
    est = NavigationEstimator(consumer, 13, 4000, DT, block_steps=8)
    out = est.estimate(0.0, np.zeros((4000, 3)), np.zeros((4000, 3)), np.zeros(4000))
    radius = np.hypot(out.position_error[:, 0], out.position_error[:, 1])
    assert np.quantile(radius, 0.95) == pytest.approx(1.5, rel=0.05)
    assert np.quantile(np.abs(out.position_error[:, 2]), 0.95) == pytest.approx(0.5, rel=0.06)


def test_px4_preset_matches_the_plugins_own_bias_recursion():
    # The plugin as written, every 4 ms physics step: bias += rw sqrt(dt) n dt - bias / 60 (a batched AR(1)
    # filter over 2000 chains x 2000 steps = 8 s = 34 tau; the first 500 steps, 8 tau, are the transient).
    p = navigation_params(NavigationSection(preset="px4-sitl"))
    dt, a = 0.004, 1 - 1 / 60
    bias = lfilter([2.0 * dt**1.5], [1.0, -a], np.random.default_rng(14).standard_normal((2000, 2000)), axis=1)
    # variance of 4000 samples: rel. std 2.2 %, tolerance 10 %
    assert np.var(bias[:, [1500, 1999]]) == pytest.approx(p.horizontal_sigma_m**2, rel=0.10)
    lag = 50                                     # one 5 Hz fix interval
    r = np.corrcoef(bias[:, 1000:1950:50].ravel(), bias[:, 1000 + lag:1950 + lag:50].ravel())[0, 1]
    assert r == pytest.approx(math.exp(-lag * dt / p.correlation_time_s), abs=0.03)   # 38000 pairs
    assert (p.update_rate_hz, p.latency_s) == (5.0, 0.12)
    sigma, tau = px4_plugin_gm(2.0, dt, 60.0)
    assert sigma == pytest.approx(2.0 * dt**1.5 * 60 / math.sqrt(119)) and tau == pytest.approx(0.238, abs=1e-3)


def test_validation_names_the_key():
    with pytest.raises(ValidationError, match="horizontal_sigma_m"):
        NavigationSection(horizontal_sigma_m=-0.1)
    with pytest.raises(InputError, match="compass_bias_deg"):
        parse_model(NavigationSection, {"compass_bias_deg": -2.0}, "nav.yaml")
    with pytest.raises(InputError, match="preset"):
        parse_model(NavigationSection, {"preset": "gopro"}, "nav.yaml")
    with pytest.raises(InputError, match="unknown key"):
        parse_model(NavigationSection, {"sigma": 1.0}, "nav.yaml")
    with pytest.raises(InputError, match="correlation_time_s"):
        parse_model(NavigationSection, {"correlation_time_s": 0.0}, "nav.yaml")
    assert navigation_params(NavigationSection(white_noise_m=0.2)).white_noise_m == 0.2   # override wins
    assert navigation_params(NavigationSection()).preset == "consumer"
