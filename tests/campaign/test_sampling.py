"""Seeding: a trial's draws are a pure function of (root seed, trial id, config); wind draws ignore the path
(common random numbers); the box designs cover the box."""

from __future__ import annotations

import numpy as np

from wrp_eval.campaign.config import CampaignSection, Choice, Normal, Uniform
from wrp_eval.campaign.sampling import commanded_offsets, draw_value, draw_wind, trial_inputs


def section(**kw) -> CampaignSection:
    return CampaignSection.model_validate(kw)


def test_same_seed_same_draws_and_independent_of_other_trials():
    s = section(perturbation={"design": "box"})
    a = trial_inputs(s, 11, 5, 10)
    for k in range(5):  # drawing other trials first changes nothing
        trial_inputs(s, 11, k, 10)
    b = trial_inputs(s, 11, 5, 10)
    assert a.wind == b.wind and a.flight_seed == b.flight_seed
    np.testing.assert_array_equal(a.commanded_offsets, b.commanded_offsets)
    np.testing.assert_array_equal(a.disturbance, b.disturbance)
    c = trial_inputs(s, 11, 6, 10)
    assert c.wind != a.wind and c.flight_seed != a.flight_seed
    assert trial_inputs(s, 12, 5, 10).wind != a.wind


def test_wind_is_common_to_paths_of_any_length():
    s = section(perturbation={"design": "box"})
    short, long = trial_inputs(s, 3, 9, 4), trial_inputs(s, 3, 9, 50)
    assert short.wind == long.wind
    assert short.commanded_offsets.shape == (4, 4) and long.commanded_offsets.shape == (50, 4)


def test_changing_one_wind_input_leaves_the_others():
    a = draw_wind(section(), 1, 2)
    b = draw_wind(section(wind={"speed_10m_m_s": 7.5}), 1, 2)
    assert b.speed_10m_m_s == 7.5 and a.direction_deg == b.direction_deg and a.seed == b.seed


def test_distributions_stay_in_their_support():
    rng = np.random.default_rng(0)
    u = [draw_value(Uniform(dist="uniform", low=2, high=3), rng) for _ in range(500)]
    n = [draw_value(Normal(dist="normal", mean=0, std=5, clip=(-1, 1)), rng) for _ in range(500)]
    c = [draw_value(Choice(dist="choice", values=["a", "b"], weights=[0, 1]), rng) for _ in range(50)]
    assert 2 <= min(u) and max(u) < 3 and abs(np.mean(u) - 2.5) < 0.05
    assert min(n) == -1 and max(n) == 1       # std 5 clipped: both bounds are hit
    assert set(c) == {"b"}                    # weight 0 is never drawn
    assert draw_value(4.0, rng) == 4.0


def test_box_offsets_fill_the_box_and_sobol_is_extendable():
    s = section(n_trials=64, perturbation={"design": "box", "position_half_width_m": 2, "yaw_half_width_deg": 10})
    offs = np.stack([commanded_offsets(s, 5, k, 3) for k in range(64)])      # (64, 3, 4)
    assert np.all(np.abs(offs[..., :3]) <= 2) and np.all(np.abs(offs[..., 3]) <= np.radians(10) + 1e-12)
    # a scrambled Sobol design: every coordinate has exactly one point in each of 64 strata
    strata = np.floor((offs[..., 0] / 2 + 1) / 2 * 64)
    assert all(np.unique(strata[:, j]).size == 64 for j in range(3))
    bigger = section(n_trials=128, perturbation=s.perturbation.model_dump())
    np.testing.assert_array_equal(commanded_offsets(bigger, 5, 17, 3), offs[17])


def test_lhs_design_is_stratified_per_campaign():
    s = section(n_trials=20, perturbation={"design": "box", "sampler": "lhs", "position_half_width_m": 1})
    offs = np.stack([commanded_offsets(s, 2, k, 2) for k in range(20)])
    strata = np.floor((offs[..., 1] + 1) / 2 * 20)
    assert all(np.unique(strata[:, j]).size == 20 for j in range(2))


