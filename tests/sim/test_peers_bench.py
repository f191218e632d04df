"""The peers bench's translation of our Phantom 4 into RotorPy's parameters (the timings are the bench's)."""

import logging

import numpy as np
import pytest

from wrp_eval.sim.config import SimSection
from wrp_eval.sim.peers_bench import rotorpy_params, run_bench
from wrp_eval.sim.vehicle import PHANTOM4


def test_rotorpy_parameters_are_our_vehicle():
    section = SimSection()
    p = rotorpy_params(section)
    assert p["mass"] == PHANTOM4.mass_kg and (p["Ixx"], p["Iyy"], p["Izz"]) == PHANTOM4.inertia_kg_m2
    # top rotor speed gives our maximum thrust per motor; yaw moment per thrust as ours
    assert p["k_eta"] * p["rotor_speed_max"] ** 2 == pytest.approx(PHANTOM4.max_thrust_per_motor_n)
    assert p["k_m"] / p["k_eta"] == pytest.approx(PHANTOM4.yaw_torque_per_newton_m)
    # rotors on the X at the arm length
    arms = np.array([np.linalg.norm(r) for r in p["rotor_pos"].values()])
    np.testing.assert_allclose(arms, PHANTOM4.arm_length_m)
    # quadratic drag along x: F = c_Dx v^2 = 0.5 rho C_d A v^2 with A the body's width x height
    area = PHANTOM4.body_width_m * PHANTOM4.body_height_m
    assert p["c_Dx"] == pytest.approx(0.5 * section.air_density_kg_m3 * section.drag_coefficient * area)


def test_without_rotorpy_the_group_is_skipped_in_one_line(caplog):
    try:
        import rotorpy  # noqa: F401
    except ImportError:
        with caplog.at_level(logging.INFO, logger="wrp_eval"):
            assert run_bench() == []
        out = caplog.messages
        assert len(out) == 1 and "skipped" in out[0] and "[peers]" in out[0]
    else:
        pytest.skip("RotorPy is installed here: the bench would run")
