"""What the aircraft carries, in flight: fly-through photos on the navigation estimate, their recorded position
priors, the battery and wind returns, and a flight's independence of its batch (short MuJoCo flights)."""

import contextlib

import numpy as np
import pytest

from wrp_eval.camera import Camera
from wrp_eval.planning.path import FlightPath
from wrp_eval.ship.motion import ShipMotionSection
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.flight import FlightSimulator
from wrp_eval.sim.flight_state import (
    COMPLETED,
    RETURNED_BATTERY,
    RETURNED_WIND_AVERAGE,
    FlightTargets,
)
from wrp_eval.sim.navigation import (
    NavigationEstimator,
    NavigationSection,
    navigation_params,
)
from wrp_eval.sim.onboard import Onboard, ShipInScene, view_depths
from wrp_eval.sim.power import JOULES_PER_WH, level_flight_power_w
from wrp_eval.sim.simple_wind import ConstantWind
from wrp_eval.sim.vehicle import PHANTOM4
from wrp_eval.streams import flight_generators

from .conftest import make_path

CALM = ConstantWind([0.0, 0.0, 0.0])
# make_path's views are at y = 0 / 2 m, 20-22 m up, looking towards +y (yaw 90 / 120 deg), 20 deg down: a hull
# from y = 20 m faces them
BOX = np.array([[-60.0, 20.0, 0.0], [90.0, 40.0, 25.0]])


@contextlib.contextmanager
def _simulator(**update):
    """A small simulator (4 drones a model, one thread) with ``update`` applied to the default section."""
    with FlightSimulator(SimSection(drones_per_model=4, threads=1, **update)) as sim:
        yield sim


def _nav_errors(preset: str, seed, batch: int, dt: float, n_steps: int) -> np.ndarray:
    """(n_steps, batch, 3) m: the navigation's position error at t = k dt of flights seeded like
    FlightSimulator.fly(flight_rngs=seed): each flight's first spawned stream drives its navigation."""
    gens = [g.spawn(2)[0] for g in flight_generators(seed, batch)]
    nav = NavigationEstimator(navigation_params(NavigationSection(preset=preset)), gens, batch, dt)
    zeros = np.zeros((batch, 3))
    return np.stack([nav.estimate(k * dt, zeros, zeros, np.zeros(batch)).position_error for k in range(n_steps)])


# -- without MuJoCo -------------------------------------------------------------------------------------------
def test_view_depths_run_along_the_optical_axes_to_the_hull():
    path = make_path(3)
    depth = view_depths(path, BOX)
    # from (x, y, z) looking at yaw psi, pitch -20 deg: the face y = 20 is (20 - y) / (cos 20 sin psi) away
    expected = (20.0 - path.positions[:, 1]) / (np.cos(np.radians(20.0)) * np.sin(path.yaw))
    assert depth == pytest.approx(expected)
    assert np.isnan(view_depths(path, None)).all()
    # an axis that misses the box (looking away from it): the distance to its nearest point
    away = FlightPath(path.positions[:1], path.yaw[:1] + np.pi, path.pitch[:1], np.zeros(1, int), np.zeros(1, int),
                np.zeros(1, int), speed_m_s=5.0)
    assert view_depths(away, BOX) == pytest.approx([20.0])


def test_a_photo_on_the_move_blurs_by_the_distance_flown_over_the_views_gsd():
    # a level airframe flying sideways at 4 m/s past a view 18 m from the hull, no rotation between chunks
    sec = SimSection(navigation={"preset": "ideal"})
    path = make_path(2)
    targets = FlightTargets.from_path(path, 1, None, PHANTOM4.camera_offset_m, np.array([18.0, 30.0]))
    dt = 0.05
    onboard = Onboard(sec, PHANTOM4, targets, None, 0, dt, path.speed_m_s, path.camera)
    rot = np.eye(3)[None]
    yaw = np.zeros(1)
    velocity = np.array([[0.0, 4.0, 0.0]])
    position = np.array([[1.0, 2.0, 20.0]])
    nav = onboard.sense(0.0, position, velocity, yaw)
    attitude = onboard.point_camera(rot, yaw, np.array([0.0]))
    attitude = onboard.point_camera(rot, yaw, np.array([0.0]))
    rows, views, delay = np.array([0]), np.array([0]), np.array([0.03])
    shot = onboard.shoot(rows, views, delay, 2.0, position, velocity, rot, nav, attitude, targets)
    camera = Camera()
    assert shot.blur_px == pytest.approx([4.0 * sec.capture.exposure_s / camera.gsd_m(18.0)])
    # the shutter 30 ms later: the camera (8 cm ahead, 7.5 cm below the centre of mass) has moved 12 cm along y
    assert shot.time.tolist() == [2.03]
    assert shot.position == pytest.approx(position + [0.08, 4.0 * 0.03, -0.075])
    assert np.array_equal(shot.estimated_position, shot.position)      # ideal navigation: the truth recorded


