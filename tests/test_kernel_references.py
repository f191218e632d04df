"""The compiled kernels against the numpy formulas they replaced (issue 19): the numpy code of session 8, kept
here as the reference, on random inputs and on the edge cases (NaN, calm wind, points on nodes, zero-length
segments). The kernels must give the same numbers up to rounding and the same NaNs."""

import numpy as np
import pytest

from wrp_eval.sim.capture_mode import through_profile
from wrp_eval.sim.controller import GAIN_PRESETS, PositionController, quat_to_matrix
from wrp_eval.sim.gimbal import Gimbal, GimbalParams, GimbalSection
from wrp_eval.sim.navigation import NavigationEstimator, navigation_params
from wrp_eval.sim.phases import reference_profile
from wrp_eval.sim.vehicle import GRAVITY_M_S2, PHANTOM4
from wrp_eval.wind.air_wake import (
    CAVITY_TOP_R,
    DECAY_EXPONENT,
    FACKRELL_COEF,
    FACKRELL_LENGTH_EXP,
    FACKRELL_WIDTH_COEF,
    MIN_LATERAL_TAPER_R,
    MIN_RAMP_R,
    WAKE_HEIGHT_COEF,
    ShipAirWake,
)
from wrp_eval.wind.grid import WindGrid, interpolate

RNG = np.random.default_rng(19)
BOX = np.array([[-70.0, -10.0, 0.0], [70.0, 10.0, 25.0]])


def _same(got, want, atol=1e-12):
    got, want = np.asarray(got, float), np.asarray(want, float)
    assert got.shape == want.shape
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=atol)


# -- the mean wind: 8-point IDW and trilinear on per-column levels (session 8's numpy) -------------------------
def _cell_reference(axis, coord):
    coord = np.clip(np.nan_to_num(coord, nan=axis[0]), axis[0], axis[-1])
    idx = np.clip(np.searchsorted(axis, coord, side="right") - 1, 0, axis.size - 2)
    return idx, (coord - axis[idx]) / (axis[idx + 1] - axis[idx])


def _interpolate_reference(grid, points, method, power=2.0):
    c, s = np.cos(grid.grid_yaw_rad), np.sin(grid.grid_yaw_rad)
    gx, gy = c * points[:, 0] + s * points[:, 1], -s * points[:, 0] + c * points[:, 1]
    i, fx = _cell_reference(grid.x_m, gx)
    j, fy = _cell_reference(grid.y_m, gy)
    ci, cj = np.stack([i, i + 1, i, i + 1], axis=1), np.stack([j, j, j + 1, j + 1], axis=1)
    heights = grid.heights_m[ci, cj]
    zc = np.clip(np.nan_to_num(np.broadcast_to(points[:, 2:3], heights.shape[:2]), nan=0.0),
                 heights[..., 0], heights[..., -1])
    k = np.clip((heights <= zc[..., None]).sum(axis=2) - 1, 0, heights.shape[2] - 2)
    h_lo = np.take_along_axis(heights, k[..., None], 2)[..., 0]
    h_hi = np.take_along_axis(heights, k[..., None] + 1, 2)[..., 0]
    fz = (zc - h_lo) / (h_hi - h_lo)
    v_lo, v_hi = grid.velocity_mps[ci, cj, k], grid.velocity_mps[ci, cj, k + 1]
    if method == "trilinear":
        wx = np.stack([1 - fx, fx, 1 - fx, fx], axis=1)
        wy = np.stack([1 - fy, 1 - fy, fy, fy], axis=1)
        return np.einsum("nc,ncd->nd", wx * wy, v_lo + fz[..., None] * (v_hi - v_lo))
    fxc = np.stack([fx, 1 - fx, fx, 1 - fx], axis=1)
    fyc = np.stack([fy, fy, 1 - fy, 1 - fy], axis=1)
    d2 = np.concatenate([fxc**2 + fyc**2 + fz**2, fxc**2 + fyc**2 + (1 - fz) ** 2], axis=1)
    on_node = d2 < 1e-24
    with np.errstate(divide="ignore"):
        w = np.where(on_node, 0.0, d2 ** (-0.5 * power))
    hit = on_node.any(axis=1)
    w[hit] = on_node[hit].astype(float)
    w /= w.sum(axis=1, keepdims=True)
    return np.einsum("nc,ncd->nd", w, np.concatenate([v_lo, v_hi], axis=1))


