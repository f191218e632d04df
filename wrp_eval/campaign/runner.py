"""Run a campaign (resumably) and summarise a campaign folder.

``run_campaign`` = trial config + path -> fingerprint -> take the folder's lock -> skip stored trials
-> batches of the remaining trial ids -> backend -> records buffered and written in atomic chunks, each one
logged to rerun and counted by the progress bar -> close. Re-running the same call resumes.
"""

from __future__ import annotations

import hashlib
import json
import platform
import time
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from wrp_eval.campaign import backends
from wrp_eval.campaign.code_digest import trial_code_digest
from wrp_eval.campaign.config import CampaignSection, TrialConfig
from wrp_eval.campaign.evaluators import (
    DEFAULT_EVALUATOR,
    RENAMED_EVALUATORS,
    CampaignContext,
    resolve_factory,
)
from wrp_eval.campaign.progress import CampaignProgress
from wrp_eval.campaign.rerun_log import CampaignRecorder
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError
from wrp_eval.logs import progress_log, progress_shown
from wrp_eval.planning.path import FlightPath, digest_of_document
from wrp_eval.ship.resolve import resolve_ship_full

# settings that do not change any trial's result: excluded from the fingerprint
_NEUTRAL_KEYS = ("n_trials", "batch_size", "backend", "outputs")
# the config sections a trial (flight + oracle) reads; the path enters through its digest
_TRIAL_SECTIONS = ("ship", "wind", "sim", "oracle", "campaign")


@dataclass(frozen=True)
class CampaignSummary:
    """out_dir; n_trials; done (stored now), failed, errors (trials that raised); ran: trials run this call;
    wall_s of this call; trials_per_min of this call; rerun_s: time spent logging to rerun this call;
    stress_note: the turbulence stress-test line (campaign/turbulence.py) or None."""

    out_dir: Path
    n_trials: int
    done: int
    failed: int
    errors: int
    ran: int
    wall_s: float
    trials_per_min: float
    rerun_s: float
    stress_note: str | None = None


def with_overrides(trial: TrialConfig, *, n_trials: int | None = None, backend: str | None = None,
                   workers: int | None = None, rerun: bool | None = None) -> TrialConfig:
    """The trial config with command-line overrides of the ``campaign:`` section (only that section is
    validated again, for the overridden values)."""
    section = trial.campaign.model_dump()
    if n_trials is not None:
        section["n_trials"] = n_trials
    if backend is not None:
        section["backend"]["kind"] = backend
    if workers is not None:
        section["backend"]["workers"] = workers
    if rerun is not None:
        section["outputs"]["rerun"] = rerun
    return trial.model_copy(update={"campaign": CampaignSection.model_validate(section)})


def fingerprint(config_doc: dict, digest: str, root_seed: int, evaluator: str, options: dict, code: str) -> str:
    """Hash of everything that decides a trial's result: the config sections a flight and its scoring read
    (:data:`_TRIAL_SECTIONS`), the path digest, the root seed, the evaluator (an LHS design also depends on
    n_trials) and ``code``, the digest of the evaluator's sources (:func:`trial_code_digest`). The surrogate,
    wrp, export, planning (the path has its own digest) and study sections are left out: retuning the
    surrogate must not make thousands of stored flights unusable."""
    doc = {name: json.loads(json.dumps(config_doc.get(name))) for name in _TRIAL_SECTIONS}
    campaign = doc["campaign"]
    design = campaign["perturbation"]
    lhs = design["design"] not in ("none", "physical") and design["sampler"] == "lhs"
    for key in _NEUTRAL_KEYS:
        if not (key == "n_trials" and lhs):
            campaign.pop(key, None)
    hashed = {"config": doc, "path": digest, "seed": root_seed, "evaluator": evaluator, "options": options,
              "code": code}
    return hashlib.sha256(json.dumps(hashed, sort_keys=True, default=str).encode()).hexdigest()[:16]


