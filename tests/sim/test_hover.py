"""The analytic hover balance the simulator's hover is checked against."""

import numpy as np
import pytest

from wrp_eval.sim.config import SimSection
from wrp_eval.sim.hover import airframe_only, analytic_hover_balance
from wrp_eval.sim.navigation import NavigationSection, navigation_params
from wrp_eval.sim.simple_wind import ConstantWind
from wrp_eval.sim.vehicle import PHANTOM4


def test_balance_is_the_weight_drag_triangle_and_follows_the_wind_side():
    section = SimSection()
    ship_heading = 90.0                                                   # bow east
    bow = analytic_hover_balance(ConstantWind.blowing_from(10.0, 90.0, ship_heading).vector, section)
    beam = analytic_hover_balance(ConstantWind.blowing_from(10.0, 0.0, ship_heading).vector, section)
    for b in (bow, beam):
        assert np.tan(np.radians(b["tilt_deg"])) * PHANTOM4.weight_n == pytest.approx(b["drag_force_n"])
        assert b["thrust_n"] == pytest.approx(np.hypot(b["drag_force_n"], PHANTOM4.weight_n))
    # from the bow the wind meets the nose (breadth W), from the side the flank (length L > W): more drag
    assert beam["drag_force_n"] > bow["drag_force_n"] > 0.0
    calm = analytic_hover_balance(np.zeros(3), section)
    assert calm["drag_force_n"] == 0.0 and calm["thrust_n"] == pytest.approx(PHANTOM4.weight_n)


def test_airframe_only_changes_only_the_navigation_to_the_truth():
    section = SimSection(gains="stiff", navigation=NavigationSection(preset="rtk"))
    assert not navigation_params(section.navigation).is_ideal
    only = airframe_only(section)
    assert navigation_params(only.navigation).is_ideal
    assert only.model_dump(exclude={"navigation"}) == section.model_dump(exclude={"navigation"})
    assert section.navigation.preset == "rtk"                            # the caller's section is untouched