@pytest.mark.parametrize("method", ["idw", "trilinear"])
@pytest.mark.parametrize("common_levels", [True, False])
def test_wind_interpolation_equals_the_numpy_formulas(method, common_levels):
    x, y = np.array([-300.0, -100.0, 50.0, 400.0]), np.array([-200.0, 0.0, 250.0])
    heights = (np.broadcast_to(np.linspace(0.0, 500.0, 6), (4, 3, 6)).copy() if common_levels
               else np.sort(RNG.uniform(5.0, 400.0, (4, 3, 6)), axis=2))
    grid = WindGrid(x, y, heights, RNG.normal(0.0, 5.0, (4, 3, 6, 3)), grid_yaw_rad=0.0 if common_levels else 0.3)
    points = np.column_stack([RNG.uniform(-350, 450, 300), RNG.uniform(-250, 300, 300), RNG.uniform(-20, 550, 300)])
    points[:3, 2] = np.nan                                                   # NaN height: as z = 0
    nodes = np.column_stack([np.repeat(x, 3), np.tile(y, 4), heights[:, :, 2].ravel()])   # exactly on nodes
    points = np.vstack([points, nodes]) if common_levels else points
    for power in (2.0, 3.0):
        _same(interpolate(grid, points, method, idw_power=power, clamp=True),
              _interpolate_reference(grid, points, method, power), atol=1e-11)