def stored_fingerprint(meta: dict, code: str | None = None) -> str | None:
    """The fingerprint of a stored campaign (campaign.json) recomputed by today's code: its stored config is
    validated again, so that a setting added since (whose default keeps the old behaviour, the rule for every
    new setting) and a change in which sections count do not orphan the stored trials. ``code``: the code digest
    to recompute it with (None: the stored one). None when the stored inputs no longer validate, and for a store
    flown before ``sim.mission`` existed (battery swaps, the headway rule and the wind rules changed what ends a
    flight, so its trials cannot be extended by today's flights; the store still loads for reading). None too for
    a store without a code digest (flown before the fingerprint held one: by which code is unknown) unless
    ``code`` is given."""
    try:
        code = code or meta.get("code_digest")
        if "mission" not in meta["config"]["sim"] or not code:
            return None
        doc = TrialConfig.from_stored(meta["config"]).model_dump(mode="json")
        evaluator = meta.get("evaluator", DEFAULT_EVALUATOR)
        return fingerprint(doc, meta["path_digest"], meta["root_seed"], RENAMED_EVALUATORS.get(evaluator, evaluator),
                           meta.get("evaluator_options") or {}, code)
    except (KeyError, TypeError, ValueError):   # pydantic's ValidationError is a ValueError
        return None


def versions() -> dict:
    """Python, machine and the versions of the libraries a trial depends on (from package metadata: no
    heavy imports)."""
    found = {"python": platform.python_version(), "wrp-eval": __import__("wrp_eval").__version__}
    for name in ("numpy", "scipy", "mujoco", "open3d", "torch", "trimesh", "rerun-sdk", "pyarrow", "ray"):
        try:
            found[name] = version(name)
        except PackageNotFoundError:
            pass
    return {"machine": platform.machine(), "system": platform.platform(), "versions": found}


def open_store(store: TrialStore, trial: TrialConfig, path_doc: dict, *, root_seed: int, evaluator: str,
               evaluator_options: dict) -> tuple[str, np.ndarray]:
    """Check that the (locked) ``store`` holds nothing but this campaign's trials and (re)write its meta;
    returns (the fingerprint, the stored trial ids). A folder of another campaign is an :class:`InputError`, and
    so is one of this campaign flown by other flight / oracle code (its code digest) with trials still to fly:
    two versions' trials never mix. Complete, it is used as it is (its trials read, nothing flown), with a
    warning naming both digests."""
    digest = digest_of_document(path_doc)
    config_doc = trial.model_dump(mode="json")
    code = trial_code_digest(evaluator)
    print_ = fingerprint(config_doc, digest, root_seed, evaluator, evaluator_options, code)
    previous = store.read_meta()
    if previous is not None and previous.get("fingerprint") != print_ and stored_fingerprint(previous) != print_:
        if stored_fingerprint(previous, code) != print_:
            raise InputError(store.out_dir, "holds a campaign with a different config, path or seed (fingerprint "
                                            f"{previous.get('fingerprint')} vs {print_}); use another --out (or "
                                            "campaign.outputs.dir), or remove the folder")
        stored = store.stored_ids()
        flown_by = f"flown by other flight / oracle code (code digest {previous.get('code_digest') or 'not recorded'}"
        if not np.isin(np.arange(trial.campaign.n_trials), stored).all():
            raise InputError(store.out_dir, f"holds this campaign {flown_by} vs {code}) with trials still to fly: "
                                            "its trials stay readable, but today's would not mix with them; use "
                                            "another --out (or campaign.outputs.dir), or remove the folder")
        progress_log.warning(f"campaign {store.out_dir}: every trial stored, {flown_by} vs {code}): its trials are "
                             "used as they are; remove the folder to fly them with this code")
        return str(previous.get("fingerprint")), stored
    store.write_meta({"fingerprint": print_, "config": config_doc, "root_seed": root_seed, "path_digest": digest,
                      "code_digest": code,
                      "n_views": len(path_doc["viewpoints"]),
                      "n_trials": trial.campaign.n_trials, "evaluator": evaluator,
                      "evaluator_options": evaluator_options, "environment": versions(),
                      "updated_unix": time.time()}, path_doc)
    return print_, store.stored_ids()


