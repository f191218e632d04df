import numpy as np
import pytest

from wrp_eval.planning.config import PlanningSection
from wrp_eval.planning.path import KIND_SURFACE, KIND_TRANSITION
from wrp_eval.planning.planner import assign_sorties, plan
from wrp_eval.planning.views import GIMBAL_MAX_PITCH
from wrp_eval.ship.nofly import inside_no_fly_box, segments_intrude

CASES = [(ship, method) for ship in ("stylized", "cruise") for method in ("ours", "zhou2020", "oblique")]


@pytest.mark.parametrize("ship,method", CASES)
def test_every_view_is_safe_and_every_leg_avoids_the_ship(plans, proxies, ship, method):
    path, proxy = plans[(ship, method)].path, proxies[ship]
    assert len(path) > 10
    assert np.all(path.positions[:, 2] >= 5.0 - 1e-9)               # >= 5 m above the sea
    assert not inside_no_fly_box(path.positions, proxy.no_fly_bounds()).any()   # outside the no-fly box
    assert not segments_intrude(path.positions[:-1], path.positions[1:], proxy.no_fly_bounds()).any()
    assert np.all(path.pitch <= GIMBAL_MAX_PITCH + 1e-9)
    assert np.all(np.isfinite(path.yaw))


@pytest.mark.parametrize("ship,method", CASES)
def test_metrics_are_consistent_with_the_path(plans, ship, method):
    r = plans[(ship, method)]
    m, path = r.metrics, r.path
    assert m["length_m"] == pytest.approx(path.length_m)
    assert m["flight_time_s"] == pytest.approx(path.length_m / 5.0 + 0.5 * len(path))
    assert m["sorties"] == path.sortie.max() + 1
    assert m["n_transition_views"] == int(np.sum(path.kind == KIND_TRANSITION))
    if method != "oblique":
        assert sum(f["views"] for f in m["per_face"].values()) == m["n_views"]
        assert sum(f["samples"] for f in m["per_face"].values()) == m["n_samples"] == len(r.samples)
        assert int(np.sum(path.kind == KIND_SURFACE)) == m["n_views"]
        # the steps' timings add up to at most the total (each step timed once, the total around all of them)
        steps = ("sampling_s", "visibility_s", "min_s", "max_s", "metrics_s", "tsp_s", "transitions_s")
        assert all(m["timings"][key] > 0 for key in steps)
        assert sum(m["timings"][key] for key in steps) <= m["timings"]["total_s"] * (1 + 1e-9)
        # surface views carry their face, transition views -1
        assert np.all(path.face_id[path.kind == KIND_SURFACE] >= 0)
        assert np.all(path.face_id[path.kind == KIND_TRANSITION] == -1)


def test_ours_uses_fewer_views_than_zhou2020_on_the_stylized_ship(plans):
    # paper Table 7: 49 vs 57 - complexity-scaled radii and thresholds shrink the view set
    assert plans[("stylized", "ours")].metrics["n_views"] < plans[("stylized", "zhou2020")].metrics["n_views"]


def test_oblique_grid_follows_the_overlaps(plans, proxies):
    r = plans[("stylized", "oblique")]
    cam = r.path.camera
    width, length = cam.footprint_m(r.metrics["planned_distance_m"])
    first = r.path.positions[r.path.face_id == 4]                    # nadir sub-path
    along = np.diff(np.unique(np.round(first[:, 0], 6)))
    across = np.diff(np.unique(np.round(first[:, 1], 6)))
    assert along.max() <= length * (1 - 0.7) + 1e-9
    assert across.max() <= width * (1 - 0.75) + 1e-9
    np.testing.assert_allclose(np.degrees(r.path.pitch[r.path.face_id != 4]), -60.0)
    np.testing.assert_allclose(np.degrees(r.path.pitch[r.path.face_id == 4]), -90.0)
    assert np.ptp(r.path.positions[:, 2]) == 0.0                     # one fixed altitude
    assert set(np.unique(r.path.face_id)) == {0, 1, 2, 3, 4}


def test_sorties_split_at_the_endurance():
    pos = np.column_stack([np.arange(5) * 100.0, np.zeros(5), np.full(5, 10.0)])
    # elapsed after each view: 1, 22, 43, 64, 85 s (20 s legs + 1 s dwell)
    np.testing.assert_array_equal(assign_sorties(pos, 5.0, 1.0, 30.0), [0, 0, 1, 2, 2])


def test_same_seed_same_plan(proxies, complexity_of, fast):
    sec = PlanningSection(**fast)
    a = plan(proxies["stylized"], complexity_of["stylized"], sec, np.random.default_rng(11))
    b = plan(proxies["stylized"], complexity_of["stylized"], sec, np.random.default_rng(11))
    assert a.metrics["n_samples"] == b.metrics["n_samples"]
    np.testing.assert_array_equal(a.chosen.positions, b.chosen.positions)


def test_genetic_tour_solver_runs_seeded(proxies, complexity_of):
    sec = PlanningSection(tour_solver="ga", ga_population=30, ga_generations=40)
    a = plan(proxies["stylized"], complexity_of["stylized"], sec, np.random.default_rng(2))
    b = plan(proxies["stylized"], complexity_of["stylized"], sec, np.random.default_rng(2))
    np.testing.assert_array_equal(a.path.positions, b.path.positions)
    assert a.metrics["osmc_violations"] == 0


def test_blocked_legs_get_detour_corners(stylized_proxy):
    from wrp_eval.planning.planner import finish_path
    # port -> starboard straight through the ship, then along the starboard side
    pos = np.array([[0.0, 40, 10], [0.0, -40, 10], [30.0, -40, 10]])
    z = np.zeros(3)
    path, n = finish_path(pos, z, z, np.array([2, 3, 3]), np.zeros(3, int), stylized_proxy,
                           PlanningSection(), PlanningSection().camera(), "ours", {})
    assert n == 2 and len(path) == 5
    np.testing.assert_allclose(path.positions[1:3], [[0, 40, 32], [0, -40, 32]])   # box top 30 m + 2 m
    assert path.kind.tolist() == [0, 1, 1, 0, 0] and path.face_id.tolist() == [2, -1, -1, 3, 3]
    assert not segments_intrude(path.positions[:-1], path.positions[1:], stylized_proxy.no_fly_bounds()).any()
