"""Ship motion (wrp_eval.ship.motion): the published sea-state figures, frequencies, frames, batch independence."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model
from wrp_eval.ship.motion import (
    WMO_HS_UPPER_M,
    ShipMotionSection,
    sea_state_figures,
    ship_motion,
)

FT = 0.3048
# Lu & Liu 2019 (Int. J. Aerospace Eng. 6917393), Table 2: (heave ft, roll deg, pitch deg) per sea state and
# the frequencies (rad/s) heave 0.3491, roll 0.2856, pitch 0.5236.
PUBLISHED = {4: (2.2274, 0.6223, 0.5162), 5: (3.5638, 0.9829, 0.8202), 6: (5.3528, 1.4425, 1.2374)}
PUBLISHED_FREQ = (0.3491, 0.2856, 0.5236)
DT_S = 0.25
WINDOW = np.arange(0.0, 4000.0, DT_S)       # >= 180 periods of the slowest motion (roll, 22 s)


def _published_si(ss: int) -> np.ndarray:
    heave_ft, roll_deg, pitch_deg = PUBLISHED[ss]
    return np.array([heave_ft * FT, np.radians(roll_deg), np.radians(pitch_deg)])


def _series(motion, n: int) -> np.ndarray:
    """(n, m, 4) motion over WINDOW."""
    return motion.dof(np.broadcast_to(WINDOW, (n, WINDOW.size)))


def _up_crossing_rate(q: np.ndarray) -> np.ndarray:
    """Zero up-crossings per second along axis 1 of (n, m, 4): the mean frequency / (2 pi) (Rice 1944)."""
    ups = np.sum((q[:, :-1] < 0) & (q[:, 1:] >= 0), axis=1)
    return ups / (WINDOW[-1] - WINDOW[0])


@pytest.mark.parametrize("ss", [4, 5, 6])
def test_sinusoid_amplitude_is_the_published_figure(ss):
    """One component: the peak |q| over a long window and sqrt(2) x RMS both equal the table's amplitude."""
    motion = ship_motion(ShipMotionSection(sea_state=ss), None, 11, 4)
    q = _series(motion, 4)
    expected = _published_si(ss)
    peak = np.abs(q).max(axis=1)[:, :3]
    rms2 = np.sqrt(2.0 * np.mean(q ** 2, axis=1))[:, :3]
    np.testing.assert_allclose(peak, np.broadcast_to(expected, peak.shape), rtol=0.01)
    np.testing.assert_allclose(rms2, np.broadcast_to(expected, rms2.shape), rtol=0.02)
    np.testing.assert_allclose(motion.amplitudes()[:, :3], np.broadcast_to(expected, (4, 3)), rtol=1e-9)


def test_sea_state_4_and_6_quoted_figures():
    """The issue's figures: SS4 roll 0.62 deg / pitch 0.52 deg / heave 0.68 m, SS6 roll 1.44 deg / heave 1.63 m."""
    a4, w4 = sea_state_figures(4)
    a6, _ = sea_state_figures(6)
    np.testing.assert_allclose([a4[0], np.degrees(a4[1]), np.degrees(a4[2])], [0.68, 0.62, 0.52], rtol=0.01)
    np.testing.assert_allclose([a6[0], np.degrees(a6[1])], [1.63, 1.44], rtol=0.01)
    np.testing.assert_allclose(w4[:3], [0.349, 0.286, 0.524], rtol=0.01)


def test_lower_sea_states_scale_with_the_wmo_wave_height_bound():
    """Rows 1-3 are row 4 x Hs_max(ss) / Hs_max(4), and the motion grows monotonically with the sea state."""
    a4, _ = sea_state_figures(4)
    for ss in (1, 2, 3):
        np.testing.assert_allclose(sea_state_figures(ss)[0], a4 * WMO_HS_UPPER_M[ss] / 2.5, rtol=1e-12)
    amps = np.array([sea_state_figures(ss)[0] for ss in range(7)])
    assert np.all(np.diff(amps, axis=0) > 0)
    assert np.all(amps[0] == 0)


def test_sinusoid_frequency_is_the_published_one():
    motion = ship_motion(ShipMotionSection(sea_state=5), None, 3, 5)
    q = _series(motion, 5)
    rate = _up_crossing_rate(q)[:, :3] * 2 * np.pi
    np.testing.assert_allclose(rate, np.broadcast_to(PUBLISHED_FREQ, rate.shape), rtol=0.02)
    # exactly periodic with the table's period
    w = np.array(PUBLISHED_FREQ)
    t0 = np.full(5, 17.3)
    shifted = np.stack([motion.dof(t0 + 2 * np.pi / wd)[:, d] for d, wd in enumerate(w)], axis=1)
    np.testing.assert_allclose(shifted, motion.dof(t0)[:, :3], atol=1e-9)


