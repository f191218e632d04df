"""Power and battery model (wrp_eval/sim/power.py) against momentum theory and simple energy bookkeeping."""

import numpy as np
import pytest
from pydantic import ValidationError

from wrp_eval.sim.aero import drag_force, windward_area
from wrp_eval.sim.power import (
    Battery,
    BatterySection,
    electrical_power_w,
    hover_power_w,
    induced_power_w,
    level_flight_power_w,
    parasite_power_w,
    return_energy_j,
)
from wrp_eval.sim.vehicle import PHANTOM4 as P

RHO = 1.225
S = BatterySection()
AREA = np.pi * P.rotor_radius_m ** 2


def test_hover_power_is_momentum_theory():
    # independent closed form: T = m g / 4 per rotor, v_h = sqrt(T / (2 rho A)), P_ideal = 4 T v_h
    t = 1.38 * 9.81 / 4.0
    v_h = np.sqrt(t / (2.0 * RHO * np.pi * 0.1195 ** 2))
    expected = 4.0 * t * v_h / (S.figure_of_merit * S.drive_efficiency) + S.avionics_w
    assert hover_power_w(P, S, RHO) == pytest.approx(expected, rel=1e-9)


def test_induced_power_scales_as_thrust_to_the_1_5():
    t = np.array([[2.0, 2.0, 2.0, 2.0], [4.0, 4.0, 4.0, 4.0], [8.0, 8.0, 8.0, 8.0]])
    p = induced_power_w(t, AREA, RHO)
    np.testing.assert_allclose(p[1:] / p[:-1], 2.0 ** 1.5, rtol=1e-12)
    # per rotor, summed: an uneven split costs more than an even one at the same total (convexity)
    uneven = induced_power_w(np.array([[1.0, 3.0, 1.0, 3.0]]), AREA, RHO)
    assert uneven[0] > p[0]
    assert uneven[0] == pytest.approx(2 * (1.0 + 3.0 ** 1.5) / np.sqrt(2 * RHO * AREA))


def test_induced_power_halves_density_costs_sqrt2():
    t = np.full((1, 4), 3.0)
    assert induced_power_w(t, AREA, RHO / 2)[0] == pytest.approx(np.sqrt(2.0) * induced_power_w(t, AREA, RHO)[0])


def test_parasite_power_is_half_rho_cd_a_v_cubed():
    rel = np.array([[6.0, -3.0, 0.5], [0.0, 9.0, 0.0], [-2.0, 0.0, 0.0]])
    yaw = np.array([0.3, -1.0, 2.0])
    cd = 1.1
    f = drag_force(rel, yaw, P, cd, RHO)
    speed = np.linalg.norm(rel, axis=1)
    expected = 0.5 * RHO * cd * windward_area(rel, yaw, P) * speed ** 3
    np.testing.assert_allclose(parasite_power_w(f, rel), expected, rtol=1e-12)
    # and it enters the battery power divided by the drive efficiency only
    thrust = np.full((3, 4), P.weight_n / 4.0)
    still = electrical_power_w(thrust, np.zeros((3, 3)), np.zeros((3, 3)), P, S, RHO)
    moving = electrical_power_w(thrust, f, rel, P, S, RHO)
    np.testing.assert_allclose(moving - still, expected / S.drive_efficiency, rtol=1e-12)


def test_level_flight_power_grows_with_airspeed_and_starts_at_hover():
    p = level_flight_power_w(np.array([0.0, 5.0, 10.0, 15.0]), P, S, 1.0, RHO)
    assert p[0] == pytest.approx(hover_power_w(P, S, RHO), rel=1e-12)
    assert np.all(np.diff(p) > 0.0)


