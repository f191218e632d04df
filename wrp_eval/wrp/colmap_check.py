"""COLMAP's word on the evaluation's sign: does real photogrammetry agree that a WRP is
better or worse than the initial path under the same wind?

``wrp-eval evaluate CONFIG --colmap-check [--winds N]`` reads a finished evaluation folder (the initial path's,
ISWRP's and SWRP's campaigns, flown under common random numbers), picks N winds (trial ids that every path
flew without failing; seeded), rebuilds each flight's capture set from the store (the taken views' flown
poses, achieved gimbal pitch, roll, blur and recorded position priors) and scores it with the synthetic oracle
and with COLMAP (:class:`wrp_eval.recon.colmap.ColmapOracle`, rendered images; the ``photogrammetry`` extra).
Per wind and WRP: d = error(WRP) - error(initial) for each oracle and whether their signs agree; per WRP the
mean d of each oracle and the share of agreeing winds. A WRP that moved no viewpoint flies exactly the initial
path's flights (same winds, same seeds): d is 0 for both oracles and nothing is scored for it; a capture set
two paths share (ISWRP and SWRP can give the same path) is scored once.

Slow (one COLMAP reconstruction per capture set, ~1 min each on 2 cores): a validation command, not a test.
COLMAP's own noise on this ship is ~1.2 mm (recon/README.md, issue 17): differences below it are a coin flip
for it, so the summary also counts the winds where COLMAP's |d| exceeds ``COLMAP_NOISE_M``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from wrp_eval.atomic import write_json_atomic
from wrp_eval.campaign.records import column_array
from wrp_eval.errors import InputError
from wrp_eval.experiment import evaluated_campaign_dir
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.colmap import ColmapOracle
from wrp_eval.recon.synthetic import SyntheticOracle
from wrp_eval.recon.validate import capture_sha
from wrp_eval.surrogate.diagnostics import campaign_oracle
from wrp_eval.wrp.evaluate import read_trials

log = logging.getLogger(__name__)

COLMAP_NOISE_M = 0.0012      # COLMAP's error scatter on unchanged capture content (issue 17's jitter controls)
PATHS = ("initial", "iswrp", "swrp")


def flight_captures(campaign_dir: Path, trial_ids: np.ndarray, config_dir: str | Path = ".") -> dict:
    """{trial id: CaptureSet of the views that flight took} from a campaign folder's store."""
    scorer, store = campaign_oracle(campaign_dir, config_dir)
    table = store.read_table(["trial_id", "n_views", "flown_offsets", "camera_pitch", "camera_roll", "blur_px",
                              "estimated_offsets"])
    ids = table.column("trial_id").to_numpy()
    columns = {name: column_array(table, name) for name in ("flown_offsets", "camera_pitch", "camera_roll",
                                                             "blur_px", "estimated_offsets")}
    out = {}
    for trial in trial_ids:
        row = int(np.flatnonzero(ids == trial)[0])
        flown = columns["flown_offsets"][row]
        taken = np.all(np.isfinite(flown), axis=1)
        estimated = columns["estimated_offsets"][row]
        estimated = np.where(np.isfinite(estimated), estimated, flown)     # priors at the true pose if unrecorded
        cs = scorer.captures(np.nan_to_num(flown), columns["camera_pitch"][row], columns["camera_roll"][row],
                             columns["blur_px"][row], np.nan_to_num(estimated))
        out[int(trial)] = cs.subset(taken)
    return out


def common_winds(evaluate_dir: Path, winds: int, seed: int) -> np.ndarray:
    """``winds`` trial ids (sorted) that every path of the evaluation flew without failing (seeded choice)."""
    ok = None
    for name in PATHS:
        folder = evaluated_campaign_dir(evaluate_dir, name)
        if not (folder / "campaign.json").is_file():
            raise InputError(evaluate_dir, f"has no {folder.name}/: run `wrp-eval evaluate` first (the COLMAP check "
                                           "compares ISWRP and SWRP with the initial path: wrp.evaluate.kinds must "
                                           "name both)")
        trials = read_trials(name, folder)
        good = set(trials.trial_id[~trials.failed & np.isfinite(trials.error_m)].tolist())
        ok = good if ok is None else ok & good
    if ok is None:
        raise ValueError("no evaluated paths to compare (PATHS is empty)")
    ids = np.array(sorted(ok), dtype=int)
    if ids.size < winds:
        raise InputError(evaluate_dir, f"only {ids.size} winds flown by every path without failure; need {winds}")
    return np.sort(np.random.default_rng(seed).choice(ids, size=winds, replace=False))


