"""The one frames module: ship <-> ENU, ship frame <-> geographic (hand-computed cases, round trips and an
independent ECEF tangent-plane check), compass bearings, the wind-direction convention and the ship pose."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.errors import InputError
from wrp_eval.frames import (
    ShipPose,
    compass_to_yaw_rad,
    enu_to_ship,
    geographic_to_enu_equirectangular,
    geographic_to_ship,
    ship_pose,
    ship_to_enu,
    ship_to_geographic,
    wind_velocity,
    wrap_180,
    yaw_to_compass_deg,
)
from wrp_eval.ship.particulars import ShipParticulars

WGS84_A = 6378137.0
WGS84_F = 1 / 298.257223563
WGS84_E2 = WGS84_F * (2 - WGS84_F)


def ecef(lat_deg, lon_deg, h=0.0):
    """Geodetic -> ECEF (closed form, WGS84), written independently of pyproj."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    n = WGS84_A / np.sqrt(1 - WGS84_E2 * np.sin(lat) ** 2)
    return np.stack([(n + h) * np.cos(lat) * np.cos(lon), (n + h) * np.cos(lat) * np.sin(lon),
                     (n * (1 - WGS84_E2) + h) * np.sin(lat)], axis=-1)


def enu(lat_deg, lon_deg, lat0, lon0):
    """East, north, up (m) of points about (lat0, lon0) in the local tangent plane."""
    d = ecef(lat_deg, lon_deg) - ecef(lat0, lon0)
    la, lo = np.radians(lat0), np.radians(lon0)
    east = np.array([-np.sin(lo), np.cos(lo), 0.0])
    north = np.array([-np.sin(la) * np.cos(lo), -np.sin(la) * np.sin(lo), np.cos(la)])
    up = np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)])
    return d @ east, d @ north, d @ up


@pytest.mark.parametrize("heading, point, expected_east_north", [
    (0.0, (100.0, 0.0), (0.0, 100.0)),     # bow north: x is north
    (0.0, (0.0, 10.0), (-10.0, 0.0)),      # port of a north-heading ship is west
    (90.0, (100.0, 0.0), (100.0, 0.0)),    # bow east
    (90.0, (0.0, 10.0), (0.0, 10.0)),      # port of an east-heading ship is north
    (180.0, (0.0, 10.0), (10.0, 0.0)),     # port of a south-heading ship is east
    (45.0, (10.0, 0.0), (10 / np.sqrt(2), 10 / np.sqrt(2))),
])
def test_ship_axes_to_east_north(heading, point, expected_east_north):
    e, n = ship_to_enu(point[0], point[1], np.radians(heading))
    np.testing.assert_allclose([e, n], expected_east_north, atol=1e-12)
    np.testing.assert_allclose(enu_to_ship(e, n, np.radians(heading)), point, atol=1e-12)


def test_east_at_equator_matches_arc_length():
    # 100 m east on the equator: 100 / a rad of longitude.
    lat, lon = ship_to_geographic(np.array([[100.0, 0.0, 20.0]]), ShipPose(0.0, 0.0, 90.0))
    assert abs(lat[0]) < 1e-12
    assert lon[0] == pytest.approx(np.degrees(100.0 / WGS84_A), rel=1e-9)


@pytest.mark.parametrize("pose", [ShipPose(54.4, 10.2, 57.0), ShipPose(-33.9, 151.2, 301.5),
                                  ShipPose(0.0, 179.99, 180.0), ShipPose(78.2, 15.6, 0.0)])
def test_geographic_agrees_with_tangent_plane_within_a_centimetre_over_1km(pose):
    rng = np.random.default_rng(7)
    r = rng.uniform(0.0, 1000.0, 200)
    t = rng.uniform(0.0, 2 * np.pi, 200)
    pts = np.stack([r * np.cos(t), r * np.sin(t), np.zeros(200)], axis=1)
    lat, lon = ship_to_geographic(pts, pose)
    e, n, _ = enu(lat, lon, pose.lat_deg, pose.lon_deg)
    e_ref, n_ref = ship_to_enu(pts[:, 0], pts[:, 1], pose.heading_rad)
    assert np.max(np.hypot(e - e_ref, n - n_ref)) < 0.01
    # and the inverse recovers the ship frame to numerical precision
    np.testing.assert_allclose(geographic_to_ship(lat, lon, pose), pts[:, :2], atol=1e-6)


