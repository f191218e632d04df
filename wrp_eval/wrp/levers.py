"""Levers beyond moving a viewpoint (issue 30), screened with the oracle against their placebos.

At close range the error's spread is which views register (the inspection experiment: Spearman -0.52 between
a flight's error and its registered fraction, +0.01 with the wind speed). So the risk of viewpoint i is how
much its failing to register moves the error, measured on the initial path's own campaign flights:

* u_ki = 1 when the oracle left view i of flight k out of the reconstruction (or the flight did not take it);
* risk_i = cov_k(u_ki, e_k) (m): the error a flight loses on average with view i out, times p_i (1 - p_i)
  (a view always or never registered carries no risk: nothing the flight does changes it).

A lever is a change at the ``count`` riskiest viewpoints, applied the same way to the planned path (what would
be flown) and, for screening, to stored flights' capture sets (what those flights would have photographed):

* ``redundant``: one more view at the midpoint of the shorter leg at each chosen viewpoint (its pose the mean
  of the two ends': a second, overlapping image where registration is marginal; photogrammetry practice adds
  overlap where matching is weak, e.g. Pix4D's "image acquisition plan" advice for low-texture areas);
* ``standoff``: each chosen viewpoint moved back along its optical axis by ``standoff_fraction`` of its depth
  (so its GSD grows by that fraction: within the planner's GSD bound when the fraction is the bound's slack).

* ``face_standoff`` (one lever per face of the proxy): every surface viewpoint of the face moved back as
  ``standoff`` does (the issue's per-face standoff: a face whose views register marginally gains overlap as a
  whole); its placebos move as many viewpoints chosen at random.

Screening (counterfactual, exact on the oracle): the same flights' capture sets with and without the lever,
the same oracle seeds; gain_k = e_k(initial) - e_k(lever). In a screened flight a redundant view inherits the
mean of its two ends' flown errors (position, heading, pitch, roll, prior, blur): a stand-in for the flight
that would have taken it, stated in the result. Its control: ``placebos`` levers of the same kind at as many
viewpoints chosen at random. The verdict is the evaluation's (:func:`wrp_eval.wrp.evaluate.robustness_verdict`):
recommended when the gain's CI excludes 0 and the gain exceeds the placebos' 95th percentile.

Risk and screening use disjoint flights (the risk's first, seeded), so a lever is never judged on the flights
that chose its viewpoints.

What any lever could gain is bounded by what the capture errors cost: :func:`capture_error_sources` re-scores the
screened flights with one error removed at a time (blur, heading, attitude, position, all): a lever acting on
blur (capture mode, speed per leg) cannot gain more than the flights lose to blur.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from wrp_eval.camera import optical_axes
from wrp_eval.planning.path import CAPTURE_MODES, KIND_SURFACE, FlightPath
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.wrp.evaluate import robustness_verdict
from wrp_eval.wrp.evaluation import RobustnessVerdict


@dataclass(frozen=True)
class RegistrationRisk:
    """p_unregistered (n,): share of the flights that lost view i (not taken or not registered); risk_m (n,):
    cov(lost_i, error) over those flights (m)."""

    p_unregistered: np.ndarray
    risk_m: np.ndarray


def registration_risk(registered: np.ndarray, errors_m: np.ndarray) -> RegistrationRisk:
    """The risk map (module docstring) from ``registered`` (k flights, n views) bool and the flights' errors (k,) m."""
    lost = ~np.asarray(registered, dtype=bool)
    e = np.asarray(errors_m, dtype=float)
    risk = ((lost - lost.mean(axis=0)) * (e - e.mean())[:, None]).mean(axis=0)
    return RegistrationRisk(lost.mean(axis=0), risk)


def riskiest(risk: RegistrationRisk, count: int) -> np.ndarray:
    """The ``count`` viewpoints of highest risk (positive risk only), sorted by index."""
    order = np.argsort(-risk.risk_m, kind="stable")[:count]
    return np.sort(order[risk.risk_m[order] > 0])