def worker_spec(trial: TrialConfig, path: FlightPath, *, key: str, root_seed: int, config_dir: Path | None,
                evaluator: str, evaluator_options: dict) -> dict:
    """What a worker needs to evaluate trials of ``trial`` flying ``path`` (:func:`wrp_eval.campaign.worker.
    run_batch`); ``key`` names the evaluator a worker builds once and keeps."""
    context = CampaignContext(trial=trial, path=path, root_seed=root_seed, path_digest=digest_of_document(
        path.to_json_dict()), threads=1, config_dir=str(Path(config_dir or ".").resolve()))
    return {"key": key, "evaluator": evaluator, "evaluator_options": evaluator_options,
            "max_attempts": trial.campaign.backend.max_attempts, "context": context}


def stored_path(path: FlightPath) -> tuple[FlightPath, dict]:
    """The path as a campaign folder stores it (path.json holds degrees: the workers fly the same floats whether
    the campaign is run now, resumed from its folder, or re-scored from the stored path later) and its
    document."""
    path_doc = path.to_json_dict()
    return FlightPath.from_json_dict(path_doc, source="path"), path_doc


def backend_workers(section: CampaignSection) -> int:
    """Worker processes of a campaign section (none: one per CPU)."""
    return section.backend.workers if section.backend.workers is not None else backends.default_workers()


def run_campaign(trial: TrialConfig, path: FlightPath, out_dir: str | Path, *, root_seed: int,
                 config_dir: Path | None = None, evaluator: str = DEFAULT_EVALUATOR,
                 evaluator_options: dict | None = None,
                 ship_mesh=None) -> CampaignSummary:
    """Run (or resume) the campaign of ``trial`` flying ``path`` into ``out_dir``. ``trial`` already carries
    any overrides (see :func:`with_overrides`). ``evaluator`` names the factory ``"module:function"`` of the
    trial evaluator; ``ship_mesh``: the true ship mesh for the recording (resolved here when the recording is
    on and none is given)."""
    wall_start = time.perf_counter()
    section = trial.campaign
    evaluator_options = dict(evaluator_options or {})
    resolve_factory(evaluator)  # fail early, in the calling process, on a bad name
    path, path_doc = stored_path(path)
    out = Path(out_dir)
    workers = backend_workers(section)

    store = TrialStore(out)
    with store:
        print_, stored = open_store(store, trial, path_doc, root_seed=root_seed, evaluator=evaluator,
                                    evaluator_options=evaluator_options)
        todo = np.setdiff1d(np.arange(section.n_trials), stored)
        batches = [todo[chunk].tolist() for chunk in backends.split_batches(todo.size, section.batch_size, workers)]
        spec = worker_spec(trial, path, key=f"{print_}-{workers}", root_seed=root_seed, config_dir=config_dir,
                           evaluator=evaluator, evaluator_options=evaluator_options)

        recorder = None
        if section.outputs.rerun:
            mesh = ship_mesh if ship_mesh is not None else resolve_ship_full(trial.ship, config_dir or ".").mesh
            recorder = CampaignRecorder(out, {**path_doc, "digest": spec["context"].path_digest}, mesh)
            if stored.size:
                for row in store.read_table().to_pylist():
                    recorder.log_trial(row)

        bar = CampaignProgress(section.n_trials, int(np.unique(stored).size), enabled=progress_shown())
        with backends.TrialPool(section.backend.kind, max(1, workers) if section.backend.kind == "ray" else workers,
                                section.backend.address) as pool:
            ran = _store_as_they_come(pool.run([(spec, ids) for ids in batches]), store, section.outputs, recorder,
                                      bar)
        rerun_s = 0.0
        if recorder is not None:
            recorder.close()
            rerun_s = recorder.seconds
        table = store.read_table(["trial_id", "failed", "error"])

    wall = time.perf_counter() - wall_start
    errors = int(table.column("error").is_valid().to_numpy(zero_copy_only=False).sum())
    return CampaignSummary(out_dir=out, n_trials=section.n_trials, done=len(table),
                           failed=int(np.sum(table.column("failed").to_numpy(zero_copy_only=False))),
                           errors=errors, ran=ran, wall_s=wall,
                           trials_per_min=60.0 * ran / wall if wall > 0 else 0.0, rerun_s=rerun_s)