def _wind_average(speed: float, tau: float, dt: float, n: np.ndarray) -> np.ndarray:
    """The autopilot's average of ``speed`` after n (>= 2) samples, the first one calm: the running mean
    speed (n - 1) / n while its weight 1/n is above the first-order average's 1 - exp(-dt/tau), i.e. up to
    n* = floor(1 / (1 - exp(-dt/tau))) samples, then a first-order lag of time constant tau: the residual
    speed / n* shrinks by exp(-dt/tau) per sample."""
    n_star = np.floor(1.0 / (1.0 - np.exp(-dt / tau)))
    return np.where(n <= n_star, speed * (n - 1) / n, speed - speed / n_star * np.exp(-(n - n_star) * dt / tau))


def test_the_operator_wind_average_is_a_first_order_average_judged_after_its_time_constant():
    tau, dt, limit = 1.0, 0.05, 9.8
    sec = SimSection(navigation={"preset": "ideal"},
                     mission={"operator_wind_average_s": tau, "operator_wind_limit_m_s": limit})
    targets = FlightTargets.from_path(make_path(2), 3, None, PHANTOM4.camera_offset_m)
    onboard = Onboard(sec, PHANTOM4, targets, None, 0, dt, 5.0, Camera())
    home = targets.body[:, 0]
    onboard.decide(home, np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 12.0, 0.0]]))   # at take-off
    wind = np.array([[10.0, 0.0, 3.0], [0.0, 9.7, 0.0], [0.0, 12.0, 0.0]])     # the vertical part is not judged
    estimate, over, px4 = [], [], []
    for _ in range(80):
        decisions = onboard.decide(home, wind)
        over.append(decisions.operator_wind)
        px4.append(decisions.px4_wind)
        estimate.append(onboard.wind_estimate.average.copy())
    estimate, over = np.array(estimate), np.array(over)
    n = np.arange(2, 82)                                             # samples so far, the calm one included
    assert estimate[:, 0, 0] == pytest.approx(_wind_average(10.0, tau, dt, n), rel=1e-9)
    assert estimate[:, 1, 1] == pytest.approx(_wind_average(9.7, tau, dt, n), rel=1e-9)
    assert np.all(estimate[:, :, 2] == 0.0) and estimate[:, 2, 1] == pytest.approx(np.full(80, 12.0))
    # judged from tau on: flight 2 (a steady 12 m/s) at once, flight 0 once its average passes 9.8 m/s,
    # flight 1 (9.7 m/s) never
    judged = (n - 1) * dt >= tau - 1e-9
    assert over[:, 2].tolist() == judged.tolist() and not over[:, 1].any()
    assert over[:, 0].tolist() == (judged & (_wind_average(10.0, tau, dt, n) > limit)).tolist()
    assert over[:, 0].sum() > 0 and np.flatnonzero(over[:, 0])[0] > np.flatnonzero(judged)[0]
    assert not np.any(px4)                                            # the PX4-style limit is off by default


def test_the_px4_style_limit_judges_the_current_estimate_at_once():
    tau, dt = 10.0, 0.05
    sec = SimSection(navigation={"preset": "ideal"}, mission={"wind_estimate_tau_s": tau, "px4_wind_limit_m_s": 9.0})
    targets = FlightTargets.from_path(make_path(2), 2, None, PHANTOM4.camera_offset_m)
    onboard = Onboard(sec, PHANTOM4, targets, None, 0, dt, 5.0, Camera())
    home = targets.body[:, 0]
    wind = np.array([[10.0, 0.0, 0.0], [8.0, 0.0, 0.0]])
    first = onboard.decide(home, wind)        # the estimate starts at the first sample: no averaging time
    assert first.px4_wind.tolist() == [True, False] and not first.operator_wind.any()
    assert onboard.wind_estimate.current[:, 0].tolist() == [10.0, 8.0]


