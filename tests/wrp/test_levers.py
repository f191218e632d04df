"""The robust kind's levers (wrp/levers.py): the risk map, the path and capture-set changes, the screening."""

from __future__ import annotations

import numpy as np
import pytest

from wrp_eval.camera import optical_axes
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.wrp.levers import (
    captures_with_lever,
    leg_partners,
    path_with_lever,
    registration_risk,
    riskiest,
    screen_lever,
)


def ring_path(n: int = 12, radius: float = 30.0) -> FlightPath:
    """``n`` views on a circle round the origin facing it, pitched 10 deg down, unequal spacing."""
    ang = np.cumsum(np.linspace(0.3, 0.8, n))
    ang = 2 * np.pi * ang / ang[-1]
    pos = np.stack([radius * np.cos(ang), radius * np.sin(ang), np.full(n, 20.0)], axis=1)
    n_ = len(pos)
    return FlightPath(pos, np.arctan2(-pos[:, 1], -pos[:, 0]), np.full(n_, -np.radians(10)), np.arange(n_) % 3,
                      np.zeros(n_, int), np.zeros(n_, int))


def test_risk_is_the_covariance_of_a_lost_view_with_the_error():
    rng = np.random.default_rng(0)
    registered = np.ones((200, 4), bool)
    registered[:, 1] = rng.random(200) < 0.5          # view 1 registers in half the flights ...
    registered[:, 2] = rng.random(200) < 0.5          # ... view 2 too, but does not matter
    registered[:, 3] = False                          # view 3 never: nothing a flight does changes it
    errors = 0.010 + 0.002 * ~registered[:, 1] + 1e-4 * rng.standard_normal(200)
    risk = registration_risk(registered, errors)
    assert risk.p_unregistered[0] == 0 and risk.p_unregistered[3] == 1
    p = risk.p_unregistered[1]
    assert risk.risk_m[1] == pytest.approx(0.002 * p * (1 - p), rel=0.1)
    assert abs(risk.risk_m[2]) < 0.1 * risk.risk_m[1]
    assert risk.risk_m[0] == 0 and risk.risk_m[3] == 0
    assert riskiest(risk, 2).tolist() in ([1], [1, 2])          # only positive risks are chosen
    assert riskiest(risk, 1).tolist() == [1]


def test_the_redundant_view_sits_halfway_along_the_shorter_leg():
    path = ring_path()
    views = np.array([0, 4, 11])
    partner = leg_partners(path.positions, views)
    legs = np.linalg.norm(np.diff(path.positions, axis=0), axis=1)
    assert partner[0] == 1 and partner[2] == 10                 # the ends have one leg
    assert partner[1] == (3 if legs[3] <= legs[4] else 5)
    out = path_with_lever(path, "redundant", views, 0.1, np.full(len(path), 30.0))
    assert len(out) == len(path) + 3
    # every original view is kept, in tour order, and each new one lies between its two ends
    kept = [int(np.flatnonzero(np.all(out.positions == p, axis=1))[0]) for p in path.positions]
    assert kept == sorted(kept)
    for v, w in zip(views, partner, strict=True):
        mid = (path.positions[v] + path.positions[w]) / 2
        at = int(np.flatnonzero(np.all(np.isclose(out.positions, mid), axis=1))[0])
        assert min(kept[v], kept[w]) < at < max(kept[v], kept[w])
        assert out.face_id[at] == path.face_id[v]


def test_a_redundant_view_keeps_the_paths_per_view_modes_and_leg_speeds():
    path = ring_path()
    stop = np.zeros(len(path), dtype=bool)
    stop[4] = True
    legs = np.linspace(2.0, 5.0, len(path) - 1)
    path = path.with_stops(stop, "fly-through").with_leg_speeds(legs)
    views = np.array([4, 8])
    partner = leg_partners(path.positions, views)
    out = path_with_lever(path, "redundant", views, 0.1, np.full(len(path), 30.0))
    assert len(out.capture) == len(out) and out.leg_speeds().shape == (len(out) - 1,)
    for v, w in zip(views, partner, strict=True):
        at = int(np.flatnonzero(np.all(np.isclose(out.positions, (path.positions[v] + path.positions[w]) / 2),
                                       axis=1))[0])
        # between a stop and another view it stops too; both halves of the split leg at that leg's speed
        assert out.capture[at] == ("stop" if stop[v] or stop[w] else "fly-through")
        assert out.leg_speeds()[at - 1] == out.leg_speeds()[at] == legs[min(v, w)]
    assert out.stops("fly-through").sum() == 2


