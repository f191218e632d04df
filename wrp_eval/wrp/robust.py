"""``wrp-eval optimize --kind robust``: the levers of wrp_eval/wrp/levers.py screened on the initial path's
campaign, and the path with the levers that beat their placebos (the initial path when none does).

Writes <out>/path.json and <out>/levers.json (the risk map, each lever's screening and verdict, the flights used,
the times). ``robust_s``, the optimiser's own time: the risk map (read from the campaign's ``view_registered``
column, or the oracle again on a campaign stored before it) and the levers' placement; ``screen_s``, timed apart:
the oracle's screening of each lever and its placebos on stored flights (the confirmation). No new flights.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pyarrow as pa

from wrp_eval.atomic import write_json_atomic
from wrp_eval.campaign.records import column_array
from wrp_eval.errors import InputError
from wrp_eval.experiment import ExperimentContext
from wrp_eval.logs import progress_log
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.sim.onboard import view_depths
from wrp_eval.surrogate.diagnostics import CampaignOracle, campaign_oracle
from wrp_eval.wrp.colmap_check import flight_captures
from wrp_eval.wrp.config import WrpSection
from wrp_eval.wrp.levers import (
    LeverScreen,
    RegistrationRisk,
    capture_error_sources,
    captures_with_lever,
    face_views,
    lever_kind,
    path_with_lever,
    registration_risk,
    riskiest,
    screen_lever,
)


def rescored_registration(ship, captures: dict[int, CaptureSet], seed_of: dict, n_views: int
                          ) -> tuple[np.ndarray, np.ndarray]:
    """(flights, n_views) bool registered and (flights,) errors m of the flights ``captures`` (trial id -> capture
    set) scored by ``ship`` with each trial's oracle seed."""
    registered = np.zeros((len(captures), n_views), bool)
    errors = np.empty(len(captures))
    for k, (trial, cs) in enumerate(captures.items()):
        result = ship.score(cs, seed=int(seed_of[trial]))
        if result.registered_mask is None:
            raise InputError("wrp.robust", f"the oracle ({result.oracle}) does not say which views it registered")
        registered[k, cs.planned_index[result.registered_mask]] = True
        errors[k] = result.error_m
    return registered, errors


# levers applied in this order: standoff keeps the view indices, redundant inserts views
APPLY_ORDER = ("standoff", "redundant")