def _store_as_they_come(stream, store: TrialStore, outputs, recorder, bar: CampaignProgress) -> int:
    """Append the records of ``stream`` (task index, records) to ``store`` in chunks of ``outputs.chunk_trials``
    (or after ``outputs.flush_s``), logging each to the recorder and the progress bar; returns how many ran."""
    buffer: list[dict] = []
    last_flush = time.perf_counter()
    ran = 0
    try:
        for _, records in stream:
            buffer.extend(records)
            ran += len(records)
            if recorder is not None:
                for row in records:
                    recorder.log_trial(row)
            bar.update(len(records), sum(bool(r["failed"]) for r in records))
            if len(buffer) >= outputs.chunk_trials or time.perf_counter() - last_flush >= outputs.flush_s:
                store.append(buffer)
                buffer = []
                last_flush = time.perf_counter()
        store.append(buffer)
    finally:
        stream.close()
        bar.close()
    return ran


def active_seconds(start: np.ndarray, end: np.ndarray) -> float:
    """Length of the union of the intervals [start_i, end_i] (s): the time something was running."""
    if start.size == 0:
        return 0.0
    order = np.argsort(start)
    start, end = start[order], np.maximum.accumulate(end[order])
    gaps = np.clip(start[1:] - end[:-1], 0.0, None)
    return float(end[-1] - start[0] - gaps.sum())


def campaign_status(out_dir: str | Path) -> dict:
    """done / failed / errors / remaining of a campaign folder, and its rate in trials/min over the time it
    was running: each trial's batch occupied [finished - trial_s * its size, finished]; the union of those
    intervals is the running time (gaps between resumes are left out; parallel workers overlap). A batch's
    trials share their worker and their trial_s (the batch's seconds over its size), which is how its size is
    counted; a trial retried alone is a batch of one."""
    store = TrialStore(out_dir)
    meta = store.read_meta()
    if meta is None:
        raise InputError(out_dir, "not a campaign folder (no campaign.json)")
    table = store.read_table(["trial_id", "failed", "error", "finished_unix", "trial_s", "worker"])
    ids = table.column("trial_id").to_numpy()
    finished = table.column("finished_unix").to_numpy(zero_copy_only=False).astype(float)
    trial_s = np.nan_to_num(table.column("trial_s").to_numpy(zero_copy_only=False).astype(float))
    workers = np.asarray([str(w) for w in table.column("worker").to_pylist()])
    _, batch_of, batch_size = np.unique(np.rec.fromarrays([workers, trial_s]), return_inverse=True,
                                        return_counts=True)
    busy = trial_s * batch_size[batch_of.ravel()]
    active = active_seconds(finished - busy, finished)
    n_trials = int(meta["n_trials"])
    done = int(np.unique(ids).size)
    return {"out_dir": str(out_dir), "n_trials": n_trials, "done": done,
            "failed": int(np.sum(table.column("failed").to_numpy(zero_copy_only=False))),
            "errors": int(table.column("error").is_valid().to_numpy(zero_copy_only=False).sum()),
            "remaining": int(np.setdiff1d(np.arange(n_trials), ids).size),
            "duplicates": int(ids.size - done),
            "trials_per_min": 60.0 * done / active if active > 0 else None,
            "n_views": meta.get("n_views"), "fingerprint": meta.get("fingerprint")}
