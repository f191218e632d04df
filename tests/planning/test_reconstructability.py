import numpy as np
import pytest

from wrp_eval.planning.reconstructability import (
    SlotTable,
    masked_first_columns,
    pair_reconstructability,
    pair_reconstructability_points,
    set_reconstructability,
)


def _q_by_hand(alpha, d, d_max, theta_m):
    w1 = 1 / (1 + np.exp(-32 * (alpha - np.pi / 16)))
    w2 = 1 - min(d / d_max, 1)
    w3 = 1 - 1 / (1 + np.exp(-8 * (alpha - np.pi / 4)))
    return w1 * w2 * w3 * np.cos(theta_m)


@pytest.mark.parametrize("alpha", [np.pi / 16, np.pi / 8, np.pi / 4, np.pi / 2])
def test_symmetric_pair_matches_the_formula(alpha):
    d, d_max = 30.0, 60.0
    s, n = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    va = d * np.array([[np.sin(alpha / 2), 0, np.cos(alpha / 2)]])
    vb = d * np.array([[-np.sin(alpha / 2), 0, np.cos(alpha / 2)]])
    q = pair_reconstructability_points(s, n, va, vb, d_max)[0]
    assert q == pytest.approx(_q_by_hand(alpha, d, d_max, alpha / 2))


def test_at_alpha1_w1_is_one_half():
    alpha, d, d_max = np.pi / 16, 10.0, 40.0
    w3 = 1 - 1 / (1 + np.exp(-8 * (np.pi / 16 - np.pi / 4)))
    s, n = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    va = d * np.array([[np.sin(alpha / 2), 0, np.cos(alpha / 2)]])
    vb = d * np.array([[-np.sin(alpha / 2), 0, np.cos(alpha / 2)]])
    q = pair_reconstructability_points(s, n, va, vb, d_max)[0]
    assert q == pytest.approx(0.5 * 0.75 * w3 * np.cos(alpha / 2))


def test_larger_distance_and_angle_are_used_and_far_views_give_nothing():
    s, n = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    va = np.array([[0.0, 0.0, 10.0]])                        # theta 0, d 10
    vb = 20.0 * np.array([[np.sin(0.5), 0, np.cos(0.5)]])    # theta 0.5 rad, d 20
    q = pair_reconstructability_points(s, n, va, vb, 40.0)[0]
    assert q == pytest.approx(_q_by_hand(0.5, 20.0, 40.0, 0.5))
    assert pair_reconstructability_points(s, n, va, vb * 3, 40.0)[0] == 0.0    # d_m = 60 >= d_max


def test_set_reconstructability_sums_the_pairs():
    s, n = np.zeros(3), np.array([0.0, 0.0, 1.0])
    views = np.array([[10, 0, 20.0], [-10, 0, 20.0], [0, 12, 18.0]])
    pairs = [(0, 1), (0, 2), (1, 2)]
    expected = sum(pair_reconstructability_points(s[None], n[None], views[[i]], views[[j]], 50.0)[0]
                   for i, j in pairs)
    assert set_reconstructability(s, n, views, 50.0) == pytest.approx(expected)


def test_slot_table_matches_the_reference_and_cache():
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(-5, 5, (6, 2)), np.zeros(6)])
    normals = np.tile([0.0, 0.0, 1.0], (6, 1))
    positions = np.column_stack([rng.uniform(-30, 30, (9, 2)), rng.uniform(10, 40, 9)])
    visible = rng.random((9, 6)) < 0.6
    active = rng.random(9) < 0.7
    plain = SlotTable.build(visible, points, normals, positions, 80.0)
    cached = SlotTable.build(visible, points, normals, positions, 80.0, cache=True)
    for j in range(6):
        seen = np.flatnonzero(visible[:, j] & active)
        ref = set_reconstructability(points[j], normals[j], positions[seen], 80.0) if len(seen) > 1 else 0.0
        assert plain.h(active)[j] == pytest.approx(ref)
        assert cached.h(active)[j] == pytest.approx(ref, rel=1e-5)


@pytest.mark.parametrize("rows, columns, share", [(300, 40, 0.3), (50, 60, 0.05), (200, 12, 0.9), (7, 5, 0.0),
                                                  (7, 5, 1.0)])
def test_masked_first_columns_is_the_stable_argsort_it_replaces(rows, columns, share):
    mask = np.random.default_rng(rows + columns).random((rows, columns)) < share
    for width in {1, max(int(mask.sum(axis=1).max()), 1), columns}:
        assert np.array_equal(masked_first_columns(mask, width),
                              np.argsort(~mask, axis=1, kind="stable")[:, :width])


