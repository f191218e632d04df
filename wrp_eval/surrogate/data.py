"""Training data of the surrogate: a small value type, the campaign adapter, the split, a known test function.

Offsets are measured from the PLANNED viewpoints of one path: (dx, dy, dz) m in the ship frame and dyaw rad
(the campaign stage's convention, wrp_eval/campaign/records.py). The surrogate learns the flown offsets ->
oracle error map (the paper's fit function f(p, a), Sec. 4.1).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wrp_eval.campaign.config import TrialConfig
from wrp_eval.campaign.records import column_array
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recon.scored_ship import scored_ship
from wrp_eval.surrogate.features import CONDITION_NAMES, ViewContext, campaign_view_context, reference_conditions
from wrp_eval.surrogate.scarce import ScarceCoverage, ship_scarce_coverage

POSE_NAMES = ("x_m", "y_m", "z_m", "cos_yaw", "sin_yaw", "pitch_rad", "index")


@dataclass(frozen=True)
class TrialData:
    """Trials of one path.

    offsets (n_trials, n_views, 4): flown offsets (dx, dy, dz m, dyaw rad; 0 where a view was not taken, see
    ``conditions``); error (n_trials,) m: the oracle's
    reconstruction error (NaN where none); failed (n_trials,) bool; planned_pose (n_views, 7) or None: the
    planned pose features of every viewpoint (:data:`POSE_NAMES`); trial_id (n_trials,) int;
    path_digest: the campaign's content hash of the path (None for data not tied to a stored path);
    deviation (n_trials, n_views, 4) or None: the wind-induced part (flown - commanded), for r_s;
    conditions (n_trials, n_views, 5) or None: blur px and wind m/s at each view and whether it was taken
    (:data:`CONDITION_NAMES`; NaN where not recorded; None: none recorded); views: the path's
    :class:`ViewContext` (None: per-view inputs unavailable, only the ``offsets`` input set can be trained);
    registered (n_trials, n_views) or None: 1 where the oracle registered the view, 0 where it did not, NaN where
    the view was not taken or the store does not record it (the campaign's ``view_registered``);
    scarce: the path's :class:`~wrp_eval.surrogate.scarce.ScarceCoverage` on the ship (None: the ``scarce`` input
    set cannot be trained).
    """

    offsets: np.ndarray
    error: np.ndarray
    failed: np.ndarray
    planned_pose: np.ndarray | None = None
    trial_id: np.ndarray | None = None
    path_digest: str | None = None
    deviation: np.ndarray | None = None
    source: str = ""
    conditions: np.ndarray | None = None
    views: ViewContext | None = None
    registered: np.ndarray | None = None
    scarce: ScarceCoverage | None = None

    @property
    def n_trials(self) -> int:
        return int(self.offsets.shape[0])

    @property
    def n_views(self) -> int:
        return int(self.offsets.shape[1])

    def complete(self) -> np.ndarray:
        """(n_trials,) bool: the flight took every view (True where the data does not record it)."""
        if self.conditions is None:
            return np.ones(self.n_trials, bool)
        return ~np.any(np.asarray(self.conditions, float)[..., -1] < 0.5, axis=1)

    def targeted(self) -> np.ndarray:
        """(n_trials,) bool: the campaign commanded some view off the plan (the targeted trials of the physical
        design; every trial of the box and common designs; False where the data records no commanded offsets)."""
        if self.deviation is None:
            return np.zeros(self.n_trials, bool)
        commanded = np.asarray(self.offsets, float) - np.asarray(self.deviation, float)
        return np.any(np.abs(np.nan_to_num(commanded)) > 1e-9, axis=(1, 2))

    def __post_init__(self) -> None:
        off = np.asarray(self.offsets)
        if off.ndim != 3 or off.shape[2] != 4:
            raise InputError(self.source or "trial data", f"offsets must be (n_trials, n_views, 4), got {off.shape}")
        if np.asarray(self.error).shape != (off.shape[0],):
            raise InputError(self.source or "trial data",
                             f"error must be ({off.shape[0]},), got {np.asarray(self.error).shape}")
        if self.planned_pose is not None and np.asarray(self.planned_pose).shape[0] != off.shape[1]:
            raise InputError(self.source or "trial data", "planned_pose has a different number of viewpoints")
        if self.conditions is not None and np.asarray(self.conditions).shape != (*off.shape[:2], len(CONDITION_NAMES)):
            raise InputError(self.source or "trial data",
                             f"conditions must be {(*off.shape[:2], len(CONDITION_NAMES))}")
        if self.views is not None and len(self.views) != off.shape[1]:
            raise InputError(self.source or "trial data", "views has a different number of viewpoints")
        if self.registered is not None and np.asarray(self.registered).shape != off.shape[:2]:
            raise InputError(self.source or "trial data", f"registered must be {off.shape[:2]}")


def physical_variance_share(data: TrialData) -> dict[str, float] | None:
    """How much of the flown offsets' variance the flights made: per component group, the summed
    variance of the wind-induced part (flown - commanded) over the summed variance of the flown offsets, over
    every trial x viewpoint taken: ``position`` (x, y, z, m^2 / m^2) and ``yaw``. None without a deviation."""
    if data.deviation is None:
        return None
    flown = np.asarray(data.offsets, dtype=float).reshape(-1, 4)
    dev = np.asarray(data.deviation, dtype=float).reshape(-1, 4)
    ok = np.all(np.isfinite(flown), axis=1) & np.all(np.isfinite(dev), axis=1)
    if ok.sum() < 2:
        return None
    v_flown, v_dev = flown[ok].var(axis=0), dev[ok].var(axis=0)
    return {"position": float(v_dev[:3].sum() / v_flown[:3].sum()) if v_flown[:3].sum() > 0 else 1.0,
            "yaw": float(v_dev[3] / v_flown[3]) if v_flown[3] > 0 else 1.0}


def planned_pose_features(positions: np.ndarray, yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """(n_views, 7) pose features of a path: x, y, z (m), cos yaw, sin yaw, pitch (rad), index / (n - 1)."""
    n = positions.shape[0]
    index = np.arange(n) / max(1, n - 1)
    return np.column_stack([positions, np.cos(yaw), np.sin(yaw), pitch, index]).astype(float)


def path_pose_features(path) -> np.ndarray:
    """Pose features of a :class:`wrp_eval.planning.path.FlightPath`."""
    return planned_pose_features(np.asarray(path.positions, float), np.asarray(path.yaw, float),
                                 np.asarray(path.pitch, float))


def load_campaign_trials(campaign_dir: str | Path, *, views: bool = True, config_dir: str | Path = ".",
                         scarce: bool = False) -> TrialData:
    """The trials of a campaign folder (the campaign stage's ``TrialStore``): flown offsets, error_m, failed,
    the conditions at each view (blur, wind) and, with ``views``, the path's :class:`ViewContext` (the ship and
    oracle of the campaign's stored config, resolved relative to ``config_dir``: ~1 s; None without a stored
    config), with ``scarce`` too its :class:`ScarceCoverage` (~0.2 s for 141 views), and which views the oracle
    registered (NaN in stores written before that column).

    A view a flight did not take (it turned home, or the trial raised) gets offset 0 and the condition
    ``taken`` 0 (its other conditions NaN): such trials stay, since what a missing view costs is what each
    view's coverage is worth; trials without any view are dropped and counted in ``source``. The planned pose
    comes from the folder's path.json; trials are returned in trial-id order.
    """

    folder = Path(campaign_dir)
    store = TrialStore(folder)
    meta = store.read_meta()
    if meta is None:
        raise InputError(folder, "not a campaign folder (no campaign.json); run `wrp-eval campaign` first")
    table = store.read_table(["trial_id", "n_views", "path_digest", "commanded_offsets", "flown_offsets",
                              "error_m", "failed", "blur_px", "wind_at_views", "view_registered"])
    if len(table) == 0:
        raise InputError(folder, "the campaign has no stored trials yet")
    path = FlightPath.load(folder / "path.json")
    flown = column_array(table, "flown_offsets")
    commanded = column_array(table, "commanded_offsets")
    if flown.shape[1] != len(path):
        raise InputError(folder, f"trials have {flown.shape[1]} viewpoints but path.json has {len(path)}")
    digests = set(table.column("path_digest").to_pylist())
    if len(digests) != 1:
        raise InputError(folder, f"trials of {len(digests)} different paths in one store")
    error = table.column("error_m").to_numpy(zero_copy_only=False).astype(float)
    failed = table.column("failed").to_numpy(zero_copy_only=False).astype(bool)
    trial_id = table.column("trial_id").to_numpy().astype(int)
    taken = np.all(np.isfinite(flown), axis=2)                     # (trials, views): the view was photographed
    usable = taken.any(axis=1)
    order = np.argsort(trial_id[usable], kind="stable")
    keep = np.flatnonzero(usable)[order]
    dropped = int((~usable).sum())
    incomplete = int((~taken[keep].all(axis=1)).sum())
    conditions = np.concatenate([column_array(table, "blur_px")[..., None], column_array(table, "wind_at_views"),
                                 taken[..., None].astype(float)], axis=2)[keep]
    context = scarce_cover = None
    if views and "config" in meta:     # a store written without its config (tests) has no ship to look at
        trial = TrialConfig.from_stored(meta["config"])
        ship = scored_ship(trial.ship, trial.oracle, trial.campaign.oracle, config_dir)
        context = campaign_view_context(ship, path, conditions)
        scarce_cover = ship_scarce_coverage(ship, captures_from_path(path)) if scarce else None
    return TrialData(offsets=np.nan_to_num(flown[keep]), error=error[keep], failed=failed[keep],
                     planned_pose=path_pose_features(path), trial_id=trial_id[keep],
                     path_digest=str(meta.get("path_digest", digests.pop())),
                     deviation=flown[keep] - commanded[keep], conditions=conditions, views=context,
                     registered=column_array(table, "view_registered")[keep], scarce=scarce_cover,
                     source=f"{folder} ({len(keep)} trials, {incomplete} of them with views not taken; "
                            f"{dropped} without any view)")


def split_indices(n: int, val_fraction: float, test_fraction: float,
                  rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A random partition of ``range(n)`` trials into (train, val, test) index arrays (each sorted)."""
    n_test = max(1, int(round(test_fraction * n)))
    n_val = max(1, int(round(val_fraction * n)))
    if n - n_test - n_val < 2:
        raise InputError("surrogate data", f"{n} usable trials are too few to split into train/val/test")
    perm = rng.permutation(n)
    return np.sort(perm[n_test + n_val:]), np.sort(perm[n_test:n_test + n_val]), np.sort(perm[:n_test])


