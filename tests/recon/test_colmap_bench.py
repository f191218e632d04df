"""The COLMAP time-against-width bench's arithmetic (no COLMAP run): the per-set projection and the set count."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.colmap_bench import project, validation_set_count
from wrp_eval.recon.scenarios import reference_capture_set


def test_each_stage_of_the_full_set_scales_with_its_own_width_ratio():
    full = {"render_s": 20.0, "features_s": 30.0, "matching_s": 90.0, "mapping_s": 40.0}
    sweep = {800: {"render_s": 2.0, "features_s": 3.0, "matching_s": 4.0, "mapping_s": 3.0},
             1600: {"render_s": 8.0, "features_s": 9.0, "matching_s": 4.0, "mapping_s": 6.0}}
    out = project(full, sweep)
    assert out[800] == pytest.approx(180.0)
    assert out[1600] == pytest.approx(20 * 4 + 30 * 3 + 90 * 1 + 40 * 2)


def test_validation_set_count_follows_the_set_list():
    cs = reference_capture_set(30)
    n = len(cs)
    path = FlightPath(cs.positions, cs.yaw, cs.pitch, np.zeros(n, int), np.zeros(n, int), np.zeros(n, int))
    # 27 sets of the path + 2 modes x 3 winds x 2 flights + 2 other presets x 2 + 2 winds >= 8 x 2 recorded
    # blurs + 2 repeats of the reference
    assert validation_set_count(path, own_preset="consumer") == 27 + 12 + 4 + 4 + 2
    assert validation_set_count(path, own_preset="px4-sitl") == 27 + 12 + 6 + 4 + 2
