"""``wrp-eval envelope``: where the planned mission meets its spec, against the wind speed and direction.

A campaign of campaigns. Per relative wind direction a :class:`~wrp_eval.envelope.search.BoundarySearch` picks
the U10 cells to fly; each cell flies its flights in looks of the sequential test
(:mod:`wrp_eval.envelope.sequential`) and stops as soon as its interval decides the threshold. Every round flies
the next look of every open cell (one per direction, plus the forecast's) together, in batches spread over the
workers of ONE pool (:class:`~wrp_eval.campaign.backends.TrialPool`, local processes or Ray), so the workers
start and build their simulator once and the simulator advances many flights at a time. Each cell is a
campaign folder: a killed envelope resumes, and no stored flight is flown again.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path

import numpy as np

from wrp_eval.campaign.backends import TrialPool, split_batches
from wrp_eval.campaign.code_digest import trial_code_digest
from wrp_eval.campaign.config import TrialConfig
from wrp_eval.campaign.evaluators import DEFAULT_EVALUATOR, resolve_factory
from wrp_eval.campaign.runner import (
    backend_workers,
    fingerprint,
    open_store,
    stored_path,
    versions,
    with_overrides,
    worker_spec,
)
from wrp_eval.campaign.sampling import trial_inputs
from wrp_eval.campaign.store import TrialStore
from wrp_eval.envelope.cells import (
    Cell,
    CellKey,
    TestRule,
    cell_trial,
    direction_name,
    ending_counts,
    limiting_cause,
    relative_directions,
    replay,
    stored_trials,
)
from wrp_eval.envelope.config import EnvelopeGrid
from wrp_eval.envelope.result import CellResult, DirectionBoundary, Envelope, ForecastWind
from wrp_eval.envelope.search import BoundarySearch
from wrp_eval.envelope.sequential import MEETS, clopper_pearson, repeated_interval
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath, digest_of_document
from wrp_eval.wrp.evaluate import PathTrials
from wrp_eval.wrp.jobs import SPEC_ERROR_FACTOR, windfree_error

log = logging.getLogger(__name__)


def spec_of(ctx: ExperimentContext, path: FlightPath) -> tuple[float, float]:
    """(error m, completeness) a flight must meet: ``wrp.evaluate``'s spec, the error defaulting to
    1.1 x the path's wind-free error as the evaluation's does."""
    ev = ctx.config.wrp.evaluate
    error = ev.spec_error_m if ev.spec_error_m is not None else SPEC_ERROR_FACTOR * windfree_error(ctx, path)
    return float(error), float(ev.spec_completeness)


@dataclasses.dataclass
class _Flying:
    """What a round needs: the cells so far, the test, the worker spec (``worker``: one evaluator per worker
    process for every cell) and the campaign's seeds. Cells live under ``cells/<path digest>/``: envelopes of
    different paths (``wrp-eval run`` flies the recommended one) share a folder without mixing flights."""

    ctx: ExperimentContext
    out: Path
    path: FlightPath
    path_doc: dict
    base: TrialConfig
    rule: TestRule
    evaluator: str
    evaluator_options: dict
    workers: int
    cells: dict = dataclasses.field(default_factory=dict)
    worker: dict | None = None
    flown: int = 0

    def cell(self, key: CellKey) -> Cell:
        """The cell of ``key``, opened (its folder checked, its stored flights replayed) on first use."""
        if key not in self.cells:
            trial = cell_trial(self.base, key, self.ctx.particulars.heading_deg, self.rule.max_flights)
            folder = self.out / "cells" / digest_of_document(self.path_doc) / key.folder_name
            cell = Cell(key, folder, trial)
            with TrialStore(cell.folder) as store:
                open_store(store, trial, self.path_doc, root_seed=self.ctx.campaign_seed, evaluator=self.evaluator,
                           evaluator_options=self.evaluator_options)
            replay(cell, self.rule)
            self.cells[key] = cell
            if self.worker is None:          # one evaluator per worker for every cell: they differ only in wind
                print_ = fingerprint(trial.model_dump(mode="json"), "envelope", self.ctx.campaign_seed,
                                     self.evaluator, self.evaluator_options, trial_code_digest(self.evaluator))
                self.worker = worker_spec(trial, self.path, key=f"envelope-{print_}-{self.workers}",
                                        root_seed=self.ctx.campaign_seed, config_dir=self.ctx.config_dir,
                                        evaluator=self.evaluator, evaluator_options=self.evaluator_options)
        return self.cells[key]


def _wanted(flying: _Flying, searches: dict[float, BoundarySearch], forecast: CellKey | None) -> list[Cell]:
    """The open cells of the next round: per direction the search's next cell (finished cells are fed to the
    search until it asks for an open one), and the forecast's cell; each once."""
    wanted: dict[CellKey, Cell] = {}
    for relative, search in searches.items():
        while (speed := search.next_speed()) is not None:
            cell = flying.cell(CellKey.of(relative, speed))
            if not cell.finished:
                wanted[cell.key] = cell
                break
            search.record(speed, flying.rule.meets(cell))
    if forecast is not None and not (cell := flying.cell(forecast)).finished:
        wanted[cell.key] = cell
    return list(wanted.values())