# -- flights --------------------------------------------------------------------------------------------------
def test_calm_ideal_fly_through_takes_every_view_near_the_plan_with_finite_blur():
    path = make_path(4)
    with _simulator(navigation={"preset": "ideal"}, capture={"mode": "fly-through"}) as sim:
        res = sim.fly(path, CALM, batch=2, ship=ShipInScene(BOX, wind_speed_10m_m_s=0.0))   # calm: a still sea
        open_sea = sim.fly(path, CALM, batch=1)
    assert res.outcome.tolist() == [COMPLETED, COMPLETED] and not res.failed.any() and res.taken.all()
    # the shutter opens the trigger latency after the crossing: 50 ms at <= 5 m/s is <= 25 cm along the path
    assert np.linalg.norm(res.offsets[..., :3], axis=-1).max() < 0.5
    assert np.array_equal(res.estimated_offsets, res.offsets)          # the estimate is the truth
    assert np.all(np.diff(res.capture_time_s, axis=1) > 0.0)
    # the ship's box gives every view a depth, hence a blur; over open sea it is unknown
    assert np.isfinite(res.blur_px).all() and np.all(res.blur_px >= 0.0)
    assert np.isnan(open_sea.blur_px).all() and np.array_equal(open_sea.offsets[0], res.offsets[0])
    # view 0 is photographed hovering (no blur), views 1 and 2 at ~4.5 m/s, turning: pixels of blur
    assert res.blur_px[:, 0] == pytest.approx([0.0, 0.0], abs=0.05) and res.blur_px[:, 1:3].max() > 2.0


def test_consumer_navigation_errors_are_nearly_constant_over_a_flight():
    path = make_path(5)
    batch, seed = 8, 3
    with _simulator(navigation={"preset": "ideal"}) as sim:
        ideal = sim.fly(path, CALM, batch=1)
    with _simulator(navigation={"preset": "consumer"}) as sim:
        res = sim.fly(path, CALM, batch=batch, flight_rngs=seed)
        dt = sim.section.timestep_s * sim.section.chunk_steps
    assert not res.failed.any() and res.taken.all()
    # the photo's position prior is the estimate: recorded - true = the navigation error at the shutter (the
    # error of the chunk the trigger fell in, or of the next: the shutter opens up to a chunk later), up to
    # the velocity noise over the shutter delay (<= 0.1 m/s x 50 ms)
    recorded = res.estimated_offsets[..., :3] - res.offsets[..., :3]
    err = _nav_errors("consumer", seed, batch, dt, int(res.capture_time_s.max() / dt) + 3)
    k = np.round(res.capture_time_s / dt).astype(int)
    flights = np.arange(batch)[:, None]
    miss = np.minimum(np.abs(recorded - err[k, flights]).max(-1), np.abs(recorded - err[k - 1, flights]).max(-1))
    assert miss.max() < 0.02
    # the Gauss-Markov error (tau 1100 s) hardly moves over a flight: consecutive views see nearly the same error
    horizontal = recorded[..., :2]
    assert np.corrcoef(horizontal[:, :-1].ravel(), horizontal[:, 1:].ravel())[0, 1] > 0.95
    # the controller puts the estimate on the plan, so the camera is displaced by minus the error: against the
    # same flight with a perfect navigation, same sign on every view and a similar size
    moved = (res.offsets[..., :2] - ideal.offsets[..., :2])[:, 1:]
    large = np.abs(horizontal[:, 1:]).min(axis=1) > 0.6                # (batch, 2): clearly beyond the noise
    assert large.sum() >= 4
    for i, axis in zip(*np.nonzero(large), strict=True):
        assert np.all(np.sign(moved[i, :, axis]) == -np.sign(horizontal[i, 1:, axis]))
        ratio = moved[i, 1:, axis] / moved[i, :-1, axis]
        assert np.all((ratio > 0.5) & (ratio < 2.0))
    assert np.corrcoef(moved[:, :-1].ravel(), moved[:, 1:].ravel())[0, 1] > 0.9