def split_flights(trial_ids: np.ndarray, risk_flights: int, screen_flights: int,
                  rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Disjoint seeded draws of ``risk_flights`` and ``screen_flights`` trial ids (each sorted)."""
    if trial_ids.size < risk_flights + screen_flights:
        raise InputError("wrp.robust", f"the campaign has {trial_ids.size} flights that did not fail; the risk map "
                                       f"and the screening need {risk_flights} + {screen_flights}")
    chosen = rng.choice(trial_ids, risk_flights + screen_flights, replace=False)
    return np.sort(chosen[:risk_flights]), np.sort(chosen[risk_flights:])


@dataclass(frozen=True)
class _Campaign:
    """The initial path's campaign as the robust kind reads it."""

    folder: Path
    scorer: CampaignOracle
    table: pa.Table
    seed_of: dict[int, int]

    @property
    def path(self) -> FlightPath:
        return self.scorer.path

    def scored_ids(self) -> np.ndarray:
        """Sorted ids of the trials that did not fail and have an error (the draws depend on the config and seed
        only, not on the order the chunks were stored in)."""
        ok = ~self.table.column("failed").to_numpy(zero_copy_only=False).astype(bool)
        ok &= np.isfinite(self.table.column("error_m").to_numpy(zero_copy_only=False).astype(float))
        return np.sort(self.table.column("trial_id").to_numpy()[ok])

    def score(self, sets: Sequence[CaptureSet], trial_ids: np.ndarray) -> np.ndarray:
        """(k,) the oracle's errors of ``sets``, each with its trial's oracle seed."""
        return np.array([self.scorer.ship.score(cs, seed=self.seed_of[int(t)]).error_m
                         for cs, t in zip(sets, trial_ids, strict=True)])


def _read_campaign(folder: Path, config_dir: str | Path) -> _Campaign:
    scorer, store = campaign_oracle(folder, config_dir)
    table = store.read_table(["trial_id", "oracle_seed", "failed", "n_views", "error_m", "view_registered"])
    if table.column("oracle_seed").null_count:
        raise InputError(folder, "has trials without an oracle seed: their flights cannot be re-scored")
    seeds = zip(table.column("trial_id").to_pylist(), table.column("oracle_seed").to_pylist(), strict=True)
    return _Campaign(folder, scorer, table, {int(t): int(s) for t, s in seeds})


def _risk_map(camp: _Campaign, risk_ids: np.ndarray, config_dir: str | Path) -> tuple[RegistrationRisk, str]:
    """The risk map of ``risk_ids``' flights, from the stored ``view_registered`` column or, for a campaign stored
    before it, the oracle again; and where it came from."""
    rows = np.flatnonzero(np.isin(camp.table.column("trial_id").to_numpy(), risk_ids))   # any order: a covariance
    stored = column_array(camp.table.take(rows), "view_registered")
    if not np.all(np.isnan(stored), axis=1).any():
        return (registration_risk(stored == 1.0, camp.table.column("error_m").to_numpy()[rows]),
                f"the campaign's view_registered column, {risk_ids.size} flights")
    registered, errors = rescored_registration(camp.scorer.ship, flight_captures(camp.folder, risk_ids, config_dir),
                                               camp.seed_of, len(camp.path))
    return (registration_risk(registered, errors),
            f"re-scored {risk_ids.size} flights (the campaign has no view_registered column)")


def _lever_targets(section: WrpSection, path: FlightPath, views: np.ndarray, face_names: Sequence[str]
                   ) -> dict[str, np.ndarray]:
    """The levers to screen and the viewpoints each acts on: the riskiest ``views`` for redundant / standoff (none
    when no view is at risk), each face's surface viewpoints for face_standoff."""
    levers = section.robust.levers
    targets: dict[str, np.ndarray] = {lever: views for lever in levers if lever != "face_standoff" and views.size}
    if "face_standoff" in levers:
        targets |= {f"standoff_face_{face_names[f]}": at for f, at in face_views(path).items()}
    return targets


def _screen_levers(camp: _Campaign, section: WrpSection, targets: dict[str, np.ndarray], depths: np.ndarray,
                   screen_ids: np.ndarray, config_dir: str | Path, rng: np.random.Generator
                   ) -> tuple[dict[str, LeverScreen], dict]:
    """Each lever of ``targets`` (name -> its viewpoints) screened on the flights ``screen_ids`` against its
    placebos, and what each capture error costs those flights (:func:`capture_error_sources`)."""
    rob, path = section.robust, camp.path
    flights = list(flight_captures(camp.folder, screen_ids, config_dir).values())
    base = camp.score(flights, screen_ids)
    planned_sets = captures_from_path(path)
    windfree_base = float(camp.scorer.ship.score(planned_sets, seed=0).error_m)
    sources = capture_error_sources(lambda sets: camp.score(sets, screen_ids), flights, base, planned_sets)
    screens: dict[str, LeverScreen] = {}
    for name, views in targets.items():
        def change(cs: CaptureSet, at: np.ndarray, kind: str = lever_kind(name)) -> CaptureSet:
            return captures_with_lever(cs, kind, at, rob.standoff_fraction, depths, path)

        def windfree(at: np.ndarray | None, change: Callable[[CaptureSet, np.ndarray], CaptureSet] = change) -> float:
            # the planned captures changed as the flights' are (a redundant view given a view id after the path's):
            # the oracle draws each view's noise by its view id, so renumbering the views after an insertion would
            # reshuffle it
            if at is None:
                return windfree_base
            return float(camp.scorer.ship.score(change(planned_sets, at), seed=0).error_m)

        screens[name] = screen_lever(lambda sets: camp.score(sets, screen_ids), flights, base, change, windfree,
                                     name, views, len(path), rob.placebos, rng, section.evaluate.bootstrap,
                                     section.evaluate.confidence)
    return screens, sources


def _with_levers(path: FlightPath, levers: dict[str, np.ndarray], standoff_fraction: float,
                 depths_m: np.ndarray) -> FlightPath:
    """``path`` with each of ``levers`` (name -> viewpoints, in apply order): a viewpoint two standoff levers share
    is moved back once (the fraction is the GSD slack; stacked, nothing screened it)."""
    moved = np.zeros(len(path), dtype=bool)
    for name, views in levers.items():
        kind = lever_kind(name)
        if kind == "standoff":
            views = np.asarray(views, dtype=int)
            views, moved[views] = views[~moved[views]], True
        path = path_with_lever(path, kind, views, standoff_fraction, depths_m, name)
    return path


def _chosen(screens: dict[str, LeverScreen], apply: str | list[str]) -> list[str]:
    """The screened levers the robust path applies, in apply order: the recommended ones, all, or those named."""
    if isinstance(apply, list):
        return _in_apply_order([name for name in apply if name in screens])
    return [name for name in _in_apply_order(list(screens)) if apply == "all" or screens[name].verdict.recommended]


def _in_apply_order(names: Sequence[str]) -> list[str]:
    """Levers that keep the view indices (every standoff) before those that insert views (redundant)."""
    return sorted(names, key=lambda name: APPLY_ORDER.index(lever_kind(name)))


def robust_job(ctx: ExperimentContext, section: WrpSection, out: Path, campaign: str | Path | None = None) -> dict:
    """The robust kind (module docstring) of ``section`` into ``out``; returns levers.json."""
    start = time.perf_counter()
    rob = section.robust
    camp = _read_campaign(Path(campaign or section.campaign_dir or ctx.training_campaign_dir), ctx.config_dir)
    path = camp.path
    seed = section.seed if section.seed is not None else ctx.run_seed
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(13,)))
    risk_ids, screen_ids = split_flights(camp.scored_ids(), rob.risk_flights, rob.screen_flights, rng)
    risk, risk_source = _risk_map(camp, risk_ids, ctx.config_dir)
    views = riskiest(risk, max(1, math.ceil(rob.views_fraction * len(path))))
    depths = view_depths(path, ctx.flight_proxy.bounds)
    targets = _lever_targets(section, path, views, ctx.flight_proxy.face_names)
    if isinstance(rob.apply, list) and set(rob.apply) - set(targets):      # before minutes of screening
        raise InputError("wrp.robust.apply", f"names {sorted(set(rob.apply) - set(targets))}, which is no lever to "
                                             f"screen here (levers: {sorted(targets)})")
    placed_s = time.perf_counter() - start
    screens, sources = _screen_levers(camp, section, targets, depths, screen_ids, ctx.config_dir, rng)
    screen_s = time.perf_counter() - start - placed_s
    chosen = _chosen(screens, rob.apply)
    robust_path = _with_levers(path, {name: targets[name] for name in chosen}, rob.standoff_fraction, depths)
    out.mkdir(parents=True, exist_ok=True)
    robust_path.save(out / "path.json")
    doc = {"kind": "robust", "campaign": str(camp.folder), "seed": seed, "views": views.tolist(),
           "risk_flights": risk_ids.tolist(), "risk_source": risk_source, "screen_flights": screen_ids.tolist(),
           "p_unregistered": risk.p_unregistered.tolist(), "risk_m": risk.risk_m.tolist(),
           "levers": {k: v.to_json_dict() for k, v in screens.items()}, "error_sources": sources,
           "applied": chosen, "apply": rob.apply,
           "moved": bool(chosen), "robust_s": time.perf_counter() - start - screen_s, "screen_s": screen_s,
           "screening": "counterfactual: the screened flights' own capture sets with the lever applied, the same "
                        "oracle seeds; a redundant view takes the mean of its two ends' flown errors"}
    write_json_atomic(out / "levers.json", doc)
    _log_screens(screens)
    progress_log.info(f"robust: applied {chosen or 'no lever'}; {doc['robust_s']:.1f} s to place the levers "
                      f"({risk_source}), {screen_s:.1f} s to screen them -> {out}")
    return doc