def test_narrow_band_process_keeps_rms_and_mean_frequency():
    """K components: sqrt(2) x RMS (flight mean of the mean square) is the table's amplitude, and the zero
    up-crossing rate is the components' mean frequency sqrt(sum a^2 w^2 / sum a^2), within 10 %."""
    n = 48
    section = ShipMotionSection(sea_state=4, components=6, relative_bandwidth=0.2)
    motion = ship_motion(section, None, 5, n)
    q = _series(motion, n)
    rms2 = np.sqrt(2.0 * np.mean(q ** 2, axis=(0, 1)))
    np.testing.assert_allclose(rms2, sea_state_figures(4)[0], rtol=0.10)
    rate = _up_crossing_rate(q) * 2 * np.pi
    np.testing.assert_allclose(rate.mean(axis=0), motion.frequencies().mean(axis=0), rtol=0.10)
    np.testing.assert_allclose(motion.frequencies(), np.broadcast_to(sea_state_figures(4)[1], (n, 4)), rtol=0.10)
    # frequencies drawn within the band
    w0 = sea_state_figures(4)[1][None, :, None]
    assert np.all(np.abs(motion.frequency_rad_s / w0 - 1.0) <= 0.1 + 1e-12)


def test_amplitude_scale_multiplies_each_dof():
    base = ship_motion(ShipMotionSection(sea_state=3), None, 2, 2)
    scaled = ship_motion(ShipMotionSection(sea_state=3, amplitude_scale=(2.0, 5.0, 3.0, 0.0)), None, 2, 2)
    t = np.array([3.0, 40.0])
    np.testing.assert_allclose(scaled.dof(t), base.dof(t) * [2.0, 5.0, 3.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("sea_state", [None, 0])
def test_calm_sea_is_no_motion(sea_state):
    section = ShipMotionSection(sea_state=sea_state)
    assert not section.enabled
    assert ship_motion(section, None, 1, 3) is None
    assert ShipMotionSection().enabled                  # the default (from_wind) is not a calm sea


@pytest.mark.parametrize("components", [1, 4])
def test_flight_does_not_depend_on_its_batch(components):
    seeds = np.random.SeedSequence(2024).spawn(3)
    section = ShipMotionSection(sea_state=5, components=components)
    batch = ship_motion(section, None, [np.random.default_rng(s) for s in seeds], 3)
    t = np.array([1.0, 55.5, 310.0])
    q = batch.dof(t)
    for i, seed in enumerate(seeds):
        alone = ship_motion(section, None, [np.random.default_rng(seed)], 1)
        np.testing.assert_array_equal(alone.dof(t[i:i + 1]), q[i:i + 1])
    assert not np.allclose(q[0], q[1])                    # flights get their own phases


def test_dof_time_shapes_agree():
    motion = ship_motion(ShipMotionSection(sea_state=4, components=3), None, 9, 3)
    t = np.array([[0.0, 10.0], [5.0, 2.0], [7.0, 100.0]])
    q = motion.dof(t)
    assert q.shape == (3, 2, 4)
    np.testing.assert_allclose(q[:, 1], motion.dof(t[:, 1]), atol=1e-15)
    np.testing.assert_allclose(motion.dof(5.0), motion.dof(np.full(3, 5.0)), atol=1e-15)


def test_pose_rotation_matches_zyx_euler_and_signs():
    motion = ship_motion(ShipMotionSection(sea_state=6, amplitude_scale=(1, 20, 20, 20)), None, 4, 6)
    t = np.linspace(0.0, 30.0, 6)
    translation, rot = motion.pose(t)
    heave, roll, pitch, yaw = motion.dof(t).T
    expected = Rotation.from_euler("ZYX", np.stack([yaw, pitch, roll], axis=1)).as_matrix()
    np.testing.assert_allclose(rot, expected, atol=1e-12)
    np.testing.assert_allclose(translation, np.stack([0 * heave, 0 * heave, heave], axis=1), atol=0)
    # roll + = starboard (y < 0) down; pitch + = bow (x > 0) down; yaw + = bow to port (y > 0)
    roll_only = Rotation.from_euler("ZYX", [[0.0, 0.0, 0.1]]).as_matrix()[0]
    pitch_only = Rotation.from_euler("ZYX", [[0.0, 0.1, 0.0]]).as_matrix()[0]
    yaw_only = Rotation.from_euler("ZYX", [[0.1, 0.0, 0.0]]).as_matrix()[0]
    assert (roll_only @ [0.0, -10.0, 0.0])[2] < 0
    assert (pitch_only @ [70.0, 0.0, 0.0])[2] < 0
    assert (yaw_only @ [70.0, 0.0, 0.0])[1] > 0


def test_to_ship_frame_inverts_pose():
    """A point and camera fixed to the ship: moved into the world by pose, back by to_ship_frame (round trip)."""
    n = 5
    rng = np.random.default_rng(0)
    motion = ship_motion(ShipMotionSection(sea_state=6, components=3, amplitude_scale=(2, 10, 10, 10)), None, 8, n)
    t = rng.uniform(0, 500, n)
    p_ship = rng.uniform(-70, 70, (n, 3))
    r_ship = Rotation.random(n, random_state=1).as_matrix()
    translation, rot = motion.pose(t)
    p_world = np.einsum("nij,nj->ni", rot, p_ship) + translation
    r_world = rot @ r_ship
    back_p, back_r = motion.to_ship_frame(t, p_world, r_world)
    np.testing.assert_allclose(back_p, p_ship, atol=1e-9)
    np.testing.assert_allclose(back_r, r_ship, atol=1e-12)
    fwd_p, fwd_r = motion.to_world_frame(t, back_p, back_r)
    np.testing.assert_allclose(fwd_p, p_world, atol=1e-9)
    np.testing.assert_allclose(fwd_r, r_world, atol=1e-12)
    # the moving ship: a world-fixed point is not ship-fixed
    later_p, _ = motion.to_ship_frame(t + 3.0, p_world, r_world)
    assert np.all(np.linalg.norm(later_p - p_ship, axis=1) > 1e-3)


@pytest.mark.parametrize("bad, key", [({"sea_state": 7}, "motion.sea_state"),
                                      ({"sea_state": -1}, "motion.sea_state"),
                                      ({"components": 0}, "motion.components"),
                                      ({"amplitude_scale": [1, 1, -2, 1]}, "motion.amplitude_scale"),
                                      ({"wave_height_m": 2}, "motion.wave_height_m")])
def test_bad_config_names_the_key(bad, key):
    from pydantic import BaseModel

    class Holder(BaseModel):
        motion: ShipMotionSection = ShipMotionSection()

    with pytest.raises(InputError, match=key):
        parse_model(Holder, {"motion": bad}, "experiment.yaml")
    with pytest.raises(ValueError, match="sea_state"):
        sea_state_figures(7)


def test_from_wind_each_flight_swings_in_the_sea_of_its_own_wind():
    from wrp_eval.ship.motion import (
        ShipMotionSection,
        sea_state_figures,
        ship_motion,
        wind_wave_height_m,
        wmo_sea_state,
    )
    # Pierson-Moskowitz fully developed sea: Hs = 0.21 (1.06 U10)^2 / g
    speeds = np.array([0.0, 6.0, 12.0])
    hs = wind_wave_height_m(speeds)
    assert hs == pytest.approx(0.21 * (1.06 * speeds) ** 2 / 9.81)
    assert wmo_sea_state(hs).tolist() == [0, 3, 5]
    motion = ship_motion(ShipMotionSection(), None, 4, 3, speeds)   # the default section: from_wind
    assert motion.sea_state.tolist() == [0, 3, 5] and motion.flights(np.array([2])).sea_state.tolist() == [5]
    row4, freqs = sea_state_figures(4)
    assert motion.amplitudes() == pytest.approx(hs[:, None] / 2.5 * row4[None, :])
    assert motion.frequencies()[1:] == pytest.approx(np.tile(freqs, (2, 1)))            # the table's, in a wind
    assert np.all(motion.dof(np.linspace(0, 60, 7)[None, :].repeat(3, 0))[0] == 0.0)     # calm: still
    alone = ship_motion(ShipMotionSection(), None, [np.random.default_rng(4).spawn(3)[2]], 1, speeds[2:])
    assert np.array_equal(alone.dof(17.0)[0], motion.dof(17.0)[2])                      # batch-independent


def test_from_wind_needs_the_wind_and_unknown_words_are_refused():
    from wrp_eval.ship.motion import ShipMotionSection, ship_motion
    with pytest.raises(ValueError, match="wind speed"):
        ship_motion(ShipMotionSection(), None, 0, 2)
    with pytest.raises(ValueError):
        ShipMotionSection(sea_state="windy")
