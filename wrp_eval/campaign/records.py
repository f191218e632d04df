"""Trial records: what an evaluator returns for a trial, and the one Parquet row stored per trial.

Per-viewpoint arrays are stored as nested lists (``list<fixed_size_list<float64, k>>``); read them back as
``(batch, n_views, k)`` arrays with :func:`column_array`. Offsets are (dx, dy, dz) m and dyaw rad, from the
PLANNED viewpoint (so flown = commanded + wind-induced deviation). Views never taken are NaN.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

METRIC_NAMES = ("error_m", "hole_part_m", "accuracy_part_m", "accuracy_m", "completeness", "precision", "fscore",
                "registered_fraction")


@dataclass
class TrialOutcome:
    """What an evaluator hands back for one trial.

    flown_offsets (n_views, 4): capture pose minus planned viewpoint (dx, dy, dz m, dyaw rad), NaN rows for
    views not taken; metrics: oracle figures by name (``METRIC_NAMES``; missing ones are stored as NaN);
    failed/reason: the flight or the reconstruction failed (a result, not an error); trajectory (m, 3) m:
    down-sampled flown positions; wind_at_views (n_views, 3) m/s: the wind felt at each capture;
    timings: seconds by phase (e.g. flight_s, oracle_s); camera_pitch (n_views,) rad: the gimbal pitch
    achieved at each capture (the planned one unless the gimbal saturated), NaN for views not taken.
    The capture realism (all per view, NaN for views not taken; None when the evaluator has none):
    capture_time_s (n_views,) s of the shutter; camera_roll (n_views,) rad: the residual roll;
    estimated_offsets (n_views, 4): the navigation's record of
    the capture pose minus the plan (the image's position prior); blur_px (n_views,); battery_charge
    (n_views,) fraction left at the shutter; ship_motion (n_views, 4): heave m, roll, pitch, yaw rad of the
    ship at the shutter; view_registered (n_views,): 1 where the oracle registered the view, 0 where it did not
    (None when the oracle does not say); flight_outcome: "completed" or why the mission ended early (returned
    home: battery with no sortie left, wind limit, no headway; lost) or failed.
    The mission (None when the evaluator has none): sorties flown; view_sortie (n_views,) int: the sortie that
    took each view (0: none did); mission_time_s: the last photo or the end, battery swaps included; ending:
    the outcome's name (:data:`wrp_eval.sim.flight_state.OUTCOME_NAMES`)."""

    flown_offsets: np.ndarray
    metrics: dict[str, float]
    failed: bool = False
    reason: str = ""
    trajectory: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    wind_at_views: np.ndarray | None = None
    timings: dict[str, float] = field(default_factory=dict)
    camera_pitch: np.ndarray | None = None
    capture_time_s: np.ndarray | None = None
    camera_roll: np.ndarray | None = None
    estimated_offsets: np.ndarray | None = None
    blur_px: np.ndarray | None = None
    battery_charge: np.ndarray | None = None
    ship_motion: np.ndarray | None = None
    view_registered: np.ndarray | None = None
    flight_outcome: str | None = None
    sorties: int | None = None
    view_sortie: np.ndarray | None = None
    mission_time_s: float | None = None
    ending: str | None = None


# per-view columns of the capture realism: name -> values per view (1: a list of floats, k: nested lists)
REALISM_COLUMNS = {"capture_time_s": 1, "camera_roll": 1, "estimated_offsets": 4, "blur_px": 1, "battery_charge": 1,
                   "ship_motion": 4, "view_registered": 1}


def _nested(k: int) -> pa.DataType:
    return pa.list_(pa.list_(pa.float64(), k))


SCHEMA = pa.schema([
    pa.field("trial_id", pa.int64(), nullable=False),
    pa.field("root_seed", pa.int64()),
    pa.field("path_digest", pa.string()),
    # inputs drawn
    pa.field("wind_speed_10m_m_s", pa.float64()),
    pa.field("wind_direction_deg", pa.float64()),
    pa.field("turbulence_severity", pa.string()),
    pa.field("turbulence_sigma_w_mps", pa.float64()),
    pa.field("mesoscale_file", pa.string()),
    pa.field("mesoscale_time", pa.string()),
    pa.field("wind_seed", pa.uint64()),
    pa.field("flight_seed", pa.uint64()),
    pa.field("oracle_seed", pa.uint64()),
    pa.field("n_views", pa.int32()),
    pa.field("commanded_offsets", _nested(4)),
    pa.field("disturbance", _nested(4)),
    # flown
    pa.field("flown_offsets", _nested(4)),
    pa.field("camera_pitch", pa.list_(pa.float64())),   # rad per view; null in campaigns stored before it
    pa.field("wind_at_views", _nested(3)),
    # capture realism (null in campaigns stored before it, and for evaluators without it)
    *[pa.field(name, pa.list_(pa.float64()) if k == 1 else _nested(k)) for name, k in REALISM_COLUMNS.items()],
    pa.field("flight_outcome", pa.string()),
    # the mission: sorties, the sortie of each view, its time, how it ended (null in campaigns stored before)
    pa.field("sorties", pa.int32()),
    pa.field("view_sortie", pa.list_(pa.int32())),
    pa.field("mission_time_s", pa.float64()),
    pa.field("ending", pa.string()),
    pa.field("trajectory", _nested(3)),
    # oracle
    *[pa.field(name, pa.float64()) for name in METRIC_NAMES],
    pa.field("failed", pa.bool_()),
    pa.field("failure_reason", pa.string()),
    pa.field("error", pa.string()),          # the exception of a trial that raised (then failed is true)
    pa.field("attempts", pa.int32()),
    # timings
    pa.field("flight_s", pa.float64()),
    pa.field("oracle_s", pa.float64()),
    pa.field("trial_s", pa.float64()),
    pa.field("worker", pa.string()),
    pa.field("finished_unix", pa.float64()),
])
TIMING_COLUMNS = ("flight_s", "oracle_s", "trial_s", "worker", "finished_unix")


def _rows(a: np.ndarray | None, k: int) -> list | None:
    return None if a is None else np.asarray(a, dtype=float).reshape(-1, k).tolist()


def _per_view(a: np.ndarray | None, k: int) -> list | None:
    if a is None:
        return None
    return np.asarray(a, dtype=float).ravel().tolist() if k == 1 else _rows(a, k)


def make_record(inputs, outcome: TrialOutcome | None, *, root_seed: int, path_digest: str, n_views: int,
                attempts: int, trial_s: float, worker: str, finished_unix: float,
                error: str | None = None) -> dict:
    """One row of :data:`SCHEMA` from a trial's inputs and its outcome (None when the trial raised)."""
    wind = inputs.wind
    row = {
        "trial_id": inputs.trial_id, "root_seed": root_seed, "path_digest": path_digest,
        "wind_speed_10m_m_s": wind.speed_10m_m_s, "wind_direction_deg": wind.direction_deg,
        "turbulence_severity": wind.severity, "turbulence_sigma_w_mps": wind.sigma_w_m_s,
        "mesoscale_file": wind.file, "mesoscale_time": wind.time, "wind_seed": wind.seed,
        "flight_seed": inputs.flight_seed, "oracle_seed": inputs.oracle_seed, "n_views": n_views,
        "commanded_offsets": _rows(inputs.commanded_offsets, 4), "disturbance": _rows(inputs.disturbance, 4),
        "attempts": attempts, "trial_s": trial_s, "worker": worker, "finished_unix": finished_unix,
    }
    if outcome is None:
        nan = np.full((n_views, 4), np.nan)
        row.update({"flown_offsets": _rows(nan, 4), "camera_pitch": None, "wind_at_views": None, "trajectory": None,
                    **{name: None for name in REALISM_COLUMNS}, "flight_outcome": None, "sorties": None,
                    "view_sortie": None, "mission_time_s": None, "ending": None,
                    **{m: float("nan") for m in METRIC_NAMES}, "failed": True,
                    "failure_reason": "error", "error": error, "flight_s": None, "oracle_s": None})
        return row
    row.update({
        "flown_offsets": _rows(outcome.flown_offsets, 4),
        "camera_pitch": None if outcome.camera_pitch is None else np.asarray(outcome.camera_pitch, float).tolist(),
        "wind_at_views": _rows(outcome.wind_at_views, 3),
        **{name: _per_view(getattr(outcome, name), k) for name, k in REALISM_COLUMNS.items()},
        "flight_outcome": outcome.flight_outcome,
        "sorties": outcome.sorties,
        "view_sortie": None if outcome.view_sortie is None else np.asarray(outcome.view_sortie, int).tolist(),
        "mission_time_s": outcome.mission_time_s,
        "ending": outcome.ending,
        "trajectory": _rows(outcome.trajectory, 3),
        **{m: float(outcome.metrics.get(m, float("nan"))) for m in METRIC_NAMES},
        "failed": bool(outcome.failed), "failure_reason": outcome.reason, "error": None,
        "flight_s": outcome.timings.get("flight_s"), "oracle_s": outcome.timings.get("oracle_s"),
    })
    return row


def records_to_table(records: list[dict]) -> pa.Table:
    return pa.Table.from_pylist(records, schema=SCHEMA)


def column_array(table: pa.Table, name: str) -> np.ndarray:
    """Float array of a per-viewpoint column: (rows, n_views, k) for the vector columns (``commanded_offsets``,
    ``flown_offsets``, ``disturbance``, ``wind_at_views``), (rows, n_views) for ``camera_pitch``. A null cell
    (a trial that raised; ``camera_pitch`` in chunks stored before the column: use the planned pitch) becomes
    NaN."""
    col = table.column(name).combine_chunks()
    vector = pa.types.is_fixed_size_list(col.type.value_type)
    shape = (col.type.value_type.list_size,) if vector else ()
    n = int(pc.max(table.column("n_views")).as_py()) if len(table) else 0
    out = np.full((len(table), n, *shape), np.nan)
    valid = col.is_valid().to_numpy(zero_copy_only=False)
    if valid.any():
        values = pc.list_flatten(col.filter(pa.array(valid)))
        values = pc.list_flatten(values) if vector else values
        out[valid] = values.to_numpy(zero_copy_only=False).reshape(-1, n, *shape)
    return out