def test_compass_heading_convention():
    # Ship heading 57 deg; a camera looking along the bow has compass 57, to port 57 - 90 = 327,
    # to starboard 147, aft 237.
    yaw = np.radians([0.0, 90.0, -90.0, 180.0])
    np.testing.assert_allclose(yaw_to_compass_deg(yaw, 57.0), [57.0, 327.0, 147.0, 237.0], atol=1e-9)
    back = compass_to_yaw_rad(yaw_to_compass_deg(yaw, 57.0), 57.0)
    np.testing.assert_allclose(wrap_180(np.degrees(back - yaw)), 0.0, atol=1e-9)
    assert np.all((yaw_to_compass_deg(np.linspace(-7, 7, 50), 359.0) >= 0)
                  & (yaw_to_compass_deg(np.linspace(-7, 7, 50), 359.0) < 360))


def test_wrap_180():
    np.testing.assert_allclose(wrap_180(np.array([-180.0, 180.0, 190.0, -190.0, 540.0, 0.0])),
                               [180.0, 180.0, -170.0, 170.0, 180.0, 0.0])


@pytest.mark.parametrize("direction_from, heading, expected", [
    (270.0, None, (5.0, 0.0)),        # a westerly blows toward the east
    (0.0, None, (0.0, -5.0)),         # a northerly blows toward the south
    (0.0, 0.0, (-5.0, 0.0)),          # from the north, bow north: from the bow, toward the stern (-x)
    (90.0, 0.0, (0.0, 5.0)),          # from the east, bow north: from starboard, toward port (+y)
    (90.0, 90.0, (-5.0, 0.0)),        # from the east, bow east: from the bow
    (270.0, 90.0, (5.0, 0.0)),        # from the west, bow east: from astern, toward the bow
    (180.0, 270.0, (0.0, -5.0)),      # from the south, bow west: from port (south of a west-heading ship)
])
def test_wind_velocity_blows_from_the_compass_bearing(direction_from, heading, expected):
    v = wind_velocity(5.0, np.radians(direction_from), None if heading is None else np.radians(heading))
    np.testing.assert_allclose(v, [*expected, 0.0], atol=1e-12)


def test_wind_velocity_is_batched_and_the_ship_frame_is_the_rotated_enu():
    rng = np.random.default_rng(2)
    speed, direction, heading = rng.uniform(0, 20, (4, 5)), rng.uniform(0, 2 * np.pi, 5), 1.3
    enu, ship = wind_velocity(speed, direction), wind_velocity(speed, direction, heading)
    assert enu.shape == ship.shape == (4, 5, 3) and np.all(enu[..., 2] == 0)
    np.testing.assert_allclose(np.linalg.norm(ship, axis=-1), speed)
    np.testing.assert_allclose(np.stack(ship_to_enu(ship[..., 0], ship[..., 1], heading), -1), enu[..., :2],
                               atol=1e-12)


def test_ship_pose_of_particulars_tuples_and_poses():
    particulars = ShipParticulars(140, 20, 12, 15, 6, lat_deg=23.7, lon_deg=-89.5, heading_deg=45.0)
    assert ship_pose(particulars) == ShipPose(23.7, -89.5, 45.0) == ship_pose((23.7, -89.5, 45.0))
    assert ship_pose(ShipPose(1.0, 2.0, 3.0)).heading_rad == pytest.approx(np.radians(3.0))
    with pytest.raises(InputError, match="ship"):
        ship_pose("north")


def test_equirectangular_placement_keeps_parallels_straight():
    pose = ShipPose(23.7, -89.5, 0.0)
    lat = np.full(5, 24.0)
    east, north = geographic_to_enu_equirectangular(lat, np.linspace(-90.5, -88.5, 5), pose)
    np.testing.assert_allclose(north, 6_371_000.0 * np.radians(0.3))          # one parallel: one northing
    np.testing.assert_allclose(np.diff(east), 6_371_000.0 * np.cos(np.radians(23.7)) * np.radians(0.5))
    # within 1 km of the ship it agrees with the geodesic frame to ~0.3 % (sphere vs ellipsoid)
    lat2, lon2 = ship_to_geographic(np.array([[700.0, -400.0, 0.0]]), pose)
    e, n = geographic_to_enu_equirectangular(lat2, lon2, pose)
    np.testing.assert_allclose([e[0], n[0]], [400.0, 700.0], rtol=5e-3)
