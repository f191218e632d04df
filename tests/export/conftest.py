"""Shared fixtures: a ship off Kiel at heading 57 deg and a two-sortie path around it."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.camera import Camera
from wrp_eval.export.config import ExportSection
from wrp_eval.planning.path import KIND_SURFACE, FlightPath
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.proxy import build_proxy
from wrp_eval.ship.resolve import resolve_particulars

SHIP_POSE = {"lat_deg": 54.4, "lon_deg": 10.2, "heading_deg": 57.0}


@pytest.fixture(scope="session")
def ship():
    """(particulars, proxy) of the stylized ship at SHIP_POSE."""
    section = ShipSection.model_validate({"particulars": SHIP_POSE})
    particulars, _ = resolve_particulars(section, ".", "test")
    return particulars, build_proxy(particulars)


def ring_path(proxy, n: int = 24, sorties: int = 2, stand_off_m: float = 30.0) -> FlightPath:
    """n views on an ellipse outside the no-fly box, looking at the ship centre, split into sorties."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    a = proxy.length_m / 2 + stand_off_m
    b = proxy.breadth_m / 2 + stand_off_m
    z = np.linspace(8.0, 45.0, n)
    positions = np.stack([a * np.cos(t), b * np.sin(t), z], axis=1)
    target = np.array([0.0, 0.0, proxy.height_m / 2])
    d = target - positions
    yaw = np.arctan2(d[:, 1], d[:, 0])
    pitch = np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1]))
    sortie = (np.arange(n) * sorties) // n
    return FlightPath(positions, yaw, pitch, np.zeros(n, int), np.full(n, KIND_SURFACE), sortie, Camera(),
                speed_m_s=5.0, dwell_s=2.0)


@pytest.fixture
def make_ring_path():
    """The :func:`ring_path` factory (test modules cannot import conftest under --import-mode=importlib)."""
    return ring_path


@pytest.fixture
def path(ship):
    return ring_path(ship[1])


@pytest.fixture
def section():
    return ExportSection()
