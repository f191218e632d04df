"""Incremental registration of the synthetic oracle (``oracle.synthetic.registration: incremental``).

Known by construction: a view registers only on 2D-3D matches to points that two registered views already
triangulated (as COLMAP's incremental mapper), so a chain of views whose neighbours overlap pairwise but
never three at a time stops at the seed pair, while the connected-component model registers it all.
"""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.camera import yaw_pitch_towards
from wrp_eval.recon.config import OracleSection, SyntheticOracleSection
from wrp_eval.recon.synthetic import SyntheticOracle, register_incremental
from wrp_eval.sim.captures import CaptureSet

from .conftest import make_box, ring_views


def _section(registration: str, **kw) -> OracleSection:
    return OracleSection(synthetic=SyntheticOracleSection(rays_x=40, rays_y=27, registration=registration, **kw))


def _wall_chain(step_m: float, views: int = 8) -> CaptureSet:
    """Views 12 m off the +y face (y = 3) of a long wall, level, looking square-on, ``step_m`` apart.

    The footprint of a view is 2 * 12 * tan(21.9 deg) = 9.65 m wide: with a 6 m step neighbours share 3.65 m
    (38 %) and no point is seen by three views; with a 3.4 m step every point is seen by 2-3 views."""
    x = (np.arange(views) - (views - 1) / 2) * step_m
    positions = np.column_stack([x, np.full(views, 15.0), np.full(views, 8.0)])
    targets = np.column_stack([x, np.full(views, 3.0), np.full(views, 8.0)])
    yaw, pitch = yaw_pitch_towards(positions, targets)
    return CaptureSet(positions, yaw, pitch, np.arange(views))


@pytest.fixture(scope="module")
def wall():
    return make_box((90.0, 6.0, 20.0), (0.0, 0.0, 8.0))  # z from -2 to 18, long +-y faces


def test_chain_without_triple_overlap_registers_only_the_seed_pair(wall):
    cs = _wall_chain(6.0)
    comp = SyntheticOracle(_section("components")).evaluate(cs, wall, seed=0)
    inc = SyntheticOracle(_section("incremental")).evaluate(cs, wall, seed=0)
    # every neighbour pair is linked: one component of 8
    assert comp.registered_views == 8 and not comp.failed
    # the third view of the chain sees none of the points the seed pair triangulated
    assert inc.registered_views == 2 and inc.failed
    order = inc.extra["registration_order"]
    assert len(order) == 2 and abs(order[0] - order[1]) == 1  # the seed is a neighbour pair
    assert "fewer than 3" in inc.reason


def test_chain_with_triple_overlap_registers_every_view(wall):
    inc = SyntheticOracle(_section("incremental")).evaluate(_wall_chain(3.4), wall, seed=0)
    assert inc.registered_views == 8 and not inc.failed
    order = inc.extra["registration_order"]
    assert sorted(order) == list(range(8))
    # it grows along the chain: every view after the seed pair is a neighbour of an earlier one
    assert all(min(abs(v - w) for w in order[:k]) == 1 for k, v in enumerate(order) if k >= 2)


def test_well_covered_box_registers_every_view(box_on_water):
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 16, target=(0, 0, 1.5))
    comp = SyntheticOracle(_section("components")).evaluate(cs, box_on_water, seed=0)
    inc = SyntheticOracle(_section("incremental")).evaluate(cs, box_on_water, seed=0)
    assert inc.registered_views == 32 and not inc.failed and inc.reason == ""
    assert sorted(inc.extra["registration_order"]) == list(range(32))
    assert inc.completeness > 0.95
    # the same views registered -> the same reconstruction as the component model
    assert inc.error_m == comp.error_m and inc.n_points == comp.n_points


def test_incremental_registration_is_deterministic(box_on_water):
    cs = ring_views((0, 0, 0), 22.0, (3.0, 16.0), 12, target=(0, 0, 1.5))
    a = SyntheticOracle(_section("incremental")).evaluate(cs, box_on_water, seed=3)
    b = SyntheticOracle(_section("incremental")).evaluate(cs, box_on_water, seed=3)
    assert a.extra["registration_order"] == b.extra["registration_order"]
    for field in ("registered_views", "error_m", "completeness", "n_points"):
        assert getattr(a, field) == getattr(b, field)


def _two_view_seed_and_a_third(m_rays: int, same_ray: bool = False):
    """Hand-built pairs: views 0 and 1 triangulate the 20 hits of view 0 (rays 0..19 of view 1); view 2
    matches the first ``m_rays`` of them (on distinct rays of view 2, or all on one ray)."""
    hits = np.arange(20)
    hit = np.concatenate([hits, hits[:m_rays]])
    partner = np.concatenate([np.full(20, 1), np.full(m_rays, 2)])
    grid = np.concatenate([100 + hits, 200 + (np.zeros(m_rays, int) if same_ray else hits[:m_rays])])
    order = np.argsort(hit, kind="stable")  # pairs sorted by hit, as the oracle builds them
    triangulates = np.concatenate([np.ones(20, bool), np.zeros(m_rays, bool)])
    return dict(n_views=3, n_hits=20, hit_view=np.zeros(20, int), hit=hit[order], partner=partner[order],
                matchable=np.ones(len(hit), bool), triangulates=triangulates[order], grid_index=grid[order],
                rays_per_view=100)


@pytest.mark.parametrize("m_rays, same_ray, registered", [(5, False, True), (4, False, False),
                                                         (10, True, False)])
def test_registration_threshold_counts_distinct_rays_on_triangulated_points(m_rays, same_ray, registered):
    mask, order = register_incremental(**_two_view_seed_and_a_third(m_rays, same_ray), min_rays=5)
    assert order[:2] == [0, 1]
    assert mask.tolist() == [True, True, registered]
    assert order == ([0, 1, 2] if registered else [0, 1])


def test_seed_pair_needs_the_threshold_too():
    mask, order = register_incremental(**_two_view_seed_and_a_third(5), min_rays=21)
    assert not mask.any() and order == []
