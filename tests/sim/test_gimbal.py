"""The camera gimbal: follow mode on a level airframe, the first-order stabilisation loop (exact zero-order-hold
discretisation of dx/dt = 2 pi f (u - x): x_k+1 = x_k + (1 - exp(-2 pi f dt)) (u - x_k)), its rate limit and
the mechanical stops."""

import numpy as np
import pytest
from pydantic import ValidationError
from scipy.spatial.transform import Rotation

from wrp_eval.sim.gimbal import Gimbal, GimbalParams, GimbalSection, airframe_angles

DT = 0.05     # the position-loop chunk, 20 Hz


def _airframe(yaw_deg: float = 0.0, nose_down_deg: float = 0.0, roll_right_deg: float = 0.0) -> np.ndarray:
    """(1, 3, 3) world-from-body, Z-Y-X (yaw, pitch, roll): positive pitch lowers the nose (body x towards -z),
    positive roll lowers the right wing (body y, the left wing, goes up)."""
    return Rotation.from_euler("ZYX", [yaw_deg, nose_down_deg, roll_right_deg], degrees=True).as_matrix()[None]


def _params(**update) -> GimbalParams:
    return GimbalParams.of(GimbalSection(**update))


def test_airframe_angles_are_the_elevations_of_nose_and_left_wing():
    nose, wing = airframe_angles(np.concatenate([_airframe(30.0, 10.0, 0.0), _airframe(-70.0, 0.0, 20.0)]))
    assert np.degrees(nose) == pytest.approx([-10.0, 0.0])
    assert np.degrees(wing) == pytest.approx([0.0, 20.0])


def test_a_level_airframe_gets_the_wanted_pitch_and_no_roll():
    params = _params()
    rot = np.concatenate([_airframe(40.0), _airframe(-120.0)])
    wanted = np.radians([-20.0, -90.0])
    gimbal = Gimbal(params, rot, wanted, DT)
    att = gimbal.step(rot, np.radians([40.0, -120.0]), wanted)
    assert att.pitch == pytest.approx(wanted, abs=1e-12)
    assert att.roll == pytest.approx([0.0, 0.0], abs=1e-12)
    assert att.yaw == pytest.approx(np.radians([40.0, -120.0]))      # follow mode: the airframe's heading
    assert not att.saturated.any()                                     # -90 is the stop itself, not beyond it


def test_a_nose_down_airframe_is_compensated_by_the_pitch_joint():
    rot = _airframe(0.0, 15.0, 0.0)                                    # nose 15 deg down (forward flight)
    gimbal = Gimbal(_params(), rot, np.radians([-30.0]), DT)
    assert np.degrees(gimbal.joint[0]) == pytest.approx([-15.0, 0.0])  # joint -30 + 15
    assert np.degrees(gimbal.step(rot, np.zeros(1), np.radians([-30.0]), advance=False).pitch) == pytest.approx([-30.0])


def test_the_residual_roll_decays_as_the_first_order_loop_once_below_the_rate_limit():
    f_hz = 10.0
    params = _params(bandwidth_hz=f_hz)
    level, rolled = _airframe(), _airframe(roll_right_deg=20.0)
    wanted = np.radians([-20.0])
    gimbal = Gimbal(params, level, wanted, DT)                       # settled on the level airframe
    roll = []
    for _ in range(12):                                               # the airframe rolls 20 deg and stays
        roll.append(gimbal.step(rolled, np.zeros(1), wanted).roll[0])
    roll = np.degrees(np.array(roll))
    gain = 1.0 - np.exp(-2.0 * np.pi * f_hz * DT)
    max_step = 90.0 * DT                                              # 90 deg/s
    before = np.concatenate([[20.0], roll[:-1]])                      # the residual before each step
    limited = gain * before > max_step
    assert limited[0] and not limited[-1]
    # rate-limited steps move the joint by exactly the limit, the others by the loop's gain
    assert (before - roll)[limited] == pytest.approx(np.full(limited.sum(), max_step))
    assert roll[~limited] == pytest.approx(before[~limited] * np.exp(-2.0 * np.pi * f_hz * DT), rel=1e-9)
    assert np.all(np.abs(np.diff(np.concatenate([[20.0], roll]))) <= max_step + 1e-9)
    assert abs(roll[-1]) < 1e-3 and np.all(roll >= 0.0)               # no overshoot: a first-order loop


def test_without_rate_limit_the_roll_follows_the_closed_form_exponential():
    f_hz = 2.0
    params = _params(bandwidth_hz=f_hz, rate_limit_deg_s=1e6)
    level, rolled = _airframe(), _airframe(roll_right_deg=20.0)
    wanted = np.radians([-20.0])
    gimbal = Gimbal(params, level, wanted, DT)
    k = np.arange(1, 9)
    roll = []
    for _ in k:
        roll.append(np.degrees(gimbal.step(rolled, np.zeros(1), wanted).roll[0]))
    assert np.array(roll) == pytest.approx(20.0 * np.exp(-2.0 * np.pi * f_hz * DT * k), rel=1e-9)


def test_the_rate_limit_bounds_every_joint_move():
    params = _params(rate_limit_deg_s=30.0)
    rot = _airframe()
    gimbal = Gimbal(params, rot, np.radians([0.0]), DT)
    joints = []
    for _ in range(10):                                               # a new view 60 deg lower
        gimbal.step(rot, np.zeros(1), np.radians([-60.0]))
        joints.append(gimbal.joint[0, 0])
    steps = np.degrees(np.diff(np.concatenate([[0.0], joints])))
    assert steps[:5] == pytest.approx(np.full(5, -30.0 * DT))         # slewing at the limit
    assert np.all(np.abs(steps) <= 30.0 * DT + 1e-9)


def test_the_joints_stop_at_their_mechanical_range():
    params = _params()                                                # pitch -90..+30, roll +-35 (DJI)
    level = _airframe()
    gimbal = Gimbal(params, level, np.radians([40.0]), DT)
    att = gimbal.step(level, np.zeros(1), np.radians([40.0]), advance=False)
    assert np.degrees(att.pitch) == pytest.approx([30.0]) and att.saturated.tolist() == [True]
    # rolled 45 deg: the roll joint stops at -35 deg, 10 deg of roll reach the camera
    rolled = _airframe(roll_right_deg=45.0)
    gimbal = Gimbal(params, level, np.radians([-20.0]), DT)
    for _ in range(30):
        att = gimbal.step(rolled, np.zeros(1), np.radians([-20.0]))
    assert np.degrees(gimbal.joint[0, 1]) == pytest.approx(-35.0)
    assert np.degrees(att.roll) == pytest.approx([10.0]) and att.saturated.tolist() == [True]


def test_the_section_rejects_bad_ranges_and_rates():
    with pytest.raises(ValidationError, match="pitch_range_deg"):
        GimbalSection(pitch_range_deg=(30.0, -90.0))
    with pytest.raises(ValidationError, match="bandwidth_hz"):
        GimbalSection(bandwidth_hz=0.0)
    with pytest.raises(ValidationError, match="rate_limit_deg_s"):
        GimbalSection(rate_limit_deg_s=-1.0)
    with pytest.raises(ValidationError, match="unknown"):
        GimbalSection(unknown=1.0)
