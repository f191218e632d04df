import numpy as np

from wrp_eval.sim.simple_wind import ConstantWind, mean_wind_vector


def test_mean_wind_vector_blows_from_the_given_direction():
    assert np.allclose(mean_wind_vector(10.0, 0.0), [-10.0, 0.0, 0.0])
    assert np.allclose(mean_wind_vector(4.0, 90.0), [0.0, -4.0, 0.0])
    assert ConstantWind([1, 2, 3]).velocity(np.zeros((2, 3)), 0.0).shape == (2, 3)
