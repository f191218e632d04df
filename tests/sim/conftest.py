"""Shared fixtures of the sim tests: a small simulator and short paths."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.planning.path import FlightPath
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.flight import FlightSimulator

# the airframe, controller and flight logic alone: the truth as navigation, photos at rest with no trigger delay,
# no battery return (no wind-limit return either: off by default): the simulator before the capture realism of
# issue 16, bit for bit
CONTROLLER_ONLY = dict(navigation={"preset": "ideal"}, capture={"mode": "stop", "trigger_latency_s": 0.0},
                       battery={"enabled": False})


@pytest.fixture(scope="session")
def section() -> SimSection:
    return SimSection(drones_per_model=4, threads=1)


@pytest.fixture(scope="session")
def controller_section() -> SimSection:
    return SimSection.model_validate(dict(drones_per_model=4, threads=1, **CONTROLLER_ONLY))


@pytest.fixture(scope="session")
def controller_simulator(controller_section):
    sim = FlightSimulator(controller_section)
    yield sim
    sim.close()


@pytest.fixture(scope="session")
def simulator(section):
    sim = FlightSimulator(section)
    yield sim
    sim.close()


def make_path(n: int = 4, spacing_m: float = 8.0, dwell_s: float = 1.0) -> FlightPath:
    """n viewpoints along a line at 20 m with alternating yaw and a climb, gimbal pitch -20 deg."""
    x = spacing_m * np.arange(n)
    pos = np.stack([x, 2.0 * (np.arange(n) % 2), 20.0 + 0.5 * np.arange(n)], axis=1)
    yaw = np.radians(90.0 + 30.0 * (np.arange(n) % 2))
    return FlightPath(pos, yaw, np.full(n, np.radians(-20.0)), np.zeros(n, int), np.zeros(n, int), np.zeros(n, int),
                speed_m_s=5.0, dwell_s=dwell_s)


@pytest.fixture
def short_path() -> FlightPath:
    return make_path()