# -- the ship's air wake (session 8's numpy) -------------------------------------------------------------------
def _smooth(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def _factors_reference(wake, points, wind):
    speed = np.hypot(wind[:, 0], wind[:, 1])
    calm = speed < 1e-9
    d = np.where(calm[:, None], [1.0, 0.0], wind[:, :2] / np.where(calm, 1.0, speed)[:, None])
    ax, ay = np.abs(d[:, 0]), np.abs(d[:, 1])
    half_along = wake.half_length * ax + wake.half_breadth * ay
    half_across = wake.half_length * ay + wake.half_breadth * ax
    height, width, length = wake.height, 2.0 * half_across, 2.0 * half_along
    h, w = np.minimum(height, 8.0 * width), np.minimum(width, 8.0 * height)
    r = np.minimum(h, w) ** (2.0 / 3.0) * np.maximum(h, w) ** (1.0 / 3.0)
    rw, rl = width / height, np.clip(length / height, 0.3, 3.0)
    exponent = np.where(rw < 1.0, np.maximum(0.0, FACKRELL_LENGTH_EXP * (rw - 0.33) / 0.67), FACKRELL_LENGTH_EXP)
    cavity = FACKRELL_COEF * width / (rl**exponent * (1.0 + FACKRELL_WIDTH_COEF * rw))
    cavity_top = height + CAVITY_TOP_R * r
    rel = points[:, :2] - wake.centre
    s = rel[:, 0] * d[:, 0] + rel[:, 1] * d[:, 1]
    c = -rel[:, 0] * d[:, 1] + rel[:, 1] * d[:, 0]
    cc = np.clip(c, -half_across, half_across)
    with np.errstate(divide="ignore", invalid="ignore"):
        mid_x = np.where(ax > 1e-12, cc * d[:, 1] / d[:, 0], 0.0)
        half_x = np.where(ax > 1e-12, wake.half_length / ax, np.inf)
        mid_y = np.where(ay > 1e-12, -cc * d[:, 0] / d[:, 1], 0.0)
        half_y = np.where(ay > 1e-12, wake.half_breadth / ay, np.inf)
    lee, windward = np.minimum(mid_x + half_x, mid_y + half_y), np.maximum(mid_x - half_x, mid_y - half_y)
    fetch = np.maximum(lee - windward, MIN_RAMP_R * r)
    x_lee, x_wind, x_up, lateral = s - lee, s - windward, s + half_along, np.abs(c) - half_across
    decay = (np.maximum(x_lee - cavity, 0.0) / r + 1.0) ** -DECAY_EXPONENT
    start = cavity + 0.5 * wake.extent_scale_lengths * r
    taper = 1.0 - _smooth((x_lee - start) / (0.5 * wake.extent_scale_lengths * r))
    spread = np.maximum(r / 3.0 * np.cbrt(np.maximum(x_up, 0.0) / r), MIN_LATERAL_TAPER_R * r)
    shape = np.where(calm, 0.0, _smooth(x_wind / fetch) * decay * taper * (1.0 - _smooth(lateral / spread)))
    top = np.maximum(WAKE_HEIGHT_COEF * r * np.cbrt(np.maximum(x_up, 0.0) / r + (height / (WAKE_HEIGHT_COEF * r)) ** 3),
                     cavity_top + CAVITY_TOP_R * r)
    z = points[:, 2]
    return (wake.lee_deficit * shape * (1.0 - _smooth((z - height) / (top - height))),
            1.0 + (wake.turbulence_ratio - 1.0) * shape * (1.0 - _smooth((z - cavity_top) / (top - cavity_top))))


def test_air_wake_factors_equal_the_numpy_formulas():
    wake = ShipAirWake(BOX, lee_deficit=0.8, turbulence_ratio=2.0)
    n = 400
    points = np.column_stack([RNG.uniform(-400, 400, n), RNG.uniform(-250, 250, n), RNG.uniform(0, 90, n)])
    wind = RNG.normal(0.0, 6.0, (n, 3))
    wind[:4] = 0.0                                       # calm
    wind[4:8, 1] = 0.0                                   # along the ship: no limit across
    wind[8:12, 0] = 0.0                                  # beam on
    for got, want in zip(wake.factors(points, wind), _factors_reference(wake, points, wind), strict=True):
        _same(got, want)


# -- the position loop (session 8's numpy, Lee et al. 2010 with the integral and the tilt limit) ---------------
def _position_loop_reference(params, gains, integral, pos, vel, body_z, ref_pos, ref_vel, ref_acc, yaw, dt, integrate):
    e_p = pos - ref_pos
    integral = integral + np.where(integrate[:, None], e_p * dt, 0.0)
    norm = np.sqrt((integral ** 2).sum(axis=1, keepdims=True))
    integral = integral * np.minimum(1.0, gains.integral_limit_m_s2 / gains.ki / np.maximum(norm, 1e-12))
    acc = -gains.kp * e_p - gains.kv * (vel - ref_vel) - gains.ki * integral + ref_acc
    acc[:, 2] = np.maximum(acc[:, 2] + GRAVITY_M_S2, 0.2 * GRAVITY_M_S2)
    horiz = np.hypot(acc[:, 0], acc[:, 1])
    acc[:, :2] *= np.minimum(1.0, acc[:, 2] * np.tan(params.max_tilt_rad) / np.maximum(horiz, 1e-12))[:, None]
    b3 = acc / np.sqrt((acc ** 2).sum(axis=1))[:, None]
    thrust = np.clip(params.mass_kg * (acc * body_z).sum(axis=1), 0.0, 4.0 * params.max_thrust_per_motor_n)
    cy, sy = np.cos(yaw), np.sin(yaw)
    phi = -np.arcsin(np.clip(-sy * b3[:, 0] + cy * b3[:, 1], -1.0, 1.0))
    theta = np.arctan2(cy * b3[:, 0] + sy * b3[:, 1], b3[:, 2])
    cz, sz, ct, st, cp, sp = (np.cos(0.5 * yaw), np.sin(0.5 * yaw), np.cos(0.5 * theta), np.sin(0.5 * theta),
                              np.cos(0.5 * phi), np.sin(0.5 * phi))
    quat = np.stack([cz * ct * cp + sz * st * sp, cz * ct * sp - sz * st * cp, cz * st * cp + sz * ct * sp,
                     sz * ct * cp - cz * st * sp], axis=1)
    return thrust, quat, integral


def test_position_loop_equals_the_numpy_formulas():
    n = 200
    controller = PositionController(PHANTOM4, GAIN_PRESETS["default"], n)
    integral = np.zeros((n, 3))
    quat = RNG.normal(size=(n, 4))
    body_z = np.ascontiguousarray(quat_to_matrix(quat / np.linalg.norm(quat, axis=1, keepdims=True))[:, :, 2])
    for _ in range(5):        # the integral carries over: saturating, frozen where integrate is False
        args = (RNG.normal(0, 3, (n, 3)), RNG.normal(0, 3, (n, 3)), body_z, RNG.normal(0, 3, (n, 3)),
                RNG.normal(0, 2, (n, 3)), RNG.normal(0, 25, (n, 3)), RNG.uniform(-7, 7, n))
        integrate = RNG.random(n) < 0.7
        thrust, quat_d = controller(*args, 0.05, integrate)
        want_thrust, want_quat, integral = _position_loop_reference(PHANTOM4, controller.gains, integral, *args,
                                                                    0.05, integrate)
        _same(thrust, want_thrust)
        _same(quat_d, want_quat)
        _same(controller.integral, integral)


# -- the reference's speed profiles (session 8's numpy) --------------------------------------------------------
def _through_reference(length, tau, v0, v1, v_max, accel):
    v_peak = np.minimum(v_max, np.sqrt(np.maximum(accel * length + 0.5 * (v0 ** 2 + v1 ** 2), 0.0)))
    v_peak = np.maximum(v_peak, np.maximum(v0, v1))
    t_acc, t_dec = (v_peak - v0) / accel, (v_peak - v1) / accel
    s_acc, s_dec = 0.5 * (v_peak + v0) * t_acc, 0.5 * (v_peak + v1) * t_dec
    with np.errstate(divide="ignore", invalid="ignore"):
        t_cruise = np.where(v_peak > 1e-9, np.maximum(length - s_acc - s_dec, 0.0) / v_peak, 0.0)
    duration = t_acc + t_cruise + t_dec
    moving = tau < duration
    tau = np.clip(tau, 0.0, duration)
    in_acc, in_cruise = tau < t_acc, tau < t_acc + t_cruise
    t_d = tau - t_acc - t_cruise
    s = np.where(in_acc, v0 * tau + 0.5 * accel * tau ** 2,
                 np.where(in_cruise, s_acc + v_peak * (tau - t_acc),
                          s_acc + v_peak * t_cruise + v_peak * t_d - 0.5 * accel * t_d ** 2))
    v = np.where(in_acc, v0 + accel * tau, np.where(in_cruise, v_peak, v_peak - accel * t_d))
    a = np.where(moving, np.where(in_acc & (t_acc > 0), accel, np.where(in_cruise, 0.0,
                                                                      np.where(t_dec > 0, -accel, 0.0))), 0.0)
    return np.minimum(s, length), v, a, duration


def test_speed_profiles_equal_the_numpy_formulas():
    n = 500
    length = np.concatenate([RNG.uniform(0, 40, n), [0.0, 1e-9, np.nan, 5.0]])
    tau = np.concatenate([RNG.uniform(-2, 30, n), [0.0, 1.0, 1.0, np.nan]])
    v0, v1 = RNG.uniform(0, 5, n + 4), RNG.uniform(0, 5, n + 4)
    v_max = np.maximum(np.maximum(v0, v1), RNG.uniform(0, 6, n + 4))
    for got, want in zip(through_profile(length, tau, v0, v1, v_max, 2.5),
                         _through_reference(length, tau, v0, v1, v_max, 2.5), strict=True):
        _same(got, want)
    for t_jerk in (0.0, 0.625):
        for got, want in zip(reference_profile(length, tau, 5.0, 2.5, t_jerk),
                             _rest_to_rest_reference(length, tau, 5.0, 2.5, t_jerk), strict=True):
            _same(got, want, atol=1e-11)


def _trapezoid_reference(length, tau, v_max, a_max):
    tri = length < v_max ** 2 / a_max
    v_peak = np.where(tri, np.sqrt(np.maximum(length, 0.0) * a_max), v_max)
    t_acc = v_peak / a_max
    t_cruise = np.where(tri, 0.0, length / v_max - t_acc)
    duration = 2.0 * t_acc + t_cruise
    s_acc, big_s_acc = 0.5 * a_max * t_acc ** 2, a_max * t_acc ** 3 / 6.0
    big_s_end = big_s_acc + s_acc * t_cruise + 0.5 * v_peak * t_cruise ** 2 + (length * t_acc - big_s_acc)
    after = np.maximum(tau - duration, 0.0)
    moving = (tau >= 0.0) & (tau < duration)
    tau = np.clip(tau, 0.0, duration)
    t_c, t_dec = tau - t_acc, duration - tau
    in_acc, in_dec = tau < t_acc, t_dec < t_acc
    s = np.where(in_acc, 0.5 * a_max * tau ** 2,
                 np.where(in_dec, length - 0.5 * a_max * t_dec ** 2, s_acc + v_peak * t_c))
    v = np.where(in_acc, a_max * tau, np.where(in_dec, a_max * t_dec, v_peak))
    a = np.where(moving, np.where(in_acc, a_max, np.where(in_dec, -a_max, 0.0)), 0.0)
    big_s = np.where(in_acc, a_max * tau ** 3 / 6.0,
                     np.where(in_dec, big_s_end - (length * t_dec - a_max * t_dec ** 3 / 6.0),
                              big_s_acc + s_acc * t_c + 0.5 * v_peak * t_c ** 2))
    return s, v, a, big_s + length * after, duration


def _rest_to_rest_reference(length, tau, v_max, a_max, t_jerk):
    s1, v1, a1, big1, duration = _trapezoid_reference(length, tau, v_max, a_max)
    if t_jerk <= 0.0:
        return s1, v1, a1, duration
    s0, v0, _, big0, _ = _trapezoid_reference(length, tau - t_jerk, v_max, a_max)
    return (big1 - big0) / t_jerk, (s1 - s0) / t_jerk, (v1 - v0) / t_jerk, duration + t_jerk


# -- a kernel never indexes past a wrong-sized batch ------------------------------------------------------------
def test_a_batch_of_the_wrong_size_is_refused_not_read_past_its_end():
    controller = PositionController(PHANTOM4, GAIN_PRESETS["default"], 2)
    five = np.zeros((5, 3))
    with pytest.raises(ValueError, match=r"pos must have shape \(2, 3\), got \(5, 3\)"):
        controller(five, five, five, five, five, five, np.zeros(5), 0.05)
    gimbal = Gimbal(GimbalParams.of(GimbalSection()), np.tile(np.eye(3), (2, 1, 1)), np.zeros(2), 0.05)
    with pytest.raises(ValueError, match="rot must have shape"):
        gimbal.step(np.tile(np.eye(3), (5, 1, 1)), np.zeros(5), np.zeros(5))
    nav = NavigationEstimator(navigation_params(), 0, 2, 0.05)
    with pytest.raises(ValueError, match="position must have shape"):
        nav.estimate(0.0, five, five, np.zeros(5))
    grid = WindGrid(np.array([0.0, 1.0]), np.array([0.0, 1.0]), np.broadcast_to([0.0, 1.0], (2, 2, 2)).copy(),
                    np.zeros((2, 2, 2, 3)))
    with pytest.raises(ValueError, match="value_index must index"):
        interpolate(grid, np.full((3, 3), 0.5), values=grid.velocity_mps[None], value_index=np.array([3, 0, 0]))
