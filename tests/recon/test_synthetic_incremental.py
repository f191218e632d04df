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


def _numpy_mapper(n, n_hits, hit_view, h, p, g, t, rays_per_view, ray_weight, seed, min_rays):
    """The vectorised-per-step mapper the compiled loop replaced (session 18), kept as the reference."""
    v_of = hit_view[h]
    registered, order = np.zeros(n, dtype=bool), []
    hit_ptr = np.searchsorted(h, np.arange(n_hits + 1))
    view_ptr = np.searchsorted(v_of, np.arange(n + 1))
    by_partner = np.argsort(p, kind="stable")
    partner_ptr = np.searchsorted(p[by_partner], np.arange(n + 1))
    tri_hit, corr_ray = np.zeros(n_hits, dtype=bool), np.zeros(n * rays_per_view, dtype=bool)
    corr_count = np.zeros(n)

    def distinct(idx):
        last = {int(x): i for i, x in enumerate(idx)}
        return idx[[last[int(x)] == i for i, x in enumerate(idx)]] if len(idx) else idx

    def register(v):
        registered[v] = True
        order.append(v)
        own = np.arange(view_ptr[v], view_ptr[v + 1])
        own = own[t[own] & registered[p[own]]]
        seen = by_partner[partner_ptr[v]:partner_ptr[v + 1]]
        seen = seen[t[seen] & registered[v_of[seen]]]
        new = np.concatenate([h[own], h[seen]])
        new = distinct(new[~tri_hit[new]])
        if len(new) == 0:
            return
        tri_hit[new] = True
        rays = np.concatenate([g[hit_ptr[x]:hit_ptr[x + 1]] for x in new])
        rays = distinct(rays[~corr_ray[rays]])
        corr_ray[rays] = True
        corr_count[:] += np.bincount(rays // rays_per_view, weights=ray_weight[rays], minlength=n)

    for v in seed:
        register(v)
    while True:
        cand = np.where(registered, -1, corr_count)
        v = int(np.argmax(cand))
        if cand[v] < min_rays:
            break
        register(v)
    return registered, order


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_compiled_mapper_registers_what_the_numpy_mapper_did(seed):
    """Random candidate pairs (many hits per view, repeated rays, weights): the same registered views in the same
    order as the per-step numpy mapper the compiled loop replaced (the threshold's stop: the tests above)."""
    rng = np.random.default_rng(seed)
    n, rays_per_view, n_hits = 14, 60, 3000
    share = 0.75 ** np.arange(n)                                             # later views see less
    hit_view = np.sort(rng.choice(n, n_hits, p=share / share.sum()))
    hit = np.sort(rng.integers(0, n_hits, 20000))
    partner = (hit_view[hit] + rng.integers(1, 4, hit.size)) % n             # neighbours in a ring
    grid = partner * rays_per_view + rng.integers(0, rays_per_view, hit.size)
    triangulates = rng.random(hit.size) < 0.6
    ray_weight = rng.uniform(0.2, 1.0, n * rays_per_view)
    hit_ray = hit_view * rays_per_view + rng.integers(0, rays_per_view, n_hits)
    mask, order = register_incremental(n, n_hits, hit_view, hit, partner, np.ones(hit.size, dtype=bool),
                                       triangulates, grid, rays_per_view, 30, hit_ray=hit_ray, ray_weight=ray_weight)
    pair_weight = np.minimum(ray_weight[hit_ray[hit]], ray_weight[grid])
    tri = np.bincount(hit_view[hit][triangulates] * n + partner[triangulates], weights=pair_weight[triangulates],
                      minlength=n * n).reshape(n, n)
    first = divmod(int(np.argmax(np.triu(tri + tri.T, k=1))), n)
    ref_mask, ref_order = _numpy_mapper(n, n_hits, hit_view, hit, partner, grid, triangulates, rays_per_view,
                                        ray_weight, first, 30)
    assert len(order) == n and order != sorted(order)                         # the picking order matters
    assert order == ref_order and np.array_equal(mask, ref_mask)


def test_nothing_triangulated_registers_nothing_even_with_a_zero_threshold():
    """No seed pair when no pair triangulates (the argmax of an all-zero table is the diagonal, not a pair)."""
    hit = np.arange(6)
    mask, order = register_incremental(3, 6, np.array([0, 0, 1, 1, 2, 2]), hit, (hit // 2 + 1) % 3,
                                       np.ones(6, dtype=bool), np.zeros(6, dtype=bool), np.arange(6), 4, 0)
    assert order == [] and not mask.any()
