"""ship.proxy_height_error (paper Table 1): the proxy's height is off by a fraction, the mesh is not."""

import numpy as np
import pytest

from wrp_eval.config import ExperimentConfig
from wrp_eval.errors import InputError
from wrp_eval.schema import parse_model
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.resolve import resolve_ship_full


def test_only_the_proxy_height_changes(tmp_path):
    true = resolve_ship_full(ShipSection(type="stylized"), cache_dir=tmp_path)
    low = resolve_ship_full(ShipSection(type="stylized", proxy_height_error=-0.2), cache_dir=tmp_path)
    assert low.proxy.height_m == pytest.approx(0.8 * true.proxy.height_m)
    assert (low.proxy.length_m, low.proxy.breadth_m) == (true.proxy.length_m, true.proxy.breadth_m)
    assert low.proxy.centers[4, 2] == pytest.approx(low.proxy.height_m)     # the top face moved down
    np.testing.assert_array_equal(low.mesh.vertices, true.mesh.vertices)     # the ship itself did not
    assert low.particulars == true.particulars


def test_an_impossible_height_error_is_refused():
    with pytest.raises(InputError, match="proxy_height_error"):
        parse_model(ExperimentConfig, {"ship": {"proxy_height_error": -1.0}}, "cfg.yaml")