def test_no_design_means_no_offsets_and_disturbance_is_bounded():
    s = section(perturbation={"design": "none", "flown_disturbance": 0.2})
    inp = trial_inputs(s, 0, 1, 30)
    assert not inp.commanded_offsets.any()
    assert np.all((inp.disturbance >= 0.8) & (inp.disturbance <= 1.2)) and inp.disturbance.std() > 0.05
    off = trial_inputs(section(perturbation={"flown_disturbance": 0}), 0, 1, 30)
    assert np.all(off.disturbance == 1.0)


def test_common_design_shares_one_offset_disturbed_per_view():
    s = section(n_trials=32, perturbation={"design": "common", "position_half_width_m": 2, "yaw_half_width_deg": 20,
                                           "view_disturbance": 0.2, "view_jitter": 0.05})
    offs = np.stack([commanded_offsets(s, 3, k, 40) for k in range(32)])      # (32, 40, 4)
    half = np.array([2, 2, 2, np.radians(20)])
    # every view within (1 + 20 %) of the common part plus 5 % jitter of the box
    assert np.all(np.abs(offs) <= 1.2 * half + 0.05 * half + 1e-12)
    # the views of a trial move together: the per-trial mean explains most of the spread across trials
    within = offs.var(axis=1).mean(axis=0)
    between = offs.mean(axis=1).var(axis=0)
    assert np.all(between > 10 * within)
    # the common part is a Sobol design over 4 dimensions: one trial mean in each of 32 strata of dx
    strata = np.floor((offs[:, :, 0].mean(axis=1) / 2 + 1) / 2 * 32)
    assert np.unique(strata).size >= 28       # disturbance and jitter blur the strata a little
    np.testing.assert_array_equal(commanded_offsets(s, 3, 5, 40), offs[5])   # pure function of the trial
    assert not np.array_equal(commanded_offsets(s, 4, 5, 40), offs[5])


def test_solo_views_move_on_their_own_and_leave_the_rest_of_the_trial_unchanged():
    base = {"design": "common", "position_half_width_m": 2, "yaw_half_width_deg": 20}
    plain = section(n_trials=16, perturbation=base)
    solo = section(n_trials=16, perturbation={**base, "solo_views": 2})
    half = np.array([2, 2, 2, np.radians(20)])
    for k in range(16):
        a, b = commanded_offsets(plain, 3, k, 30), commanded_offsets(solo, 3, k, 30)
        changed = np.flatnonzero(np.any(a != b, axis=1))
        assert changed.size == 2                       # exactly two views take their own offset ...
        assert np.all(np.abs(b[changed]) <= half)      # ... inside the box
        np.testing.assert_array_equal(np.delete(a, changed, 0), np.delete(b, changed, 0))
        np.testing.assert_array_equal(commanded_offsets(solo, 3, k, 30), b)
    # across trials the solo views are spread over the path and their offsets over the box
    chosen = [np.flatnonzero(np.any(commanded_offsets(plain, 3, k, 30) != commanded_offsets(solo, 3, k, 30), 1))
              for k in range(16)]
    assert np.unique(np.concatenate(chosen)).size >= 15


def test_physical_design_targets_a_short_run_of_views_in_a_share_of_trials():
    s = section(perturbation={"design": "physical", "targeted_share": 0.25, "targeted_max_views": 4,
                              "targeted_position_sigma_m": 1.5, "targeted_yaw_sigma_deg": 8.0})
    offs = np.stack([commanded_offsets(s, 7, k, 40) for k in range(400)])          # (400, 40, 4)
    moved = np.any(offs != 0, axis=2)                                               # (400, 40)
    targeted = moved.any(axis=1)
    assert 0.18 < targeted.mean() < 0.32                                            # about a quarter
    for row in moved[targeted]:                                                     # one run of 1..4 views
        idx = np.flatnonzero(row)
        assert 1 <= len(idx) <= 4 and np.all(np.diff(idx) == 1)
    values = offs[moved]
    assert 1.2 < values[:, :3].std() < 1.8 and 6.0 < np.degrees(values[:, 3]).std() < 10.0
    np.testing.assert_array_equal(commanded_offsets(s, 7, 11, 40), offs[11])         # pure function of the trial
    # the targets have their own stream: the wind draws are those of an untargeted campaign
    plain = section(perturbation={"design": "physical", "targeted_share": 0.0})
    assert not np.any([commanded_offsets(plain, 7, k, 40) for k in range(50)])
    assert draw_wind(s, 7, 3) == draw_wind(plain, 7, 3)
