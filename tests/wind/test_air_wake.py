"""The ship's air wake: PRIME's building-wake geometry around the hull box, and the wind field inside it."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import build_proxy
from wrp_eval.wind.air_wake import ShipAirWake, cavity_length, wake_height, wilson_scale_length
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.field import build_wind_field

# 140 x 20 m, 12 m deep, 15 m superstructure, 6 m draft: the proxy box is 21 m high
SHIP = ShipParticulars(140, 20, 12, 15, 6, lat_deg=23.7, lon_deg=-89.5, heading_deg=45.0)
BOX = build_proxy(SHIP).bounds
H = 21.0


def _wind(deg: float, speed: float = 8.0) -> np.ndarray:
    """A horizontal ship-frame wind blowing TOWARD the azimuth ``deg`` (counter-clockwise from the bow)."""
    a = np.radians(deg)
    return np.array([speed * np.cos(a), speed * np.sin(a), 0.0])


def _frame(wake: ShipAirWake, wind: np.ndarray):
    """(d, n, geometry): the downwind unit vector, its left normal (both (2,)) and the wake geometry."""
    geo = wake.geometry(wind[None, :])
    d = geo.d[0]
    return d, np.array([-d[1], d[0]]), geo


def _points(wake, d, n, s, c, z):
    """Ship-frame points at along-wind s, across-wind c (from the box centre) and height z (broadcast)."""
    s, c, z = np.broadcast_arrays(np.asarray(s, float), np.asarray(c, float), np.asarray(z, float))
    xy = wake.centre + s[..., None] * d + c[..., None] * n
    return np.column_stack([xy.reshape(-1, 2), z.reshape(-1)])


def test_prime_lengths_in_closed_form_for_a_cube_and_the_ship_in_head_and_beam_winds():
    # a cube: R = H, L_R = 1.8 H / 1.24 (Fackrell, L/H = W/H = 1), 1.45 H: "1-2 block heights"
    assert wilson_scale_length(10.0, 10.0) == pytest.approx(10.0)
    assert cavity_length(10.0, 10.0, 10.0) == pytest.approx(1.8 * 10.0 / 1.24)
    assert wake_height(0.0, H, 20.0) == pytest.approx(H)            # the wake starts at the block's top
    wake = ShipAirWake(BOX)
    geo = wake.geometry(np.array([_wind(180.0), _wind(270.0)]))
    # head wind: the wind sees W = B = 20 m and L = 140 m (L/H clipped at 3, W/H < 1 weakens the L/H exponent)
    rw = 20.0 / H
    e = 0.3 * (rw - 0.33) / 0.67
    assert geo.scale[0] == pytest.approx(20.0 ** (2 / 3) * H ** (1 / 3))
    assert geo.cavity[0] == pytest.approx(1.8 * 20.0 / (3.0**e * (1 + 0.24 * rw)))
    # beam wind: W = 140 m, L = 20 m
    assert geo.scale[1] == pytest.approx(H ** (2 / 3) * 140.0 ** (1 / 3))
    assert geo.cavity[1] == pytest.approx(1.8 * 140.0 / ((20.0 / H) ** 0.3 * (1 + 0.24 * 140.0 / H)))
    assert geo.cavity[1] > 4 * geo.cavity[0]                           # a beam wind's cavity is far longer


@pytest.mark.parametrize("toward_deg", [180.0, 270.0, 225.0, 10.0, 123.0])
@pytest.mark.parametrize("deficit, ratio", [(0.7, 1.7), (1.1, 2.5)])
def test_deficit_and_turbulence_gain_at_the_lee_reference_point_are_the_models(toward_deg, deficit, ratio):
    wake = ShipAirWake(BOX, lee_deficit=deficit, turbulence_ratio=ratio)
    wind = _wind(toward_deg)
    p = wake.reference_point(wind)
    got_deficit, got_gain = wake.factors(p[None, :], wind)
    assert got_deficit[0] == pytest.approx(deficit, abs=1e-12)
    assert got_gain[0] == pytest.approx(ratio, abs=1e-12)
    outside_box = np.any(np.abs(p[:2]) > BOX[1, :2])
    assert outside_box and p[2] == pytest.approx(H / 2)


@pytest.mark.parametrize("toward_deg", [180.0, 270.0, 225.0, 10.0])
def test_no_effect_upwind_beside_far_downstream_or_above_the_wake(toward_deg):
    wake = ShipAirWake(BOX)
    wind = _wind(toward_deg)
    d, n, geo = _frame(wake, wind)
    hs, hc, r, cav = geo.half_along[0], geo.half_across[0], geo.scale[0], geo.cavity[0]
    c = np.linspace(-hc - 60.0, hc + 60.0, 41)[:, None]
    z = np.array([1.0, 10.0, 30.0, 60.0])[None, :]
    s = np.linspace(-hs, hs + 4 * r, 30)
    side = hc + r / 3 * np.cbrt((s + hs) / r) + 0.01                    # just beyond PRIME's wake half-width
    far = hs + cav + wake.extent_scale_lengths * r + 1.0                 # past the lee corner + cavity + extent
    cases = {
        "upwind": _points(wake, d, n, -hs - 0.5, c, z),
        "beside": np.vstack([_points(wake, d, n, s, sign * side, 10.0) for sign in (-1, 1)]),
        "far downstream": _points(wake, d, n, far, c, z),
        "above": _points(wake, d, n, np.linspace(-hs, far, 20), 0.0, 2000.0),
    }
    for name, pts in cases.items():
        deficit, gain = wake.factors(pts, wind)
        assert np.all(deficit == 0.0) and np.all(gain == 1.0), name
    inside = _points(wake, d, n, hs + cav / 2, 0.0, H / 2)             # and the wake is really there
    assert wake.deficit(inside, wind)[0] > 0.5 * wake.lee_deficit


def test_past_the_cavity_the_deficit_and_turbulence_decay_as_prime_says():
    """(x' - L_R + R)/R)^(-2/3) behind the cavity (Weil 1996 / PRIME), the plateau inside it."""
    wake = ShipAirWake(BOX, lee_deficit=0.8, turbulence_ratio=2.0)
    wind = _wind(180.0)                                                  # head wind: lee face = stern, s = 70
    d, n, geo = _frame(wake, wind)
    r, cav = geo.scale[0], geo.cavity[0]
    x_past = np.array([0.1, 0.5 * cav, 0.99 * cav, cav + r, cav + 3 * r])
    deficit, gain = wake.factors(_points(wake, d, n, 70.0 + x_past, 0.0, H / 3), wind)
    shape = np.array([1.0, 1.0, 1.0, 2.0 ** (-2 / 3), 4.0 ** (-2 / 3)])
    np.testing.assert_allclose(deficit, 0.8 * shape, rtol=1e-12)
    np.testing.assert_allclose(gain, 1.0 + 1.0 * shape, rtol=1e-12)


def test_the_wake_turns_with_the_wind():
    """A square hull: the wind and the points turned by 90 deg give the same field (the wake moved to the new
    lee side); the ship: a head wind shelters the stern, a wind toward starboard the starboard side."""
    square = ShipAirWake(np.array([[-20.0, -20.0, 0.0], [20.0, 20.0, 15.0]]))
    rng = np.random.default_rng(2)
    pts = np.column_stack([rng.uniform(-150, 150, (500, 2)), rng.uniform(0.5, 40, 500)])
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    wind = _wind(200.0)
    for a, b in zip(square.factors(pts, wind), square.factors(pts @ turn.T, turn @ wind), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)
    assert np.count_nonzero(square.deficit(pts, wind)) > 20
    ship = ShipAirWake(BOX)
    stern, starboard = np.array([-85.0, 0.0, 10.0]), np.array([0.0, -25.0, 10.0])
    pts = np.array([stern, starboard])
    head = ship.deficit(pts, _wind(180.0))                               # blowing from the bow to the stern
    beam = ship.deficit(pts, _wind(270.0))                               # blowing from port to starboard
    assert head[0] == pytest.approx(0.7) and head[1] == 0.0
    assert beam[1] == pytest.approx(0.7) and beam[0] == 0.0


@pytest.mark.parametrize("toward_deg", [180.0, 225.0, 263.0])
def test_the_fields_have_no_steps(toward_deg):
    """Sweeps at 1 cm through every edge (windward face, roof, lee face, cavity end, taper, sides, top): no
    neighbour differs by more than the steepest smooth ramp allows (a step would jump by ~0.1-0.7)."""
    wake = ShipAirWake(BOX)
    wind = _wind(toward_deg)
    d, n, geo = _frame(wake, wind)
    hs, hc, r = geo.half_along[0], geo.half_across[0], geo.scale[0]
    step = 0.01
    s = np.arange(-hs - 5, hs + geo.cavity[0] + 16 * r, step)
    c = np.arange(-hc - 3 * r, hc + 3 * r, step)
    z = np.arange(0.0, 120.0, step)
    sweeps = [_points(wake, d, n, s, 0.0, H + 2.0), _points(wake, d, n, s, hc - 1.0, H / 2),
              _points(wake, d, n, s, hc + 3.0, H / 2),
              _points(wake, d, n, hs + 0.3 * geo.cavity[0], c, H / 2), _points(wake, d, n, -hs + 2.0, c, H + 1.0),
              _points(wake, d, n, hs + geo.cavity[0], 0.0, z), _points(wake, d, n, 0.0, 0.0, z)]
    for pts in sweeps:
        for field in wake.factors(pts, wind):
            assert np.max(np.abs(np.diff(field))) < 5e-3


@pytest.mark.parametrize("data, key", [
    ({"lee_deficit": -0.1}, "lee_deficit"),
    ({"lee_deficit": 2.0}, "lee_deficit"),
    ({"turbulence_ratio": 0.5}, "turbulence_ratio"),
    ({"extent_scale_lengths": 0}, "extent_scale_lengths"),
    ({"recirculation": 2}, "unknown key"),
])
def test_bad_air_wake_sections_are_refused(data, key):
    with pytest.raises(InputError, match=key):
        parse_model(WindSection, {"air_wake": data}, "cfg.yaml")


def test_bad_boxes_are_refused():
    with pytest.raises(ValueError, match="box"):
        ShipAirWake(np.array([[0.0, 0.0, 0.0], [-1.0, 2.0, 3.0]]))
    with pytest.raises(ValueError, match="box"):
        ShipAirWake(np.zeros(3))


def _same_seed_pair(section, seed=7, ship=SHIP):
    """Two flights of one section whose turbulence draws the same numbers (common random numbers)."""
    rngs = [np.random.default_rng(seed), np.random.default_rng(seed)]
    return build_wind_field([section, section], ship, rngs, 0.05)


def test_lee_side_turbulence_is_the_configured_ratio_of_the_free_stream_and_the_mean_the_deficit():
    """Flight 0 hovers at the lee reference point, flight 1 upwind at the same height; both draw the same Dryden
    noise, so std over time of the wind at the lee point / at the free-stream point = turbulence_ratio with no
    sampling error (tolerance 1e-9: only the last bits of the interpolated mean, which sets the Dryden speed,
    differ between the two points), and the lee mean = (1 - lee_deficit) x the free-stream mean."""
    section = parse_model(WindSection, {"turbulence": {"severity": "moderate"},
                                        "air_wake": {"lee_deficit": 0.6, "turbulence_ratio": 2.2}}, "t")
    field = _same_seed_pair(section)
    probe = field.mean.velocity(np.array([[0.0, 0.0, H / 2]]), 0.0)[0]
    lee = field.wake.reference_point(probe)
    d = probe[:2] / np.hypot(*probe[:2])
    # upwind by whole grid cells (10 m), so that both points sit alike in their cells and interpolate alike
    free = lee - np.array([*(10.0 * np.round(22.0 * d)), 0.0])
    pts = np.array([lee, free])
    mean = field.mean.velocity(pts, 0.0)
    np.testing.assert_allclose(mean[0], mean[1], rtol=1e-12)              # a horizontally uniform mean
    assert field.wake.deficit(free[None, :], mean[1])[0] == 0.0           # and free-stream air
    series = np.stack([field.velocity(pts, 0.05 * k) for k in range(3000)])  # (steps, 2, 3)
    std = series.std(axis=0)
    assert np.all(std[1] > 0.3)                                           # moderate turbulence is there
    np.testing.assert_allclose(std[0] / std[1], 2.2, rtol=1e-9)
    turb_free = series[:, 1] - mean[1]
    np.testing.assert_allclose(series[:, 0], 0.4 * mean[0] + 2.2 * turb_free, atol=1e-9)


def test_gusts_are_sheltered_like_the_mean_wind():
    gusty = {"turbulence": {"severity": "none"}, "gusts": {"enabled": True, "rate_per_min": 20.0}}
    wake = parse_model(WindSection, gusty, "t")
    open_air = parse_model(WindSection, {**gusty, "air_wake": {"enabled": False}}, "t")
    sheltered, free = (build_wind_field([s], SHIP, [np.random.default_rng(3)], 0.5) for s in (wake, open_air))
    probe = free.mean.velocity(np.array([[0.0, 0.0, H / 2]]), 0.0)[0]
    pts = sheltered.wake.reference_point(probe)[None, :]
    out = np.stack([np.concatenate([sheltered.velocity(pts, 0.5 * k), free.velocity(pts, 0.5 * k)]) for k in
                    range(200)])
    np.testing.assert_allclose(out[:, 0], 0.3 * out[:, 1], rtol=1e-12)
    assert np.ptp(out[:, 1, 0]) > 1.0                                     # gusts did blow


def test_each_flight_in_the_wake_flies_the_wind_it_would_fly_alone():
    sections = [parse_model(WindSection, d, "t") for d in (
        {"direction_deg": 270.0, "turbulence": {"severity": "light"}, "gusts": {"enabled": True}},
        {"direction_deg": 0.0, "speed_10m_m_s": 9.0, "gusts": {"enabled": True}},
        {"direction_deg": 135.0, "turbulence": {"severity": "severe"}, "gusts": {"enabled": True}},
    )]
    batch = build_wind_field(sections, SHIP, np.random.default_rng(5).spawn(3), 0.05)
    alone = [build_wind_field([s], SHIP, [g], 0.05)
             for s, g in zip(sections, np.random.default_rng(5).spawn(3), strict=True)]
    rng = np.random.default_rng(1)
    sheltered = 0
    for k in range(60):
        points = np.column_stack([rng.uniform(-120, 120, (3, 2)), rng.uniform(3, 40, 3)])
        want = np.concatenate([w.velocity(points[i:i + 1], 0.05 * k) for i, w in enumerate(alone)])
        np.testing.assert_array_equal(batch.velocity(points, 0.05 * k), want)
        sheltered += np.count_nonzero(batch.wake.deficit(points, batch.mean.velocity(points, 0.05 * k)))
    assert sheltered > 10                                                  # the wake was really in play
    with pytest.raises(ValueError, match="air_wake"):
        build_wind_field([WindSection(), WindSection(air_wake={"lee_deficit": 0.5})], SHIP, 0)


def test_disabled_or_hull_less_fields_are_todays_wind_bit_for_bit():
    """Wake disabled: mean + turbulence + gusts exactly as before the wake existed; a pose without a hull
    skips the wake even when it is enabled."""
    knobs = {"turbulence": {"severity": "moderate"}, "gusts": {"enabled": True, "rate_per_min": 10.0}}
    off = parse_model(WindSection, {**knobs, "air_wake": {"enabled": False}}, "t")
    on = parse_model(WindSection, knobs, "t")
    field = build_wind_field([off] * 2, SHIP, 11, 0.05)
    twin = build_wind_field([on] * 2, (23.7, -89.5, 45.0), 11, 0.05)
    assert field.wake is None and twin.wake is None
    assert build_wind_field([on] * 2, SHIP, 11, 0.05).wake is not None
    pts = np.array([[-80.0, 0.0, 10.0], [0.0, -25.0, 15.0]])
    for k in range(50):
        t = 0.05 * k
        mean = twin.mean.velocity(pts, t)
        today = mean + twin.turbulence.velocity(pts, t, mean_wind=mean)
        today = today + twin.gusts.velocity(pts, t)
        np.testing.assert_array_equal(field.velocity(pts, t), today)