def test_standoff_moves_only_the_chosen_views_back_along_their_axes():
    path = ring_path()
    depth = np.linspace(20.0, 40.0, len(path))
    out = path_with_lever(path, "standoff", np.array([2, 5]), 0.1, depth)
    moved = np.linalg.norm(out.positions - path.positions, axis=1)
    assert moved[[2, 5]] == pytest.approx(0.1 * depth[[2, 5]])
    assert np.all(moved[np.setdiff1d(np.arange(len(path)), [2, 5])] == 0)
    back = (path.positions - out.positions)[[2, 5]] / moved[[2, 5], None]
    assert back == pytest.approx(optical_axes(path.yaw, path.pitch)[[2, 5]])
    assert np.all(np.linalg.norm(out.positions[[2, 5], :2], axis=1) > 30.0)     # farther from the ship


def test_two_chosen_neighbours_sharing_their_shorter_leg_get_one_redundant_view():
    path = ring_path()
    partner = leg_partners(path.positions, np.arange(len(path)))
    v = next(i for i in range(len(path) - 1) if partner[i] == i + 1 and partner[i + 1] == i)
    out = path_with_lever(path, "redundant", np.array([v, v + 1]), 0.1, np.zeros(len(path)))
    assert len(out) == len(path) + 1
    assert out.positions[v + 1] == pytest.approx((path.positions[v] + path.positions[v + 1]) / 2)
    cs = captures_with_lever(captures_from_path(path), "redundant", np.array([v, v + 1]), 0.1, np.zeros(len(path)),
                             path)
    assert len(cs) == len(path) + 1 and cs.planned_index[-1] == len(path)   # numbered after the path's views


def test_standoff_on_a_flown_capture_moves_it_along_its_planned_axis():
    from dataclasses import replace
    path = ring_path()
    flown = replace(captures_from_path(path), yaw=np.asarray(path.yaw) + 0.3)     # the airframe turned 17 deg
    out = captures_with_lever(flown, "standoff", np.array([4]), 0.1, np.full(len(path), 20.0), path)
    assert (flown.positions - out.positions)[4] == pytest.approx(2.0 * optical_axes(path.yaw, path.pitch)[4])
    assert np.array_equal(out.positions[np.arange(len(path)) != 4], flown.positions[np.arange(len(path)) != 4])


@pytest.mark.parametrize("lever", ["redundant", "standoff"])
def test_a_lever_on_the_planned_captures_is_the_lever_on_the_path(lever):
    path = ring_path()
    views, depth = np.array([3, 7]), np.full(len(path), 25.0)
    from_path = captures_from_path(path_with_lever(path, lever, views, 0.1, depth))
    from_captures = captures_with_lever(captures_from_path(path), lever, views, 0.1, depth, path)
    key = lambda cs: np.lexsort(cs.positions.T)  # noqa: E731
    a, b = from_path.subset(key(from_path)), from_captures.subset(key(from_captures))
    assert a.positions == pytest.approx(b.positions)
    assert a.yaw == pytest.approx(b.yaw) and a.pitch == pytest.approx(b.pitch)


def test_screening_recommends_a_lever_only_where_its_viewpoints_matter():
    """A score where the lever helps only at views 2 and 5 beats its placebos; one where it helps anywhere does
    not (the placebos gain as much)."""
    path = ring_path()
    flights = [captures_from_path(path) for _ in range(30)]
    noise = np.random.default_rng(1).normal(0, 1e-4, 30)
    base = 0.02 + noise

    def score_targeted(sets):
        return np.array([0.02 + noise[k] - 0.001 * (np.linalg.norm(cs.positions[[2, 5], :2], axis=1) > 30.5).sum()
                         for k, cs in enumerate(sets)])

    def change(cs, at):
        return captures_with_lever(cs, "standoff", at, 0.1, np.full(len(path), 25.0), path)

    def windfree(at):        # the plan itself is as good with or without the lever
        return 0.02

    rng = np.random.default_rng(0)
    targeted = screen_lever(score_targeted, flights, base, change, windfree, "standoff", np.array([2, 5]),
                            len(path), 20, rng, 500, 0.95)
    assert targeted.verdict.recommended, targeted.verdict.reason
    assert targeted.verdict.gain_m == pytest.approx(0.002) and targeted.error_gain_m == pytest.approx(0.002)
    assert targeted.windfree_gain_m == 0 and len(targeted.placebo_p95_gains_m) == 20

    def windfree_too(at):    # the same gain already without wind: a better plan, not a wind-resistant one
        return 0.02 - (0.002 if at is not None and set(at.tolist()) == {2, 5} else 0.0)

    planned = screen_lever(score_targeted, flights, base, change, windfree_too, "standoff", np.array([2, 5]),
                           len(path), 20, rng, 500, 0.95)
    assert planned.error_gain_m == pytest.approx(0.002) and planned.windfree_gain_m == pytest.approx(0.002)
    assert planned.verdict.gain_m == pytest.approx(0.0, abs=1e-12) and not planned.verdict.recommended

    def score_anywhere(sets):
        return np.array([0.02 + noise[k] - 0.001 * (np.linalg.norm(cs.positions[:, :2], axis=1) > 30.5).sum()
                         for k, cs in enumerate(sets)])

    anywhere = screen_lever(score_anywhere, flights, base, change, windfree, "standoff", np.array([2, 5]),
                            len(path), 20, rng, 500, 0.95)
    assert not anywhere.verdict.recommended
    assert "placebo" in anywhere.verdict.reason