def test_in_calm_air_the_estimate_follows_the_fly_through_path_to_the_fix_noise():
    path = make_path(5)
    with _simulator(navigation={"preset": "ideal"}) as sim:
        ideal = sim.fly(path, CALM, batch=1)
    with _simulator(navigation={"preset": "consumer"}) as sim:
        res = sim.fly(path, CALM, batch=16, flight_rngs=3)
    # the estimate's deviation across the track (y) at the views on the move, against the perfect-navigation
    # flight: what is left is the fix noise the 2 rad/s position loop cannot follow (0.05 m per axis, held per
    # 10 Hz fix); a vehicle that started converged (a long hover at view 0) gives 0.06 m rms here
    cross = (res.estimated_offsets[:, 1:, 1] - ideal.offsets[:, 1:, 1])
    assert np.sqrt((cross ** 2).mean()) < 0.1


def test_a_tiny_battery_sends_the_flight_home_with_its_reserve():
    path = make_path(5)
    capacity_wh = 0.3                          # about 6 s of flight above the 15 % reserve
    dt = 0.05
    with _simulator(navigation={"preset": "ideal"}, battery={"capacity_wh": capacity_wh},
                    record_interval_s=dt, mission={"max_sorties": 1}) as sim:
        res = sim.fly(path, CALM, batch=1)
        sec = sim.section
    assert res.outcome.tolist() == [RETURNED_BATTERY] and not res.failed[0]
    taken = res.taken[0]
    assert taken[0] and not taken.all()
    assert np.array_equal(taken, np.arange(len(path)) < taken.sum())    # the first views, then none
    assert np.isnan(res.offsets[0, ~taken]).all() and len(res.captures[0]) == taken.sum()
    assert "battery" in res.outcome_reason[0] and res.failure_reason == ("",)
    assert np.all(np.diff(res.battery_charge[0, taken]) < 0.0)
    # the autopilot turned when charge - energy home (cruise power x distance / cruise speed) reached the
    # reserve: the chunk before it was still above, the chunk of the return at or below
    tr = res.trajectory
    home = FlightTargets.from_path(path, 1, None, PHANTOM4.camera_offset_m).body[0, 0]
    cruise_w = level_flight_power_w(np.array([path.speed_m_s]), PHANTOM4, sec.battery, sec.drag_coefficient,
                                    sec.air_density_kg_m3)[0]
    home_fraction = cruise_w * np.linalg.norm(tr.position[0] - home, axis=1) / path.speed_m_s / (
        capacity_wh * JOULES_PER_WH)
    end = round(float(res.flight_time_s[0]) / dt)
    assert tr.time[end] == pytest.approx(res.flight_time_s[0])
    margin = tr.charge[0, :-1] - home_fraction[1:]          # at chunk k: the charge left after chunk k-1
    assert margin[end - 1] <= sec.battery.reserve < margin[end - 2]
    assert tr.charge[0, -1] == tr.charge[0, end - 1]         # an ended flight draws nothing


def test_a_battery_return_is_followed_by_a_swap_and_a_sortie_resumed_at_the_breakpoint():
    path = make_path(6)
    capacity_wh, swap_s = 0.95, 20.0           # about 17 s of flight above the 15 % reserve per battery
    # capacity sized for fly-through (the mode it was written for; the default is stop since issue 26) so that
    # every sortie reaches a view: with 0.9 Wh the third sortie spent its battery getting to the breakpoint and
    # back once the fly-through legs got their jerk window (each ~0.6 s longer)
    with _simulator(navigation={"preset": "ideal"}, battery={"capacity_wh": capacity_wh},
                    capture={"mode": "fly-through"},
                    mission={"max_sorties": 10, "swap_time_s": swap_s}) as sim:
        swapped = sim.fly(path, CALM, batch=1)
    with _simulator(navigation={"preset": "ideal"}, battery={"capacity_wh": capacity_wh},
                    capture={"mode": "fly-through"},
                    mission={"max_sorties": 1}) as sim:
        single = sim.fly(path, CALM, batch=1)
    assert single.outcome.tolist() == [RETURNED_BATTERY] and single.sorties.tolist() == [1]
    # with sorties enough, every view is taken, each by exactly one sortie, in order
    assert swapped.outcome.tolist() == [COMPLETED] and swapped.taken.all() and swapped.sorties[0] >= 2
    assert np.all(np.diff(swapped.view_sortie[0]) >= 0) and swapped.view_sortie[0, 0] == 1
    assert swapped.views_per_sortie.sum() == len(path) and swapped.views_per_sortie.shape == (1, swapped.sorties[0])
    # the first sortie is the single-sortie flight until it turns home
    first = swapped.view_sortie[0] == 1
    assert np.array_equal(first, single.taken[0])
    np.testing.assert_array_equal(swapped.offsets[0, first], single.offsets[0, first])
    # each swap costs at least the time on deck: the mission takes longer than its flying
    assert swapped.flight_time_s[0] > single.flight_time_s[0] + (swapped.sorties[0] - 1) * swap_s
    # each resumed sortie starts with a fresh battery (less the way back to the breakpoint): the charge rises
    # once per swap and never otherwise; it is not drawn while on deck
    rises = np.diff(swapped.trajectory.charge[0]) > 0.0
    assert rises.sum() == swapped.sorties[0] - 1