def known_function_trials(n_trials: int, n_views: int, rng: np.random.Generator, *,
                          position_half_width_m: float = 2.0, yaw_half_width_rad: float = np.radians(20.0),
                          noise_m: float = 0.01) -> tuple[TrialData, dict]:
    """Trials from a KNOWN smooth function of the offsets, for testing and timing the learner (NOT a model of
    reconstruction): error = base + sum_i w_i (dx_i^2 + dy_i^2 + 0.5 dz_i^2) + sum_i u_i dyaw_i^2
    + c * sum_i (dx_i dx_{i+1}) / n + N(0, noise). Offsets uniform in the box; w_i, u_i > 0 vary smoothly
    along the path so that the planned-pose channels matter. Returns the data and the function's parameters.
    """
    half = np.array([position_half_width_m] * 3 + [yaw_half_width_rad])
    offsets = rng.uniform(-1.0, 1.0, size=(n_trials, n_views, 4)) * half
    s = np.linspace(0.0, 2.0 * np.pi, n_views)
    w = (0.02 + 0.015 * np.sin(s)) / n_views * 10.0
    u = (0.5 + 0.4 * np.cos(s)) / n_views * 10.0
    params = {"base": 0.5, "w": w, "u": u, "c": 0.05}
    error = known_function(offsets, params) + rng.normal(0.0, noise_m, n_trials)
    positions = np.column_stack([70.0 * np.cos(s), 20.0 * np.sin(s), 15.0 + 5.0 * np.sin(2 * s)])
    pose = planned_pose_features(positions, s + np.pi, np.full(n_views, -0.3))
    target = positions * np.array([0.7, 0.3, 0.5])          # a patch between the view and the origin
    normal = (positions - target) / np.linalg.norm(positions - target, axis=1, keepdims=True)
    views = ViewContext(positions, s + np.pi, np.full(n_views, -0.3), target, normal, np.full(n_views, 0.2),
                        np.full(n_views, 10.0), reference_conditions(None, n_views))
    data = TrialData(offsets=offsets, error=error, failed=np.zeros(n_trials, bool), planned_pose=pose,
                     trial_id=np.arange(n_trials), path_digest=None, source="known function", views=views)
    return data, params


def known_function(offsets: np.ndarray, params: dict) -> np.ndarray:
    """The noiseless error of :func:`known_function_trials` for offsets (batch, n_views, 4)."""
    dx, dy, dz, dyaw = (offsets[..., k] for k in range(4))
    n = offsets.shape[-2]
    return (params["base"] + (params["w"] * (dx ** 2 + dy ** 2 + 0.5 * dz ** 2)).sum(-1)
            + (params["u"] * dyaw ** 2).sum(-1) + params["c"] * (dx[..., :-1] * dx[..., 1:]).sum(-1) / n)


