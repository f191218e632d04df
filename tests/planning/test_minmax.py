import numpy as np
import pytest

from wrp_eval.planning.minmax import _importance, maximise, minimise, set_metrics
from wrp_eval.planning.reconstructability import SlotTable, pair_reconstructability_points


def _toy():
    """One sample at the origin (normal +z) seen by three views."""
    points, normals = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    views = np.array([[12.0, 0, 20.0], [-12.0, 0, 20.0], [0.0, 14.0, 18.0]])
    visible = np.ones((3, 1), dtype=bool)
    table = SlotTable.build(visible, points, normals, views, 60.0, cache=True)

    def q(i, j):
        return pair_reconstructability_points(points, normals, views[[i]], views[[j]], 60.0)[0]
    return table, q


def test_minimise_removes_what_the_threshold_allows():
    table, q = _toy()
    # equal importance (one sample): view 0 goes first; then removing 1 or 2 would leave h = 0
    res = minimise(table, np.ones(3, bool), np.array([q(1, 2)]))
    assert res.active.tolist() == [False, True, True]
    assert res.h[0] == pytest.approx(q(1, 2), rel=1e-5)
    res = minimise(table, np.ones(3, bool), np.array([q(1, 2) * 1.01]))   # nothing can go
    assert res.active.all()


def test_unreachable_threshold_keeps_everything_and_is_capped():
    table, q = _toy()
    res = minimise(table, np.ones(3, bool), np.array([100.0]))
    assert res.active.all()
    assert res.threshold[0] == pytest.approx(q(0, 1) + q(0, 2) + q(1, 2), rel=1e-5)


def test_maximise_swaps_to_a_better_view_and_keeps_the_count():
    points, normals = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    # views 0 and 1 almost coincide (tiny triangulation angle); view 2 gives a good angle with view 0
    views = np.array([[10.0, 0, 20.0], [10.5, 0, 20.0], [-10.0, 0, 20.0]])
    table = SlotTable.build(np.ones((3, 1), bool), points, normals, views, 60.0)
    active = np.array([True, True, False])
    new, h, swaps = maximise(table, active, np.zeros(1), lambda v: np.array([2]), rounds=2)
    assert new.sum() == 2 and new[2] and swaps == 1
    assert h[0] == pytest.approx(table.h(new)[0])
    assert h[0] > table.h(active)[0]


def test_metrics_definitions_on_the_toy():
    table, q = _toy()
    active = np.ones(3, bool)
    H, R = set_metrics(table, active, np.array([q(1, 2)]))
    assert H == pytest.approx(q(0, 1) + q(0, 2) + q(1, 2), rel=1e-5)
    # without view v the sample keeps the pair of the other two: redundant iff that pair >= threshold
    pair_without = [q(1, 2), q(0, 2), q(0, 1)]
    assert R == pytest.approx(np.mean([p >= q(1, 2) - 1e-9 for p in pair_without]))


@pytest.mark.parametrize("ship", ["stylized", "cruise"])
@pytest.mark.parametrize("method", ["ours", "zhou2020"])
def test_min_max_invariants_on_planned_ships(plans, ship, method):
    r = plans[(ship, method)]
    m = r.metrics
    assert np.all(r.h >= r.thresholds - 1e-6)                     # every sample above its threshold
    assert m["n_views"] == m["n_views_after_min"]                  # maximisation keeps the count
    assert m["H"] >= m["H_min_only"] - 1e-9                        # and does not lower H(S, U)
    assert m["samples_below_asked_threshold"] <= int(np.sum(r.thresholds < _asked(r) - 1e-9))


def _asked(r):
    per_face = r.metrics["per_face"]
    thr = np.array([per_face[n]["threshold"] for n in ("bow", "stern", "port", "starboard", "top")])
    return thr[r.samples.face]


def test_ours_scales_thresholds_and_radii_with_complexity(plans):
    pf = plans[("stylized", "ours")].metrics["per_face"]
    # port/starboard are the most complex faces of the stylized fixture: threshold 0.6, smallest radius
    assert pf["port"]["threshold"] == pytest.approx(0.6)
    assert pf["top"]["threshold"] == pytest.approx(0.6 * 0.054 / 0.119)
    assert pf["top"]["radius_m"] == pytest.approx(pf["port"]["radius_m"] * 0.119 / 0.054)
    zf = plans[("stylized", "zhou2020")].metrics["per_face"]
    assert {f["threshold"] for f in zf.values()} == {0.6}
    assert len({round(f["radius_m"], 9) for f in zf.values()}) == 1


def test_importance_is_the_largest_inverse_h_of_the_samples_a_view_sees():
    rng = np.random.default_rng(3)
    visible = rng.random((30, 200)) < 0.2
    visible[7] = False                                                    # a view that sees no sample
    points, normals = rng.normal(size=(200, 3)), np.tile([0.0, 0.0, 1.0], (200, 1))
    table = SlotTable.build(visible, points, normals, rng.normal(size=(30, 3)) * 20.0, 60.0)
    h = rng.random(200) * 3.0
    h[rng.random(200) < 0.1] = 0.0
    for view in range(30):
        samples, _ = table.entries(view)
        hs = h[samples]
        expected = float(np.max(np.where(hs > 0, 1.0 / np.maximum(hs, 1e-300), np.inf))) if samples.size else 0.0
        assert _importance(table, h, view) == expected