def leg_partners(positions: np.ndarray, views: np.ndarray) -> np.ndarray:
    """For each of ``views`` the tour neighbour (i - 1 or i + 1) at the end of the shorter leg."""
    positions = np.asarray(positions, dtype=float)
    n = len(positions)
    prev, nxt = np.clip(views - 1, 0, n - 1), np.clip(views + 1, 0, n - 1)
    d_prev = np.where(views > 0, np.linalg.norm(positions[prev] - positions[views], axis=1), np.inf)
    d_next = np.where(views < n - 1, np.linalg.norm(positions[nxt] - positions[views], axis=1), np.inf)
    return np.where(d_prev <= d_next, prev, nxt)


def _mean_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.angle(np.exp(1j * a) + np.exp(1j * b))


def redundant_legs(positions: np.ndarray, views: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ends, partners): one leg per chosen view, the shorter one at it (:func:`leg_partners`); a leg two chosen
    neighbours share gets one redundant view, not two."""
    views = np.asarray(views, dtype=int)
    partner = leg_partners(positions, views)
    leg = np.minimum(views, partner) * len(positions) + np.maximum(views, partner)
    keep = np.sort(np.unique(leg, return_index=True)[1])
    return views[keep], partner[keep]


def face_views(path: FlightPath) -> dict[int, np.ndarray]:
    """The surface viewpoints (kind KIND_SURFACE) of each face id the path has, indices in path order."""
    surface = (np.asarray(path.kind) == KIND_SURFACE) & (np.asarray(path.face_id) >= 0)
    faces = np.asarray(path.face_id)
    return {int(f): np.flatnonzero(surface & (faces == f)) for f in np.unique(faces[surface])}


def lever_kind(name: str) -> str:
    """The change a screened lever makes: ``standoff`` for a face's standoff (``standoff_face_<name>``), else
    the name itself."""
    return "standoff" if name.startswith("standoff_face_") else name


def path_with_lever(path: FlightPath, lever: str, views: np.ndarray, standoff_fraction: float,
                    depths_m: np.ndarray, name: str | None = None) -> FlightPath:
    """``path`` with ``lever`` (redundant / standoff) at ``views``; ``depths_m`` (n,): each view's distance to the
    ship along its axis; ``name``: the lever's name in the path's metadata (default ``lever``)."""
    views = np.asarray(views, dtype=int)
    lever_note = {**path.metadata.get("lever", {}), name or lever: views.tolist()}
    if lever == "standoff":
        back = np.zeros(len(path))
        back[views] = standoff_fraction * np.nan_to_num(depths_m[views])
        axes = optical_axes(path.yaw, path.pitch)
        return replace(path, positions=np.asarray(path.positions) - back[:, None] * axes,
                       metadata={**path.metadata, "lever": lever_note})
    ends, partner = redundant_legs(path.positions, views)
    ids = path.view_ids()
    new = {"positions": (path.positions[ends] + path.positions[partner]) / 2,
           "yaw": _mean_angle(path.yaw[ends], path.yaw[partner]),
           "pitch": (path.pitch[ends] + path.pitch[partner]) / 2,
           "face_id": path.face_id[ends], "kind": path.kind[ends], "sortie": path.sortie[ends],
           # the new views numbered after the path's (as captures_with_lever numbers them): every other view keeps
           # its id, so the oracle's draws of the flown path stay those of the screening
           "view_id": ids.max(initial=-1) + 1 + np.arange(ends.size)}
    # the new view goes between its two ends in the tour
    slot = np.maximum(ends, partner)
    old = {**{name: np.asarray(getattr(path, name)) for name in new}, "view_id": ids}
    fields: dict[str, Any] = {name: np.insert(old[name], slot, value, axis=0) for name, value in new.items()}
    if path.capture is not None:     # a view between a stop and another view stops too
        modes = np.asarray(path.capture)
        stop_mode = CAPTURE_MODES[0]
        added = np.where((modes[ends] == stop_mode) | (modes[partner] == stop_mode), stop_mode, CAPTURE_MODES[1])
        fields["capture"] = tuple(np.insert(modes, slot, added).tolist())
    if path.leg_speed_m_s is not None:     # the split leg's two halves at its speed
        legs = np.asarray(path.leg_speed_m_s, dtype=float)
        fields["leg_speed_m_s"] = np.insert(legs, slot - 1, legs[slot - 1])
    return replace(path, **fields, metadata={**path.metadata, "lever": lever_note})


def captures_with_lever(cs: CaptureSet, lever: str, views: np.ndarray, standoff_fraction: float,
                        depths_m: np.ndarray, planned: FlightPath) -> CaptureSet:
    """A flight's capture set ``cs`` as it would have been with ``lever`` at ``views`` of the ``planned`` path
    (module docstring): standoff moves each chosen capture back along its view's planned axis; a redundant view
    gets planned_index n + leg and view id (the path's largest) + 1 + leg, leg its place among the redundant legs
    (so its view id is the one :func:`path_with_lever` gives it, and a leg whose ends were not both taken leaves
    its number unused)."""
    n = len(planned)
    index = np.full(n, -1)
    index[cs.planned_index] = np.arange(len(cs))
    if lever == "standoff":
        back = np.zeros((len(cs), 3))
        taken = index[views] >= 0
        axes = optical_axes(planned.yaw, planned.pitch)[views][taken]
        back[index[views][taken]] = standoff_fraction * np.nan_to_num(depths_m[views][taken])[:, None] * axes
        prior = None if cs.prior_positions is None else cs.prior_positions - back
        return replace(cs, positions=cs.positions - back, prior_positions=prior)
    ends, partner = redundant_legs(planned.positions, views)
    both = (index[ends] >= 0) & (index[partner] >= 0)
    a, b = index[ends][both], index[partner][both]

    def mid(values: np.ndarray) -> np.ndarray:
        return np.concatenate([values, (values[a] + values[b]) / 2])

    def optional_mid(values: np.ndarray | None) -> np.ndarray | None:
        return None if values is None else mid(values)

    leg = np.flatnonzero(both)
    return CaptureSet(mid(cs.positions), np.concatenate([cs.yaw, _mean_angle(cs.yaw[a], cs.yaw[b])]),
                      mid(cs.pitch), np.concatenate([cs.planned_index, n + leg]),
                      cs.camera, optional_mid(cs.roll), optional_mid(cs.prior_positions), optional_mid(cs.blur_px),
                      np.concatenate([cs.view_ids(), planned.view_ids().max(initial=-1) + 1 + leg]))


@dataclass(frozen=True)
class LeverScreen:
    """One lever's screening: the viewpoints it acts on, the flights it was screened on, its verdict against its
    placebos on the robustness gain (mean, CI, placebo 95th percentile, recommended and why), and beside it the
    raw error gains: mean (m), p95 (m), and the wind-free path's own gain (m); the placebos' raw mean and p95
    gains."""

    lever: str
    views: tuple[int, ...]
    flights: int
    verdict: RobustnessVerdict
    error_gain_m: float
    p95_gain_m: float
    windfree_gain_m: float
    placebo_error_gains_m: tuple[float, ...]
    placebo_p95_gains_m: tuple[float, ...]

    def to_json_dict(self) -> dict:
        return {"lever": self.lever, "views": list(self.views), "flights": self.flights,
                "verdict": self.verdict.to_json_dict(), "error_gain_m": self.error_gain_m,
                "p95_gain_m": self.p95_gain_m, "windfree_gain_m": self.windfree_gain_m,
                "placebo_error_gains_m": list(self.placebo_error_gains_m),
                "placebo_p95_gains_m": list(self.placebo_p95_gains_m)}


@dataclass(frozen=True)
class _Gains:
    robustness: np.ndarray      # (k,) m per flight: raw gain - the wind-free path's gain
    error_m: float
    p95_m: float
    windfree_m: float


def screen_lever(score: Callable[[Sequence[CaptureSet]], np.ndarray], flights: Sequence[CaptureSet],
                 base_errors_m: np.ndarray, change: Callable[[CaptureSet, np.ndarray], CaptureSet],
                 windfree_error: Callable[[np.ndarray | None], float], lever: str, views: np.ndarray, n_views: int,
                 placebos: int, rng: np.random.Generator, resamples: int, confidence: float) -> LeverScreen:
    """Screen ``change(capture set, views)`` at ``views`` against ``placebos`` of it at as many random viewpoints
    (of ``n_views``) on ``flights`` (their errors without it: ``base_errors_m``); ``score(capture sets) -> (k,)``
    errors with each flight's own oracle seed; ``windfree_error(views)``: the wind-free path's error with the lever
    at ``views`` (None: without it). The verdict is on the robustness gain, as the evaluation's
    (:func:`wrp_eval.wrp.evaluate.robustness_gains`): per flight, the raw gain minus the wind-free path's gain."""
    base = np.asarray(base_errors_m, dtype=float)
    windfree_base = windfree_error(None)

    def gains(at: np.ndarray) -> _Gains:
        errors = score([change(cs, at) for cs in flights])
        ok = np.isfinite(errors) & np.isfinite(base)
        raw = base[ok] - errors[ok]
        windfree = windfree_base - windfree_error(at)
        p95 = float(np.percentile(base[ok], 95) - np.percentile(errors[ok], 95)) if ok.any() else float("nan")
        return _Gains(raw - windfree, float(raw.mean()) if raw.size else float("nan"), p95, windfree)

    mine = gains(views)
    placebo = [gains(np.sort(rng.choice(n_views, views.size, replace=False))) for _ in range(placebos)]
    verdict = robustness_verdict(mine.robustness, np.array([g.robustness.mean() if g.robustness.size else np.nan
                                                            for g in placebo]), rng, resamples, confidence)
    return LeverScreen(lever, tuple(int(v) for v in views), len(flights), verdict, mine.error_m, mine.p95_m,
                       mine.windfree_m, tuple(g.error_m for g in placebo), tuple(g.p95_m for g in placebo))


def without_capture_error(cs: CaptureSet, source: str, planned: CaptureSet) -> CaptureSet:
    """``cs`` with one capture error removed (``planned``: the path's views as planned, indexed by view):
    "blur" (sharp images), "heading" (yaw as planned), "attitude" (pitch as planned, no roll), "position" (the
    planned positions, priors with them), "all" (every one of these)."""
    at = cs.planned_index
    if source == "blur":
        return replace(cs, blur_px=np.zeros(len(cs)))
    if source == "heading":
        return replace(cs, yaw=planned.yaw[at])
    if source == "attitude":
        return replace(cs, pitch=planned.pitch[at], roll=np.zeros(len(cs)))
    if source == "position":
        return replace(cs, positions=planned.positions[at], prior_positions=planned.positions[at])
    if source == "all":
        return replace(planned.subset(at), roll=np.zeros(len(cs)), blur_px=np.zeros(len(cs)))
    raise ValueError(f"unknown capture error {source!r}; choose from {CAPTURE_ERRORS}")


CAPTURE_ERRORS = ("blur", "heading", "attitude", "position", "all")


def capture_error_sources(score: Callable[[Sequence[CaptureSet]], np.ndarray], flights: Sequence[CaptureSet],
                          base_errors_m: np.ndarray, planned: CaptureSet) -> dict[str, dict[str, float]]:
    """What each capture error costs the flights (counterfactual, the oracle exact): per source of
    :data:`CAPTURE_ERRORS`, the flights re-scored without it: mean, std and p95 of their errors (m) and the mean
    and p95 gains against ``base_errors_m`` (m). The bound on what any lever acting on that error can gain."""
    base = np.asarray(base_errors_m, dtype=float)

    def stats(x: np.ndarray) -> dict[str, float]:        # over the flights the oracle could score
        x = x[np.isfinite(x)]
        nan = float("nan")
        return {"mean_m": float(x.mean()) if x.size else nan, "std_m": float(x.std(ddof=1)) if x.size > 1 else nan,
                "p95_m": float(np.percentile(x, 95)) if x.size else nan}

    out = {"flown": stats(base)}
    for source in CAPTURE_ERRORS:
        errors = score([without_capture_error(cs, source, planned) for cs in flights])
        row = stats(errors)
        both = np.isfinite(base) & np.isfinite(errors)
        out[source] = {**row, "mean_gain_m": float((base - errors)[both].mean()) if both.any() else float("nan"),
                       "p95_gain_m": out["flown"]["p95_m"] - row["p95_m"]}
    return out
