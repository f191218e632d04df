import numpy as np
import pytest

from wrp_eval.sim.aero import drag_force, windward_area
from wrp_eval.sim.vehicle import PHANTOM4 as P

ROTORS = 4 * np.pi * P.rotor_radius_m * P.rotor_height_m   # half the lateral surface of each blade cylinder


def test_head_on_wind_sees_width_times_height():
    # wind along the nose: its normal is the body's lateral axis -> dot1 = 0, dot2 = W
    a = windward_area(np.array([[-7.0, 0.0, 0.0]]), np.array([0.0]), P)
    assert a[0] == pytest.approx(P.body_width_m * P.body_height_m + ROTORS)


def test_side_wind_sees_length_times_height():
    a = windward_area(np.array([[0.0, 3.0, 0.0]]), np.array([0.0]), P)
    assert a[0] == pytest.approx(P.body_length_m * P.body_height_m + ROTORS)


def test_oblique_wind_and_yaw_invariance():
    # 45 deg: (L + W) / sqrt(2) * H; rotating wind and body together changes nothing
    a = windward_area(np.array([[1.0, 1.0, 0.0]]), np.array([0.0]), P)
    assert a[0] == pytest.approx((P.body_length_m + P.body_width_m) / np.sqrt(2) * P.body_height_m + ROTORS)
    yaw = 1.1
    w = np.array([[np.cos(yaw + 0.3), np.sin(yaw + 0.3), 0.0]])
    assert windward_area(w, np.array([yaw]), P)[0] == pytest.approx(
        windward_area(np.array([[np.cos(0.3), np.sin(0.3), 0.0]]), np.array([0.0]), P)[0])


def test_vertical_air_uses_the_top_area():
    a = windward_area(np.array([[0.0, 0.0, -2.0]]), np.array([0.0]), P)
    assert a[0] == pytest.approx(P.body_length_m * P.body_width_m)


def test_drag_magnitude_and_direction():
    v = np.array([[6.0, 8.0, 0.0]])
    f = drag_force(v, np.array([0.2]), P, 1.1, 1.2)
    area = windward_area(v, np.array([0.2]), P)[0]
    assert np.linalg.norm(f) == pytest.approx(0.5 * 1.2 * 1.1 * area * 100.0)
    assert np.allclose(np.cross(f[0], v[0]), 0.0)
    assert f[0] @ v[0] > 0
    assert np.allclose(drag_force(np.zeros((2, 3)), np.zeros(2), P, 1.0, 1.2), 0.0)