def test_a_wind_over_the_operator_limit_sends_the_flight_home_after_the_averaging_time():
    tau = 1.0
    with _simulator(navigation={"preset": "ideal"},
                    mission={"operator_wind_limit_m_s": 3.0, "operator_wind_average_s": tau}) as sim:
        res = sim.fly(make_path(4), ConstantWind([4.0, -1.0, 0.0]), batch=2)
        dt = sim.section.timestep_s * sim.section.chunk_steps
    assert res.outcome.tolist() == [RETURNED_WIND_AVERAGE] * 2 and not res.failed.any()
    # a constant wind is its own average: judged (and over the limit) as soon as the average has had tau
    assert tau <= res.flight_time_s[0] <= tau + dt + 1e-9
    assert "wind" in res.outcome_reason[0] and "3 m/s" in res.outcome_reason[0]
    assert not res.taken[:, -1].any()


class _StepWind:
    """Calm at t = 0, then a constant wind per flight (row i: ``speeds[i]`` m/s along +x)."""

    def __init__(self, speeds):
        self.speeds = np.asarray(speeds, dtype=float)

    def velocity(self, points, t):
        out = np.zeros((len(points), 3))
        out[:, 0] = self.speeds if t > 0.0 else 0.0
        return out


def test_a_rising_wind_turns_the_flight_when_its_average_crosses_the_limit():
    tau, limit = 1.0, 9.8
    # the old keys sim.wind_limit_m_s / wind_average_s (stored campaigns) are read as the operator policy, also
    # beside a mission section given as a model
    from wrp_eval.sim.mission import MissionSection
    beside = SimSection.model_validate({"wind_limit_m_s": 8.0, "mission": MissionSection(max_sorties=2)})
    assert beside.mission.operator_wind_limit_m_s == 8.0 and beside.mission.max_sorties == 2
    with _simulator(navigation={"preset": "ideal"}, wind_limit_m_s=limit, wind_average_s=tau) as sim:
        assert sim.section.mission.operator_wind_limit_m_s == limit
        assert sim.section.mission.operator_wind_average_s == tau
        res = sim.fly(make_path(3), _StepWind([10.0, 6.0]), batch=2)
        dt = sim.section.timestep_s * sim.section.chunk_steps
    # calm at the first chunk, then 10 m/s: the chunk whose average first exceeds 9.8 m/s (after tau)
    n = np.arange(2, 200)
    first = n[_wind_average(10.0, tau, dt, n) > limit][0]
    assert res.outcome.tolist() == [RETURNED_WIND_AVERAGE, COMPLETED]
    assert res.flight_time_s[0] == pytest.approx((first - 1) * dt) and (first - 1) * dt > tau
    assert res.taken[1].all()


def test_a_flight_does_not_depend_on_its_batch():
    path = make_path(4)
    ship = ShipInScene(BOX, ShipMotionSection(sea_state=3))
    wind = ConstantWind([3.0, 1.0, 0.0])

    def generators():
        return [np.random.default_rng(s) for s in np.random.SeedSequence(11).spawn(3)]

    with _simulator(navigation={"preset": "consumer"}) as sim:
        batch = sim.fly(path, wind, batch=3, ship=ship, flight_rngs=generators())
        alone = [sim.fly(path, wind, batch=1, ship=ship, flight_rngs=[generators()[i]]) for i in (0, 2)]
    assert not batch.failed.any() and batch.taken.all()
    assert not np.allclose(batch.offsets[0], batch.offsets[2])          # the flights differ ...
    for i, res in zip((0, 2), alone, strict=True):                                   # ... each as it would alone
        for name in ("offsets", "estimated_offsets", "capture_time_s", "blur_px", "ship_motion", "camera_roll",
                     "battery_charge"):
            assert np.array_equal(getattr(res, name)[0], getattr(batch, name)[i], equal_nan=True), name
