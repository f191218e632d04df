"""The planner's two ablation switches used by the paper's tables: Min-only (max_rounds 0, Table 2) and ours
without the transition path (transitions false, Table 6)."""

import numpy as np

from wrp_eval.planning.config import PlanningSection
from wrp_eval.planning.path import KIND_TRANSITION
from wrp_eval.planning.planner import plan


def test_without_transitions_the_same_view_set_is_flown_with_no_transition_views(proxies, complexity_of):
    rng = lambda: np.random.default_rng(5)  # noqa: E731  (same draws for both plans)
    full = plan(proxies["stylized"], complexity_of["stylized"], PlanningSection(), rng())
    bare = plan(proxies["stylized"], complexity_of["stylized"], PlanningSection(transitions=False), rng())
    # the view set is the same (sampling, Min-Max and tour do not depend on the switch) ...
    np.testing.assert_array_equal(full.chosen.positions, bare.chosen.positions)
    # ... and the bare path only gains the over-the-top detour corners, never Alg. 2 views
    assert full.metrics["n_transition_views"] > full.metrics["n_detour_views"]
    kinds = bare.path.kind == KIND_TRANSITION
    assert kinds.sum() == bare.metrics["n_detour_views"]
    assert len(bare.path) == bare.metrics["n_views"] + bare.metrics["n_detour_views"]


def test_min_only_is_the_minimised_set_and_maximisation_raises_h(proxies, complexity_of):
    rng = lambda: np.random.default_rng(5)  # noqa: E731
    min_only = plan(proxies["cruise"], complexity_of["cruise"], PlanningSection(max_rounds=0), rng())
    min_max = plan(proxies["cruise"], complexity_of["cruise"], PlanningSection(), rng())
    m, mm = min_only.metrics, min_max.metrics
    assert m["max_swaps"] == 0 and m["n_views"] == m["n_views_after_min"]
    assert (m["H"], m["R"]) == (m["H_min_only"], m["R_min_only"])
    # same minimisation in both plans; maximisation keeps the count and does not lower H (planning/minmax.py)
    assert mm["n_views"] == m["n_views"] and mm["H_min_only"] == m["H"]
    assert mm["max_swaps"] > 0 and mm["H"] > m["H"]