def _fly_look(flying: _Flying, pool: TrialPool, cells: list[Cell]) -> None:
    """The next look of every cell of ``cells``, all flights in one set of batches; stores them and decides."""
    n_views, seed, worker = len(flying.path), flying.ctx.campaign_seed, flying.worker
    if worker is None:
        raise RuntimeError(f"envelope {flying.out}: no worker spec (it is made when the first cell is opened)")
    jobs = []
    for cell in cells:
        stored = set(TrialStore(cell.folder).stored_ids().tolist())
        jobs += [(cell, trial_inputs(cell.trial.campaign, seed, k, n_views))
                 for k in range(cell.flights, flying.rule.next_target(cell.flights)) if k not in stored]
    chunks = [c.tolist() for c in split_batches(len(jobs), flying.base.campaign.batch_size, flying.workers)]
    for index, records in pool.run([(worker, [jobs[i][1] for i in chunk]) for chunk in chunks]):
        by_cell: dict[CellKey, list[dict]] = {}
        for i, record in zip(chunks[index], records, strict=True):
            by_cell.setdefault(jobs[i][0].key, []).append(record)
        for key, rows in by_cell.items():
            with TrialStore(flying.cells[key].folder) as store:
                store.append(rows)
        flying.flown += len(records)
    for cell in cells:
        replay(cell, flying.rule)
        log.info("[wrp-eval envelope] cell %s: %d/%d flights meet the spec -> %s", cell.key.folder_name,
                 cell.successes, cell.flights, cell.decision)


def _first_flights(trials: PathTrials, flights: int) -> PathTrials:
    keep = trials.trial_id < flights
    return dataclasses.replace(trials, **{f.name: getattr(trials, f.name)[keep] for f in dataclasses.fields(trials)
                                          if isinstance(getattr(trials, f.name), np.ndarray)})


def _mean(values: np.ndarray | None) -> float:
    finite = values[np.isfinite(values)] if values is not None else np.zeros(0)
    return float(finite.mean()) if finite.size else float("nan")


def cell_result(cell: Cell, rule: TestRule, heading_deg: float, forecast: bool = False) -> CellResult:
    """What a finished cell says (result.py's :class:`CellResult`): error mean and p95 over the flights that
    did not fail; sorties and mission time over the completed missions (a mission that ended early says nothing
    of what the mission needs, as in :func:`wrp_eval.wrp.evaluate.mission_summary`)."""
    stored = stored_trials(cell)
    if stored is None:
        raise RuntimeError(f"envelope cell {cell.key.folder_name}: no stored flights")
    trials = _first_flights(stored, cell.flights)
    errors = trials.error_m[~trials.failed & np.isfinite(trials.error_m)]
    done = trials.completed if trials.completed is not None else np.zeros(trials.trial_id.size, bool)
    endings = ending_counts(cell.folder, cell.flights)
    low, high = clopper_pearson(cell.successes, cell.flights, rule.confidence)
    return CellResult(
        relative_deg=cell.key.relative_deg, compass_from_deg=cell.key.compass_from_deg(heading_deg),
        speed_m_s=cell.key.speed_m_s, direction=cell.key.direction, flights=cell.flights,
        decision=cell.decision, meets=rule.meets(cell), p_meets_spec=cell.p_hat,
        p_meets_spec_ci=(float(low), float(high)),
        repeated_ci=repeated_interval(cell.successes, cell.flights, rule.confidence, rule.looks),
        p_completed=float(done.mean()) if trials.completed is not None else float("nan"),
        completeness_mean=_mean(trials.completeness),
        error_mean_m=float(errors.mean()) if errors.size else float("nan"),
        error_p95_m=float(np.percentile(errors, 95)) if errors.size else float("nan"),
        expected_sorties=_mean(trials.sorties[done]) if trials.sorties is not None else float("nan"),
        mission_time_s=_mean(trials.mission_time_s[done]) if trials.mission_time_s is not None else float("nan"),
        views_lost=_mean(trials.views_not_taken), endings=endings,
        limit=limiting_cause(trials, endings, rule.spec), folder=str(cell.folder), forecast=forecast)