def test_each_capture_error_is_removed_alone():
    from dataclasses import replace

    from wrp_eval.wrp.levers import CAPTURE_ERRORS, capture_error_sources, without_capture_error
    path = ring_path()
    planned = captures_from_path(path)
    rng = np.random.default_rng(3)
    flown = replace(planned.subset(np.arange(1, len(path))), blur_px=rng.random(len(path) - 1))
    flown = replace(flown, positions=flown.positions + rng.normal(0, 1, (len(flown), 3)),
                    yaw=flown.yaw + 0.05, pitch=flown.pitch - 0.02, roll=np.full(len(flown), 0.01),
                    prior_positions=flown.positions + 0.5)
    fields = {"blur": {"blur_px"}, "heading": {"yaw"}, "attitude": {"pitch", "roll"},
              "position": {"positions", "prior_positions"}}
    names = ("positions", "yaw", "pitch", "roll", "prior_positions", "blur_px")
    for source, changed in fields.items():
        out = without_capture_error(flown, source, planned)
        for name in names:
            assert np.array_equal(getattr(out, name), getattr(flown, name)) == (name not in changed), (source, name)
    clean = without_capture_error(flown, "all", planned)
    assert np.array_equal(clean.positions, path.positions[1:]) and np.array_equal(clean.yaw, path.yaw[1:])
    assert np.all(clean.blur_px == 0) and np.all(clean.roll == 0)

    def score(sets):      # an error that grows with the position error only
        return np.array([0.01 + 0.001 * np.linalg.norm(cs.positions - path.positions[cs.planned_index], axis=1).mean()
                         for cs in sets])

    base = score([flown])
    sources = capture_error_sources(score, [flown], base, planned)
    assert set(sources) == {"flown", *CAPTURE_ERRORS}
    assert sources["position"]["mean_gain_m"] == pytest.approx(base[0] - 0.01)
    assert sources["all"]["mean_m"] == pytest.approx(0.01)
    assert sources["blur"]["mean_gain_m"] == 0 and sources["heading"]["mean_gain_m"] == 0


def test_face_views_are_each_faces_surface_views_and_a_face_lever_is_a_standoff():
    from wrp_eval.planning.path import KIND_TRANSITION
    from wrp_eval.wrp.levers import face_views, lever_kind

    path = ring_path(12)                         # faces 0, 1, 2 in turn
    kind = np.zeros(12, int)
    kind[[4, 7]] = KIND_TRANSITION
    path = FlightPath(path.positions, path.yaw, path.pitch, np.where(kind == 0, path.face_id, -1), kind,
                      np.zeros(12, int))
    faces = face_views(path)
    assert {f: v.tolist() for f, v in faces.items()} == {0: [0, 3, 6, 9], 1: [1, 10], 2: [2, 5, 8, 11]}
    assert lever_kind("standoff_face_port") == "standoff" and lever_kind("redundant") == "redundant"


def test_a_face_levers_placebo_moves_as_many_random_views_as_the_face_has():
    from wrp_eval.wrp.robust import robust_placebo_paths

    path = ring_path(12)
    levers = {"views": [3], "applied": ["standoff_face_port"],
              "levers": {"standoff_face_port": {"views": [0, 3, 6, 9]}}}
    placebos = robust_placebo_paths(path, levers, 5, np.full(12, 30.0), 0.1, np.random.default_rng(2))
    moved = [np.flatnonzero(np.linalg.norm(p.positions - path.positions, axis=1) > 1e-9) for p in placebos.values()]
    assert all(m.size == 4 for m in moved) and len({tuple(m) for m in moved}) > 1    # 4 views each, not the same
    assert all(len(p) == 12 for p in placebos.values())


def test_a_view_two_applied_standoff_levers_share_is_moved_back_once():
    from wrp_eval.wrp.robust import _with_levers

    path = ring_path(12)
    depths = np.full(12, 30.0)
    both = _with_levers(path, {"standoff": np.array([1, 2]), "standoff_face_port": np.array([2, 3])}, 0.1, depths)
    shift = np.linalg.norm(both.positions - path.positions, axis=1)
    np.testing.assert_allclose(shift[[1, 2, 3]], 3.0)                   # 10 % of 30 m, once each
    assert not shift[np.setdiff1d(np.arange(12), [1, 2, 3])].any()
    assert both.metadata["lever"] == {"standoff": [1, 2], "standoff_face_port": [3]}
