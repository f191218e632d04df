"""Test helpers shared with tests/wrp: a planned path and a campaign folder written through the campaign
stage's own store."""

from __future__ import annotations

import numpy as np


def make_path(n_views: int):
    """A simple planned path: a ring of viewpoints around the origin looking inwards."""
    from wrp_eval.planning.path import FlightPath
    s = np.linspace(0, 2 * np.pi, n_views, endpoint=False)
    positions = np.column_stack([60 * np.cos(s), 25 * np.sin(s), np.full(n_views, 15.0)])
    return FlightPath(positions, s + np.pi, np.full(n_views, -0.3), np.zeros(n_views, int),
                      np.zeros(n_views, int), np.zeros(n_views, int))


def make_campaign(folder, n_trials: int, n_views: int, seed: int = 0, nan_trials=(), failed_trials=(),
                  registered=None, blur_px=None, trial_config=None):
    """A campaign folder written through the campaign stage's own store: commanded offsets in a box, a
    wind-induced deviation of known spread (0.3 m per axis, normal), error from the known function; the
    default trial config (its ship gives the per-view coverage). ``registered`` {trial: (n_views,) 1 / 0 / NaN}:
    the view_registered column of those trials (the others store none); ``blur_px`` (n_trials, n_views) px: the
    blur column of every trial (None: none stored); ``trial_config``: the stored trial config's settings (None: the
    default)."""
    from wrp_eval.campaign.config import TrialConfig
    from wrp_eval.campaign.store import TrialStore
    from wrp_eval.planning.path import digest_of_document as path_digest
    from wrp_eval.surrogate.data import known_function, known_function_trials
    rng = np.random.default_rng(seed)
    path = make_path(n_views)
    doc = path.to_json_dict()
    digest = path_digest(doc)
    commanded = rng.uniform(-1, 1, (n_trials, n_views, 4)) * np.array([2, 2, 2, np.radians(20)])
    deviation = rng.normal(0, 0.3, (n_trials, n_views, 4)) * np.array([1, 1, 1, 0.05])
    flown = commanded + deviation
    _, params = known_function_trials(1, n_views, np.random.default_rng(0))
    error = known_function(flown, params) + rng.normal(0, 0.005, n_trials)
    records = []
    for k in range(n_trials):
        f = flown[k].copy()
        if k in nan_trials:
            f[0] = np.nan
        records.append({"trial_id": k, "path_digest": digest, "n_views": n_views,
                        "commanded_offsets": commanded[k].tolist(), "flown_offsets": f.tolist(),
                        "error_m": float("nan") if k in failed_trials else float(error[k]),
                        "failed": k in failed_trials, "oracle_seed": 1000 + k,
                        **({"view_registered": list(registered[k])} if registered and k in registered else {}),
                        **({"blur_px": [float(b) for b in blur_px[k]]} if blur_px is not None else {})})
    with TrialStore(folder) as store:
        store.write_meta({"path_digest": digest, "n_views": n_views, "n_trials": n_trials,
                          "config": TrialConfig.model_validate(trial_config or {}).model_dump(mode="json")},
                         doc)   # the default (stylized) ship
        store.append(records[: n_trials // 2])
        store.append(records[n_trials // 2:])
    return path, digest, commanded, flown, error