def _boundary(relative: float, search: BoundarySearch, results: dict[CellKey, CellResult]) -> DirectionBoundary:
    high = search.lowest_failing
    limit = results[CellKey.of(relative, high)].limit if high is not None else ""
    proved = [s for s in search.outcomes if results[CellKey.of(relative, s)].decision == MEETS]
    return DirectionBoundary(relative_deg=float(relative), direction=direction_name(relative),
                             boundary_m_s=search.boundary_m_s, proved_m_s=max(proved) if proved else None,
                             bracket_m_s=(search.boundary_m_s, high), above_grid=search.above_grid, limit=limit)


def run_envelope(ctx: ExperimentContext, out: str | Path, grid: EnvelopeGrid, *, path: FlightPath | None = None,
                 forecast: ForecastWind | None = None, backend: str | None = None, workers: int | None = None,
                 evaluator: str = DEFAULT_EVALUATOR, evaluator_options: dict | None = None) -> Envelope:
    """Fly (or resume) the envelope of ``path`` (default the campaign's path) on ``grid`` into ``out``; with
    ``forecast`` its cell is flown too and read for the go / no-go. ``backend`` / ``workers`` override the
    campaign section's; ``evaluator``: the trial evaluator's factory (the analytic stand-in in tests)."""
    start = time.perf_counter()
    evaluator_options = dict(evaluator_options or {})
    resolve_factory(evaluator)
    path, path_doc = stored_path(path if path is not None else ctx.campaign_path)
    base = with_overrides(ctx.trial_config, backend=backend, workers=workers)
    ev = ctx.config.wrp.evaluate
    rule = TestRule(grid.look_flights, grid.max_flights, ev.go_probability, ev.confidence, spec_of(ctx, path))
    n_workers = backend_workers(base.campaign)
    flying = _Flying(ctx, Path(out), path, path_doc, base, rule, evaluator, evaluator_options, n_workers)
    searches = {float(r): BoundarySearch(grid.speeds_m_s, grid.resolution_m_s)
                for r in relative_directions(grid.directions)}
    forecast_key = CellKey.of(forecast.relative_deg, forecast.speed_m_s) if forecast is not None else None
    kind = base.campaign.backend.kind
    # one envelope process per folder (each cell's store is locked only while it is written)
    with TrialStore(flying.out), TrialPool(kind, max(1, n_workers) if kind == "ray" else n_workers,
                                           base.campaign.backend.address) as pool:
        while cells := _wanted(flying, searches, forecast_key):
            before = [c.flights for c in cells]
            _fly_look(flying, pool, cells)
            if [c.flights for c in cells] == before:
                raise RuntimeError(f"envelope {flying.out}: a round advanced no cell "
                                   f"({', '.join(c.key.folder_name for c in cells)})")
    heading = ctx.particulars.heading_deg
    results = {key: cell_result(cell, rule, heading, forecast=key == forecast_key)
               for key, cell in sorted(flying.cells.items()) if cell.flights}
    go = None if forecast_key is None else flying.cells[forecast_key].decision == MEETS
    return Envelope(
        cells=tuple(results.values()),
        boundaries=tuple(_boundary(r, s, results) for r, s in searches.items()),
        forecast=forecast, go=go,
        rule={"threshold": rule.threshold, "confidence": rule.confidence, "spec_error_m": rule.spec[0],
              "spec_completeness": rule.spec[1], "look_flights": rule.look_flights, "max_flights": rule.max_flights,
              "looks": rule.looks, "test": "Clopper-Pearson repeated intervals, Bonferroni over the looks"},
        grid=grid.model_dump(mode="json"), flights_flown=flying.flown,
        flights_total=sum(c.flights for c in results.values()), wall_s=time.perf_counter() - start,
        provenance={"config": ctx.source, "path_digest": digest_of_document(path_doc),
                    "root_seed": ctx.campaign_seed, "evaluator": evaluator, "ship_heading_deg": heading,
                    "environment": versions()})