def test_battery_drains_linearly_and_endurance_matches_closed_form():
    power = hover_power_w(P, S, RHO)
    bat = Battery(S, 2)
    e0 = bat.energy_j.copy()
    for _ in range(10):
        bat.drain(np.full(2, power), 0.05, np.array([True, False]))
    assert bat.energy_j[0] == pytest.approx(e0[0] - 10 * 0.05 * power, rel=1e-12)
    assert bat.energy_j[1] == e0[1]                       # inactive flight untouched
    endurance = S.capacity_wh * 3600.0 * (1.0 - S.reserve) / power
    assert Battery(S, 1).endurance_s(power)[0] == pytest.approx(endurance, rel=1e-12)
    # fly at 20 Hz until the reserve check fires: it fires in the chunk that crosses the closed-form time
    small = BatterySection(capacity_wh=0.05)              # 180 J: about a second of hover
    bat = Battery(small, 1)
    steps = 0
    while not bat.needs_return(0.0)[0]:
        bat.drain(np.array([power]), 0.05)
        steps += 1
    assert steps == int(np.ceil(small.capacity_j * (1 - small.reserve) / power / 0.05))


def test_needs_return_flips_exactly_at_reserve_plus_return_energy():
    # 100 Wh = 360 kJ, reserve 25 % = 90 kJ; return energies chosen so that all three flights reach
    # reserve + return energy after exactly 1000 s (all numbers exact in binary floating point)
    section = BatterySection(capacity_wh=100.0, reserve=0.25)
    power = np.array([100.0, 150.0, 200.0])
    ret = 360_000.0 - 90_000.0 - power * 1000.0
    bat = Battery(section, 3)
    bat.drain(power, 1000.0 * (1.0 - 1e-9))
    assert not bat.needs_return(ret).any()
    bat.drain(power, 1000.0 * 1e-9)
    assert bat.needs_return(ret).all()
    # the same at the simulator's 20 Hz: the check fires on step 20000, not one step earlier
    bat = Battery(section, 3)
    bat.drain(power, 0.05 * 19_999)
    assert not bat.needs_return(ret).any()
    bat.drain(power, 0.05)
    assert bat.needs_return(ret).all()
    # per flight: only the flight whose return energy is larger is due
    bat = Battery(section, 2)
    assert bat.needs_return(np.array([269_999.0, 270_000.0])).tolist() == [False, True]
    # a disabled section never ends a sortie
    assert not Battery(BatterySection(enabled=False), 1).needs_return(1e9).any()


def test_battery_stops_at_empty():
    bat = Battery(BatterySection(capacity_wh=0.01), 2)      # 36 J
    bat.drain(np.array([10.0, 100.0]), 1.0)
    assert bat.energy_j.tolist() == [26.0, 0.0]
    assert bat.depleted.tolist() == [False, True]
    np.testing.assert_allclose(bat.charge, [26.0 / 36.0, 0.0])


def test_return_energy_is_power_times_time():
    d = np.array([0.0, 100.0, 250.0])
    np.testing.assert_allclose(return_energy_j(d, 10.0, 150.0), [0.0, 1500.0, 3750.0])
    np.testing.assert_allclose(return_energy_j(d, np.array([5.0, 5.0, 10.0]), np.array([1.0, 2.0, 4.0])),
                               [0.0, 40.0, 100.0])
    with pytest.raises(ValueError, match="positive"):
        return_energy_j(d, 0.0, 150.0)


def test_batch_row_equals_the_same_flight_alone():
    rng = np.random.default_rng(3)
    thrust = rng.uniform(1.0, 6.0, (3, 4))
    rel = rng.normal(0.0, 5.0, (3, 3))
    drag = drag_force(rel, np.zeros(3), P, 1.0, RHO)
    batch = electrical_power_w(thrust, drag, rel, P, S, RHO)
    for i in range(3):
        alone = electrical_power_w(thrust[i:i + 1], drag[i:i + 1], rel[i:i + 1], P, S, RHO)
        assert alone[0] == batch[i]


@pytest.mark.parametrize("kwargs, key", [({"capacity_wh": 0.0}, "capacity_wh"),
                                         ({"reserve": 0.5, "start_charge": 0.5}, "reserve"),
                                         ({"reserve": 0.6, "start_charge": 0.4}, "reserve"),
                                         ({"figure_of_merit": 1.2}, "figure_of_merit"),
                                         ({"start_charge": -0.1}, "start_charge"),
                                         ({"capacity": 80.0}, "capacity")])
def test_bad_sections_are_rejected_naming_the_key(kwargs, key):
    with pytest.raises(ValidationError) as err:
        BatterySection(**kwargs)
    assert err.value.errors()[0]["loc"] == (key,)
