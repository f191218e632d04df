"""Shared fixtures of the planning tests: two proxies built from particulars (independent of the ship
stage's meshes) with fixed, documented complexity vectors, and the plans of every method on them."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.planning.config import PlanningSection
from wrp_eval.planning.planner import plan
from wrp_eval.ship.particulars import ShipParticulars, ShipType
from wrp_eval.ship.proxy import build_proxy

# Fixed per-face complexities (bow, stern, port, starboard, top), triangles / m^2, of the order of the
# ship stage's procedural meshes: sides busiest on the stylized ship, bow/stern on the cruise ship.
COMPLEXITY = {
    "stylized": np.array([0.076, 0.076, 0.119, 0.119, 0.054]),
    "cruise": np.array([0.37, 0.37, 0.074, 0.074, 0.078]),
}
PARTICULARS = {
    # the paper's reference ship: 140 m x 20 m x 25 m above the waterline
    "stylized": ShipParticulars(140.0, 20.0, 12.0, 19.0, 6.0, ShipType.STYLIZED),
    # a mid-size cruise ship, 250 m x 32 m, 47 m above the waterline
    "cruise": ShipParticulars(250.0, 32.0, 18.0, 37.0, 8.0, ShipType.CRUISE),
}
FAST: dict = {}  # the defaults are fast enough; kept as the one place to trade speed in tests


@pytest.fixture(scope="session")
def proxies():
    return {name: build_proxy(p) for name, p in PARTICULARS.items()}


@pytest.fixture(scope="session")
def stylized_proxy(proxies):
    return proxies["stylized"]


@pytest.fixture(scope="session")
def plans(proxies):
    """{(ship, method): PlanResult} for both ships and all three methods (seed 0)."""
    out = {}
    for ship, proxy in proxies.items():
        for method in ("ours", "zhou2020", "oblique"):
            section = PlanningSection(method=method, **FAST)
            out[(ship, method)] = plan(proxy, COMPLEXITY[ship], section, np.random.default_rng(0))
    return out


@pytest.fixture(scope="session")
def complexity_of():
    """Ship name -> fixed complexity vector (5,)."""
    return dict(COMPLEXITY)


@pytest.fixture(scope="session")
def fast():
    """Section overrides that keep a plan fast in tests."""
    return dict(FAST)