def _numpy_q_rows(table: SlotTable, samples: np.ndarray, slots: np.ndarray) -> np.ndarray:
    """q (T, M) of the view in (samples[t], slots[t]) paired with every slot of its sample (0 for pads and itself):
    the numpy rows the cache was built from before the compiled pass (session 18), kept as the reference."""
    ray_a = table.ray[samples, slots]
    cos_alpha = np.einsum("ti,tmi->tm", ray_a, table.ray[samples])
    d_pair = np.maximum(table.dist[samples, slots][:, None], table.dist[samples])
    cos_t = np.minimum(table.cos_theta[samples, slots][:, None], table.cos_theta[samples])
    q = pair_reconstructability(cos_alpha, np.where(np.isfinite(d_pair), d_pair, table.d_max), cos_t, table.d_max)
    q[table.slot_view[samples] < 0] = 0.0
    q[np.arange(len(samples)), slots] = 0.0
    return q


def test_the_cache_holds_every_views_q_row_and_zeros_in_padding_rows():
    """The compiled pair cache (session 18) against the numpy rows it was built from before: bit-equal."""
    rng = np.random.default_rng(5)
    points = rng.normal(size=(120, 3)) * 10.0
    normals = rng.normal(size=(120, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    positions = rng.normal(size=(25, 3)) * 30.0
    visible = rng.random((25, 120)) < 0.3
    cached = SlotTable.build(visible, points, normals, positions, 80.0, cache=True)
    plain = SlotTable.build(visible, points, normals, positions, 80.0)
    s, k = np.nonzero(plain.slot_view >= 0)
    assert cached.cache is not None and cached.cache.dtype == np.float32
    assert np.array_equal(cached.cache[s, k], _numpy_q_rows(plain, s, k).astype(np.float32))
    assert not cached.cache[plain.slot_view < 0].any()


def _numpy_layout(visible, points, normals, positions):
    """The vectorised construction of SlotTable's arrays the compiled pass replaced (session 18): the reference."""
    n_v, n_s = visible.shape
    si, vi = np.nonzero(visible.T)
    counts = np.bincount(si, minlength=n_s)
    width = max(int(counts.max(initial=0)), 1)
    slot = np.arange(si.size) - np.concatenate([[0], np.cumsum(counts)[:-1]])[si]
    slot_view = np.full((n_s, width), -1, dtype=np.int64)
    slot_view[si, slot] = vi
    rel = positions[vi] - points[si]
    d = np.linalg.norm(rel, axis=1)
    ray, dist, cos_theta = np.zeros((n_s, width, 3)), np.full((n_s, width), np.inf), np.zeros((n_s, width))
    ray[si, slot], dist[si, slot] = rel / d[:, None], d
    cos_theta[si, slot] = np.einsum("ni,ni->n", ray[si, slot], normals[si])
    order = np.argsort(vi, kind="stable")
    view_ptr = np.concatenate([[0], np.cumsum(np.bincount(vi, minlength=n_v))])
    return slot_view, ray, dist, cos_theta, view_ptr, si[order], slot[order]


@pytest.mark.parametrize("n_v, n_s, share", [(25, 120, 0.3), (40, 7, 0.9), (6, 30, 0.0), (300, 500, 0.02)])
def test_the_compiled_layout_is_the_numpy_layout_bit_for_bit(n_v, n_s, share):
    """Every array bit for bit, but cos_theta to the last bit (identical for the proxy's axis-aligned normals:
    the plans at gsd 7.5 / 4 / 2.5 / 1.85 mm were checked identical, caches included)."""
    rng = np.random.default_rng(n_v + n_s)
    points = rng.normal(size=(n_s, 3)) * 10.0
    normals = rng.normal(size=(n_s, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    positions = rng.normal(size=(n_v, 3)) * 30.0
    visible = rng.random((n_v, n_s)) < share
    table = SlotTable.build(visible, points, normals, positions, 80.0)
    got = (table.slot_view, table.ray, table.dist, table.cos_theta, table.view_ptr, table.view_sample, table.view_slot)
    ref = _numpy_layout(visible, points, normals, positions)
    for k, (mine, expected) in enumerate(zip(got, ref, strict=True)):
        assert mine.shape == expected.shape
        if k == 3:      # cos_theta: einsum adds the three products in its own (SIMD) order, the kernel in index
            np.testing.assert_allclose(mine, expected, rtol=0, atol=4e-16)     # order: the last bit may differ
        else:
            assert np.array_equal(mine, expected)
