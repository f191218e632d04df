"""The capture levers (issue 30): per-view capture mode and speed per leg, where a fly-through mission's photos blur.

Fly-through shoots on the move: the photo of a view taken at a corner or during a heading change blurs (the
blur of the oracle, :mod:`wrp_eval.sim.blur`) and is taken at a heading the mission did not command. Stopping
there (settle, hover the dwell, shoot: :attr:`wrp_eval.planning.path.FlightPath.capture`) removes both at the
cost of the settle and the dwell. The lever stops at the views whose blur, over the initial path's own
campaign flights, reaches the limit at its 95th percentile: ``wrp.evaluate.capture_blur_limit_px``, 1 px by
default (the image-side motion during the exposure "should ideally not exceed 1 pixel", Phase One knowledge
base KA-01341; Map Pilot's rule of thumb keeps the ground smear below one GSD, Drones Made Easy support,
"Motion Blur and Automatic Light-based Speed Adjustment"). Blur and heading risk go together: over 64
fly-through flights of the inspection path the per-view 95th percentiles of blur and of the heading offset
rank the views alike (Spearman +0.39).

The blur is read from campaign trials the evaluation does not fly (trial ids from ``n_trials`` on: the
evaluation flies trials 0 .. n_trials - 1 under the campaign's seed), so the views are never chosen on the
flights that judge them. A view never taken in those flights is not a stop.

Placebo: as many stops at views chosen at random (seeded from the campaign seed; any view of the path, the first
and last included: fly-through takes the first at rest, where the flight starts, and the last as the reference
brakes to rest on it (its trigger plane, through the target normal to the arriving leg, is crossed on arrival, at
the residual speed of the tracking error, :func:`wrp_eval.sim.phases.passing_views`), so a stop there changes
little: a placebo of 64 stops on a 141-view path spends ~0.9 of them there on average, a slightly weaker
control), flown under the same winds; the verdict is the evaluation's (the gain's CI above 0 and above the
placebos' 95th percentile).

Speed per leg (``wrp.evaluate.slow_legs``): the same views, fly-through kept, but the legs arriving at and
leaving each of them flown at ``slow_leg_speed_m_s`` (:attr:`wrp_eval.planning.path.FlightPath.leg_speed_m_s`):
the translation blur scales with the speed at the shutter (:mod:`wrp_eval.sim.blur`), and a slower corner turns
the velocity in a smaller step (less tilt and heading swing at the shutter). Its placebos slow the legs at as many
views chosen at random (the same structure: a view's arriving and leaving legs).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from wrp_eval.campaign.config import TrialConfig
from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.sim.capture_mode import FLY_THROUGH
from wrp_eval.surrogate.data import load_campaign_trials

BLUR_QUANTILE = 95.0


def blurred_views(blur_px: np.ndarray, limit_px: float, quantile: float = BLUR_QUANTILE) -> np.ndarray:
    """(n,) bool: the views whose ``quantile`` percentile of the blur ``blur_px`` (k flights, n views) px, NaN
    where a flight did not take the view, exceeds ``limit_px``; a view no flight took is not one."""
    blur = np.asarray(blur_px, dtype=float)
    taken = np.isfinite(blur).any(axis=0)
    high = np.full(blur.shape[1], -np.inf)
    if taken.any():
        high[taken] = np.nanpercentile(blur[:, taken], quantile, axis=0)
    return high > limit_px


def held_out_blur(campaign_dir: str | Path, first_trial: int, path: FlightPath) -> np.ndarray:
    """(k, n) px: the blur of every view of ``path`` in the campaign's trials with ids >= ``first_trial`` (the
    trials an evaluation of ``first_trial`` flights does not fly); InputError when there are none, when the
    campaign flew another path or in stop mode."""
    flown = FlightPath.load(Path(campaign_dir) / "path.json")
    if len(flown) != len(path) or not np.allclose(flown.positions, path.positions, atol=1e-6):
        raise InputError(campaign_dir, f"its trials flew another path ({len(flown)} views) than the one evaluated "
                                       f"({len(path)} views, wrp.path)")
    meta = TrialStore(Path(campaign_dir)).read_meta()
    if meta is None or "config" not in meta:
        raise InputError(campaign_dir, "not a campaign folder (no campaign.json with its config)")
    mode = TrialConfig.from_stored(meta["config"]).sim.capture.mode
    if mode != FLY_THROUGH:
        raise InputError(campaign_dir, f"its flights were flown in {mode} mode: their blur says nothing of a "
                                       "fly-through mission's (the capture levers need a fly-through campaign)")
    trials = load_campaign_trials(campaign_dir, views=False)
    if trials.trial_id is None or not (held_out := trials.trial_id >= first_trial).any():
        raise InputError(campaign_dir, f"no trials beyond the evaluation's {first_trial} to choose the stops on "
                                       "(wrp.evaluate.capture_stops): fly a larger campaign")
    blur: np.ndarray = (np.full((int(held_out.sum()), trials.n_views), np.nan) if trials.conditions is None
                        else trials.conditions[held_out, :, 0])
    if not np.isfinite(blur).any():
        raise InputError(campaign_dir, "the campaign records no blur per view (wrp.evaluate.capture_stops needs it)")
    return blur


def legs_at(views: np.ndarray) -> np.ndarray:
    """(n - 1,) bool: the legs arriving at or leaving the ``views`` (n,) bool."""
    views = np.asarray(views, dtype=bool)
    legs: np.ndarray = views[1:] | views[:-1]
    return legs


def slow_leg_paths(initial: FlightPath, views: np.ndarray, speed_m_s: float, placebos: int,
                   rng: np.random.Generator) -> tuple[FlightPath, dict[str, FlightPath]]:
    """The initial path flying the legs at the ``views`` (n,) bool (:func:`legs_at`) at ``speed_m_s`` (the others
    at their own speed), and ``placebos`` paths slowing the legs at as many views chosen at random by ``rng`` (the
    same structure: each view's arriving and leaving legs), named ``placebo-slow-legs-NN``."""
    own = initial.leg_speeds()

    def slowed(at: np.ndarray, placebo_of: str | None = None) -> FlightPath:
        legs = legs_at(at)
        path = initial.with_leg_speeds(np.where(legs, np.minimum(own, speed_m_s), own))
        extra = {"slow_legs": int(legs.sum()), "slow_leg_speed_m_s": speed_m_s} if placebo_of is None \
            else {"placebo_of": placebo_of}
        return replace(path, metadata={**initial.metadata, **extra})

    return slowed(np.asarray(views, dtype=bool)), {
        f"placebo-slow-legs-{k:02d}": slowed(_random_views(len(initial), int(np.count_nonzero(views)), rng),
                                             "slow-legs")
        for k in range(placebos)}


def _random_views(n: int, count: int, rng: np.random.Generator) -> np.ndarray:
    """(n,) bool: ``count`` views chosen at random by ``rng``."""
    mask = np.zeros(n, dtype=bool)
    mask[rng.choice(n, size=count, replace=False)] = True
    return mask


def capture_lever_paths(initial: FlightPath, stops: np.ndarray, placebos: int,
                        rng: np.random.Generator) -> tuple[FlightPath, dict[str, FlightPath]]:
    """The initial (fly-through) path stopping at ``stops`` (n,) bool, and ``placebos`` paths stopping at as many
    views chosen at random by ``rng``, named ``placebo-stops-NN``."""
    def stopping(mask: np.ndarray, placebo_of: str | None = None) -> FlightPath:
        path = initial.with_stops(mask, FLY_THROUGH)
        extra = {"capture_stops": int(mask.sum())} if placebo_of is None else {"placebo_of": placebo_of}
        return replace(path, metadata={**initial.metadata, **extra})

    count = int(np.count_nonzero(stops))
    return stopping(np.asarray(stops, dtype=bool)), {
        f"placebo-stops-{k:02d}": stopping(_random_views(len(initial), count, rng), "stops") for k in range(placebos)}
