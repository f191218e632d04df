"""Per-viewpoint risk: how much each viewpoint contributes to the spread of the mission's error.

What spreads the error of a flown mission is mostly which views the flight did not take (the drone turned home
on the wind limit or the battery; issue 16) and, far less, how the taken ones were placed. So, per viewpoint i:

* loss_i (m): the oracle's error of the planned path without view i minus with it (what missing it costs; a
  view that only repeats others' coverage costs ~0);
* p_i: the share of the campaign's trials in which view i was not taken;
* risk_i = |loss_i| sqrt(p_i (1 - p_i)) (m): the standard deviation view i's presence adds to the error when
  it is missed independently with probability p_i.

First order: missed views come in runs (a flight home skips the rest of the tour), and the cost of missing two
neighbours is more than the sum of each; the map ranks views, it does not add up to the campaign's spread.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rerun as rr
from matplotlib import colormaps

from wrp_eval.campaign.records import column_array
from wrp_eval.campaign.store import TrialStore
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.recording import recording


@dataclass(frozen=True)
class ViewRisk:
    """loss_m (n,), p_missed (n,), risk_m (n,) per viewpoint (module docstring); base_error_m: the full path's."""

    loss_m: np.ndarray
    p_missed: np.ndarray
    risk_m: np.ndarray
    base_error_m: float


def campaign_flown_offsets(campaign_dir: str | Path) -> np.ndarray:
    """(n_trials, n_views, 4) every stored trial's flown offsets, NaN rows for views not taken (the surrogate's
    :class:`wrp_eval.surrogate.data.TrialData` sets a view not taken to offset 0 and flags it in its conditions)."""
    return column_array(TrialStore(campaign_dir).read_table(["n_views", "flown_offsets"]), "flown_offsets")


def view_risk(scored_ship, path, offsets: np.ndarray) -> ViewRisk:
    """The risk map of ``path`` from a campaign's flown ``offsets`` (n_trials, n_views, 4) (NaN rows: views not
    taken), scored by ``scored_ship`` (:class:`wrp_eval.recon.scored_ship.ScoredShip`): one oracle call per view."""
    full = captures_from_path(path)
    base = float(scored_ship.score(full, seed=0).error_m)
    n = len(path)
    loss = np.array([float(scored_ship.score(full.subset(np.arange(n) != i), seed=0).error_m) - base
                     for i in range(n)])   # one oracle call per left-out view: the oracle scores one set at a time
    missed = ~np.all(np.isfinite(np.asarray(offsets, dtype=float)), axis=2)
    p = missed.mean(axis=0) if len(missed) else np.zeros(n)
    loss = np.where(np.isfinite(loss), loss, np.nan)
    return ViewRisk(loss, p, np.abs(loss) * np.sqrt(p * (1.0 - p)), base)


def save_risk_recording(path, risk: ViewRisk, file: str | Path, recording_id: str | None = None) -> Path:
    """``file`` (.rrd, atomically): entity ``risk/viewpoints``, the viewpoints coloured by risk (same colour map
    as the report's figure), radius growing with it; static, ship frame, metres."""
    scale = float(np.nanmax(risk.risk_m)) if np.any(risk.risk_m > 0) else 1.0
    level = np.nan_to_num(risk.risk_m / scale)
    colours = (255 * colormaps["inferno_r"](level)[:, :3]).astype(np.uint8)
    labels = [f"view {i}: risk {1e3 * r:.2f} mm (missed in {100 * q:.0f} % of flights, costs {1e3 * c:+.2f} mm)"
              for i, (r, q, c) in enumerate(zip(np.nan_to_num(risk.risk_m), risk.p_missed,
                                                np.nan_to_num(risk.loss_m), strict=True))]
    with recording(file, recording_id=recording_id) as rec:
        rec.log("risk", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.log("risk/viewpoints", rr.Points3D(np.asarray(path.positions), colors=colours, radii=0.6 + 1.4 * level,
                                               labels=labels), static=True)
    return Path(file)
