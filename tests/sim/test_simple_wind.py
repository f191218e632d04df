import numpy as np

from wrp_eval.sim.simple_wind import ConstantWind


def test_constant_wind_blows_from_the_compass_bearing_in_the_ship_frame():
    # the project's one convention (wrp_eval.frames): compass bearing the wind blows FROM
    np.testing.assert_allclose(ConstantWind.blowing_from(10.0, 0.0, 0.0).vector, [-10.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(ConstantWind.blowing_from(4.0, 90.0, 0.0).vector, [0.0, 4.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(ConstantWind.blowing_from(4.0, 90.0, 90.0).vector, [-4.0, 0.0, 0.0], atol=1e-12)
    assert ConstantWind([1, 2, 3]).velocity(np.zeros((2, 3)), 0.0).shape == (2, 3)