def _log_screens(screens: dict[str, LeverScreen]) -> None:
    for name, s in screens.items():
        v = s.verdict
        progress_log.info(f"robust lever {name} at {len(s.views)} views: robustness gain {1e3 * v.gain_m:+.3f} mm "
                          f"(placebo p95 {1e3 * v.placebo_gain_p95_m:+.3f} mm); error gain {1e3 * s.error_gain_m:+.3f} "
                          f"mm, p95 {1e3 * s.p95_gain_m:+.3f} mm, wind-free {1e3 * s.windfree_gain_m:+.3f} mm -> "
                          + ("RECOMMENDED" if v.recommended else f"not recommended ({v.reason})"))


def robust_placebo_paths(initial: FlightPath, levers: dict, count: int, depths_m: np.ndarray,
                         standoff_fraction: float, rng: np.random.Generator) -> dict[str, FlightPath]:
    """``count`` placebos of a robust path (``levers``: its levers.json): the levers it applied, each placebo at
    as many viewpoints of ``initial`` chosen at random (one draw per placebo, shared by its levers at the riskiest
    viewpoints; one more per face lever)."""
    out = {}
    for k in range(count):
        views = np.sort(rng.choice(len(initial), len(levers["views"]), replace=False))
        drawn = {}
        for name in levers["applied"]:
            drawn[name] = views
            if lever_kind(name) != name:           # a face's lever: its own draw of as many viewpoints
                drawn[name] = np.sort(rng.choice(len(initial), len(levers["levers"][name]["views"]), replace=False))
        path = _with_levers(initial, drawn, standoff_fraction, depths_m)
        out[f"placebo-robust-{k:02d}"] = replace(path, metadata={**path.metadata, "placebo_of": "robust"})
    return out


def campaign_error_sources(folder: str | Path, flights: int, seed: int, config_dir: str | Path = ".") -> dict:
    """What each capture error costs a campaign's flights (:func:`wrp_eval.wrp.levers.capture_error_sources`) on
    ``flights`` of its trials that did not fail (seeded; all of them when fewer), with the trial ids used
    (``sources`` None when every trial failed)."""
    camp = _read_campaign(Path(folder), config_dir)
    ids = camp.scored_ids()
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(14,)))
    chosen = np.sort(rng.choice(ids, min(flights, ids.size), replace=False))
    if chosen.size == 0:
        return {"flights": [], "sources": None}
    sets = list(flight_captures(camp.folder, chosen, config_dir).values())
    sources = capture_error_sources(lambda s: camp.score(s, chosen), sets, camp.score(sets, chosen),
                                    captures_from_path(camp.path))
    return {"flights": chosen.tolist(), "sources": sources}