def colmap_sign_check(evaluate_dir: str | Path, oracle_section, mesh, out: str | Path, winds: int = 10,
                      seed: int = 0, config_dir: str | Path = ".") -> dict:
    """The check of the module docstring; writes ``out``/colmap_check.json after every scored set (COLMAP's
    work under ``out``/colmap/PATH-TRIAL/) and returns its document."""
    evaluate_dir, out = Path(evaluate_dir), Path(out)
    ids = common_winds(evaluate_dir, winds, seed)
    synthetic, colmap = SyntheticOracle(oracle_section), ColmapOracle(oracle_section)
    captures = {name: flight_captures(evaluated_campaign_dir(evaluate_dir, name), ids, config_dir)
                for name in PATHS}
    moved = {name: _path_differs(evaluate_dir, name) for name in PATHS[1:]}
    scores: dict = {name: {} for name in PATHS}
    scored: dict[str, tuple[float, float]] = {}      # capture set -> scores: ISWRP and SWRP may fly one path
    doc = {"winds": ids.tolist(), "colmap_noise_m": COLMAP_NOISE_M, "rows": [], "wrp": {}}
    for trial in ids:
        for name in PATHS:
            if name != "initial" and not moved[name]:
                continue
            cs = captures[name][int(trial)]
            key = capture_sha(cs)
            if key not in scored:
                colmap.work_dir = out / "colmap" / f"{name}-{trial}"
                scored[key] = (_error(synthetic.evaluate(cs, mesh, seed=0)), _error(colmap.evaluate(cs, mesh, seed=0)))
            syn, col = scores[name][int(trial)] = scored[key]
            log.info(f"wind {trial} {name:8s} synthetic {syn * 1e3:8.2f} mm  colmap {col * 1e3:8.2f} mm")
        doc["rows"] = _rows(scores, moved)
        doc["wrp"] = _summary(doc["rows"], moved)
        write_json_atomic(out / "colmap_check.json", doc)
    return doc


def _error(result) -> float:
    """A ReconResult's error (m), NaN where the reconstruction gave none."""
    return float(result.error_m) if result.error_m is not None else float("nan")


def _path_differs(evaluate_dir: Path, name: str) -> bool:
    """Whether the WRP ``name`` moved any viewpoint (its path.json differs from the initial path's)."""
    a = FlightPath.load(evaluated_campaign_dir(evaluate_dir, "initial") / "path.json")
    b = FlightPath.load(evaluated_campaign_dir(evaluate_dir, name) / "path.json")
    return not (np.allclose(a.positions, b.positions, atol=1e-9) and np.allclose(a.yaw, b.yaw, atol=1e-12))


def _rows(scores: dict, moved: dict) -> list[dict]:
    rows = []
    for trial, (syn0, col0) in scores["initial"].items():
        for name in PATHS[1:]:
            if not moved[name] or trial not in scores[name]:
                continue
            syn, col = scores[name][trial]
            d_syn, d_col = syn - syn0, col - col0
            scored = bool(np.isfinite(d_syn) and np.isfinite(d_col))     # an oracle without a result: no vote
            rows.append({"wind": trial, "wrp": name, "synthetic_diff_m": d_syn, "colmap_diff_m": d_col,
                         "scored": scored, "signs_agree": bool(scored and np.sign(d_syn) == np.sign(d_col)),
                         "colmap_above_noise": bool(scored and abs(d_col) > COLMAP_NOISE_M)})
    return rows


def _summary(rows: list[dict], moved: dict) -> dict:
    out = {}
    for name in PATHS[1:]:
        every = [r for r in rows if r["wrp"] == name]
        mine = [r for r in every if r["scored"]]
        if not moved[name]:
            out[name] = {"moved": False, "note": "no viewpoint moved: the WRP flies the initial path's flights"}
            continue
        if not mine:
            continue
        d_syn = np.array([r["synthetic_diff_m"] for r in mine], float)
        d_col = np.array([r["colmap_diff_m"] for r in mine], float)
        above = [r for r in mine if r["colmap_above_noise"]]
        out[name] = {"moved": True, "winds": len(mine), "winds_without_a_result": len(every) - len(mine),
                     "synthetic_mean_diff_m": float(np.nanmean(d_syn)),
                     "colmap_mean_diff_m": float(np.nanmean(d_col)),
                     "mean_signs_agree": bool(np.sign(np.nanmean(d_syn)) == np.sign(np.nanmean(d_col))),
                     "sign_agreement": float(np.mean([r["signs_agree"] for r in mine])),
                     "winds_colmap_above_noise": len(above),
                     "sign_agreement_above_noise": (float(np.mean([r["signs_agree"] for r in above]))
                                                    if above else None)}
    return out
