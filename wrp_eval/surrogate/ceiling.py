"""How well can ANY surrogate fit a campaign's errors? The oracle's variance below the UAV's own precision.

The synthetic oracle is deterministic for given poses and seed, but not smooth: a pose change of a few
centimetres flips discrete decisions (which ray matches in which partner view, which views are partners,
the order of registration), and the error moves by a fraction of a millimetre even where its trend is flat
(measured on the quickstart ship: 1 mm per-view jitter -> 0.2 mm std, 5 cm -> 0.7 mm, on a 23 mm error).
No regression on the offsets can resolve that: two flights the UAV cannot tell apart (its calm-air tracking
is ~2-3 cm and ~0.1 deg, see wrp_eval/sim) get errors that differ by it.

:func:`oracle_roughness` re-scores stored trials with the flown poses jittered at that scale (independent
Gaussian per viewpoint, ``position_jitter_m`` per axis and ``yaw_jitter_rad``), takes the mean within-trial
variance of the error as the part no surrogate can learn, and reports ``r2_ceiling`` = 1 - that / the
variance of the campaign's errors (trials that did not fail): the held-out R^2 a perfect surrogate of the
smooth trend would reach on this data. It is an estimate (a finite number of trials and repeats), returned
with its inputs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wrp_eval.errors import InputError


def oracle_roughness(campaign_dir: str | Path, *, n_trials: int = 60, repeats: int = 5,
                     position_jitter_m: float = 0.02, yaw_jitter_rad: float = 0.002, seed: int = 0,
                     config_dir: str | Path = ".") -> dict:
    """Roughness of the oracle on a campaign's own trials and the R^2 ceiling it implies.

    Draws ``n_trials`` trials that did not fail (seeded), re-scores each ``repeats`` times with its flown poses
    jittered, with the trial's own oracle seed. Returns noise_var_m2 (mean within-trial variance), noise_std_m,
    total_var_m2 (variance of error_m over every trial that did not fail), r2_ceiling, and the settings.
    """
    from wrp_eval.campaign.records import column_array
    from wrp_eval.campaign.store import TrialStore
    from wrp_eval.config import ExperimentConfig
    from wrp_eval.planning.path import Path as FlightPath
    from wrp_eval.recon import make_oracle
    from wrp_eval.ship.resolve import resolve_ship_full
    from wrp_eval.sim.captures import CaptureSet

    folder = Path(campaign_dir)
    store = TrialStore(folder)
    meta = store.read_meta()
    if meta is None:
        raise InputError(folder, "not a campaign folder (no campaign.json)")
    if repeats < 2:
        raise InputError("oracle_roughness", f"repeats must be >= 2 to measure a variance, got {repeats}")
    config = ExperimentConfig.model_validate(meta["config"])
    table = store.read_table(["n_views", "flown_offsets", "error_m", "failed", "oracle_seed"])
    flown = column_array(table, "flown_offsets")
    error = table.column("error_m").to_numpy(zero_copy_only=False).astype(float)
    failed = table.column("failed").to_numpy(zero_copy_only=False).astype(bool)
    oracle_seed = table.column("oracle_seed").to_numpy().astype(np.int64)
    usable = np.flatnonzero(~failed & np.isfinite(error) & np.all(np.isfinite(flown), axis=(1, 2)))
    if usable.size < 3:
        raise InputError(folder, f"only {usable.size} trials without failure; need at least 3")
    path = FlightPath.load(folder / "path.json")
    ship = resolve_ship_full(config.ship, config_dir)
    oracle = make_oracle(config.oracle, config.campaign.oracle)
    planned = np.concatenate([np.asarray(path.positions, float), np.asarray(path.yaw, float)[:, None]], axis=1)
    pitch = np.asarray(path.pitch, float)
    rng = np.random.default_rng(seed)
    chosen = rng.choice(usable, size=min(n_trials, usable.size), replace=False)
    n = len(path)
    scores = np.empty((chosen.size, repeats))
    for row, trial in enumerate(chosen):   # one oracle call per capture set: the oracle is not batched
        for rep in range(repeats):
            jitter = np.concatenate([rng.normal(0.0, position_jitter_m, (n, 3)),
                                     rng.normal(0.0, yaw_jitter_rad, (n, 1))], axis=1)
            pose = planned + flown[trial] + jitter
            captures = CaptureSet(pose[:, :3], pose[:, 3], pitch, np.arange(n), path.camera)
            scores[row, rep] = oracle.evaluate(captures, ship.mesh,
                                               seed=int(oracle_seed[trial] % (2**31 - 1))).error_m
    finite = np.all(np.isfinite(scores), axis=1)
    if not finite.any():
        raise InputError(folder, "the oracle returned no finite error on the re-scored trials")
    noise_var = float(np.var(scores[finite], axis=1, ddof=1).mean())
    total_var = float(np.var(error[usable]))
    return {"noise_var_m2": noise_var, "noise_std_m": float(np.sqrt(noise_var)), "total_var_m2": total_var,
            "r2_ceiling": 1.0 - noise_var / total_var if total_var > 0 else float("nan"),
            "n_trials": int(finite.sum()), "repeats": int(repeats), "position_jitter_m": position_jitter_m,
            "yaw_jitter_rad": yaw_jitter_rad, "seed": seed}
