"""What each trial draws: its wind scenario, its commanded viewpoint offsets and its flown-offset disturbance.

Seeding (reproducible, independent of which other trials run, of the batching and of the backend): every draw
of trial k comes from ``SeedSequence(root_seed, spawn_key=(stream, k, ...))`` -- the same numbers as
``SeedSequence(root_seed).spawn`` produces for child k, addressed directly so that trial k never needs the
others. Streams:

* ``WIND_STREAM``: the scenario inputs (one child per input, so changing one input's distribution leaves the
  others' draws unchanged) and the wind realisation's seed. Nothing here depends on the path, so trials with
  the same id of different paths fly the same wind (common random numbers).
* ``PERTURB_STREAM``: the box design (one scrambled Sobol / LHS design per campaign; trial k takes point k),
  and, for the common design, the per-viewpoint disturbance of trial k (child (k,)).
* ``DISTURB_STREAM``: the paper's extra random disturbance of the flown offsets.
* ``FLIGHT_STREAM``: seeds handed to the flight and the oracle for any randomness of their own.
* ``TARGET_STREAM``: the physical design's targeted trials (whether, which run of viewpoints, their offsets).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.stats import qmc

from wrp_eval.campaign.config import CampaignSection, Choice, Normal, Uniform
from wrp_eval.streams import flight_generators, redrawn_seed
from wrp_eval.wind.config import WindSection

WIND_STREAM, PERTURB_STREAM, DISTURB_STREAM, FLIGHT_STREAM, TARGET_STREAM = 0, 1, 2, 3, 4
# child index of each wind input within the trial's WIND_STREAM children
_WIND_INPUTS = ("speed_10m_m_s", "direction_deg", "severity", "sigma_w_m_s", "file", "time", "seed")


def trial_rng(root_seed: int, *key: int) -> np.random.Generator:
    """The generator of one stream of one trial: ``SeedSequence(root_seed, spawn_key=key)``."""
    return np.random.default_rng(np.random.SeedSequence(root_seed, spawn_key=tuple(int(k) for k in key)))


def draw_value(spec, rng: np.random.Generator):
    """One draw of a config value: a fixed value is returned as is, a distribution is sampled."""
    if isinstance(spec, Uniform):
        return float(rng.uniform(spec.low, spec.high))
    if isinstance(spec, Normal):
        value = float(rng.normal(spec.mean, spec.std))
        return float(np.clip(value, *spec.clip)) if spec.clip is not None else value
    if isinstance(spec, Choice):
        p = None
        if spec.weights is not None:
            p = np.asarray(spec.weights, dtype=float) / float(np.sum(spec.weights))
        return spec.values[int(rng.choice(len(spec.values), p=p))]
    return spec


@dataclass(frozen=True)
class WindDraw:
    """The wind scenario of one trial, in the wind stage's conventions. speed_10m_m_s: mean wind at 10 m
    above the sea; direction_deg: meteorological (blowing FROM, clockwise from north); severity: Dryden
    severity; sigma_w_m_s: explicit turbulence intensity or None; file/time: mesoscale output (None: the
    ``wind:`` section's); seed: of the turbulence (and gust) realisation."""

    speed_10m_m_s: float
    direction_deg: float
    severity: str
    sigma_w_m_s: float | None
    file: str | None
    time: str | None
    seed: int


def trial_wind_section(base: WindSection, draw: WindDraw) -> WindSection:
    """The ``wind:`` section of one trial: the base with the trial's drawn values.

    speed/direction apply to the synthetic source (a netCDF field brings its own); ``severity`` replaces the
    turbulence severity; an explicit ``sigma_w_m_s`` replaces the intensity; ``file``/``time`` (None: keep the
    base's) pick the mesoscale output."""
    turbulence = base.turbulence.model_copy(update={"severity": draw.severity, "sigma_w_m_s": draw.sigma_w_m_s})
    update = {"speed_10m_m_s": draw.speed_10m_m_s, "direction_deg": draw.direction_deg % 360.0,
              "turbulence": turbulence}
    if draw.file is not None:
        update["file"] = draw.file
    if draw.time is not None:
        update["time"] = draw.time
    return base.model_copy(update=update)


def trial_wind_rng(draw: WindDraw, noise_draw: int = 0) -> np.random.Generator:
    """The generator of the trial's wind realisation (its turbulence and gusts): flight 0 of a batch of one
    seeded by ``draw.seed`` (:func:`wrp_eval.streams.flight_generators`), whatever batch the trial flies
    in, so a trial's wind never depends on the others; ``noise_draw`` > 0: another realisation of the same
    weather (:func:`wrp_eval.streams.redrawn_seed`)."""
    return flight_generators(redrawn_seed(draw.seed, noise_draw), 1)[0]


def draw_wind(section: CampaignSection, root_seed: int, trial_id: int) -> WindDraw:
    """The wind of trial ``trial_id``; depends only on (root_seed, trial_id, section.wind), not on the path."""
    spec = section.wind
    specs = {"speed_10m_m_s": spec.speed_10m_m_s, "direction_deg": spec.direction_deg,
             "severity": spec.turbulence.severity, "sigma_w_m_s": spec.turbulence.sigma_w_m_s,
             "file": spec.mesoscale.file, "time": spec.mesoscale.time}
    values = {name: draw_value(specs[name], trial_rng(root_seed, WIND_STREAM, trial_id, j))
              for j, name in enumerate(_WIND_INPUTS[:-1])}
    seed = int(trial_rng(root_seed, WIND_STREAM, trial_id, len(_WIND_INPUTS) - 1).integers(2**63 - 1))
    sigma = values["sigma_w_m_s"]
    return WindDraw(speed_10m_m_s=float(values["speed_10m_m_s"]),
                    direction_deg=float(values["direction_deg"]) % 360.0,
                    severity=str(values["severity"]), sigma_w_m_s=None if sigma is None else max(0.0, float(sigma)),
                    file=None if values["file"] is None else str(values["file"]),
                    time=None if values["time"] is None else str(values["time"]), seed=seed)


@lru_cache(maxsize=8)
def _lhs_design(root_seed: int, n_trials: int, dims: int) -> np.ndarray:
    """(n_trials, dims) Latin hypercube in [0, 1): one per campaign, cached per process."""
    engine = qmc.LatinHypercube(d=dims, seed=np.random.default_rng(
        np.random.SeedSequence(root_seed, spawn_key=(PERTURB_STREAM,))))
    return engine.random(n_trials)


@lru_cache(maxsize=8)
def _sobol_engine(root_seed: int, dims: int) -> qmc.Sobol:
    return qmc.Sobol(d=dims, scramble=True, seed=np.random.default_rng(
        np.random.SeedSequence(root_seed, spawn_key=(PERTURB_STREAM,))))


def unit_design_point(sampler: str, root_seed: int, n_trials: int, trial_id: int, dims: int) -> np.ndarray:
    """Point ``trial_id`` of the campaign's design in [0, 1)^dims."""
    if sampler == "lhs":
        return _lhs_design(root_seed, n_trials, dims)[trial_id]
    engine = _sobol_engine(root_seed, dims)
    engine.reset()
    if trial_id:  # scipy's fast_forward(0) overflows
        engine.fast_forward(trial_id)
    return engine.random(1)[0]


def targeted_offsets(section: CampaignSection, root_seed: int, trial_id: int, n_views: int) -> np.ndarray:
    """(n_views, 4) the physical design's commanded offsets of trial ``trial_id``: zero, except in a
    ``targeted_share`` of the trials a run of 1..``targeted_max_views`` consecutive viewpoints with Gaussian
    offsets (position std per axis, yaw std; see :class:`wrp_eval.campaign.config.Perturbation`)."""
    pert = section.perturbation
    out = np.zeros((n_views, 4))
    rng = trial_rng(root_seed, TARGET_STREAM, trial_id)
    if n_views == 0 or rng.random() >= pert.targeted_share:
        return out
    length = int(rng.integers(1, min(pert.targeted_max_views, n_views) + 1))
    start = int(rng.integers(0, n_views - length + 1))
    sigma = np.array([pert.targeted_position_sigma_m] * 3 + [np.radians(pert.targeted_yaw_sigma_deg)])
    out[start:start + length] = rng.normal(0.0, 1.0, size=(length, 4)) * sigma
    return out


def commanded_offsets(section: CampaignSection, root_seed: int, trial_id: int, n_views: int) -> np.ndarray:
    """(n_views, 4) commanded offsets (dx, dy, dz m, dyaw rad) of trial ``trial_id`` from the planned views."""
    pert = section.perturbation
    if pert.design == "physical":
        return targeted_offsets(section, root_seed, trial_id, n_views)
    if pert.design == "none":
        return np.zeros((n_views, 4))
    half = np.array([pert.position_half_width_m] * 3 + [np.radians(pert.yaw_half_width_deg)])
    if pert.design == "common":
        common = (2.0 * unit_design_point(pert.sampler, root_seed, section.n_trials, trial_id, 4) - 1.0) * half
        rng = trial_rng(root_seed, PERTURB_STREAM, trial_id)
        e = rng.uniform(-pert.view_disturbance, pert.view_disturbance, size=(n_views, 4))
        jitter = rng.uniform(-1.0, 1.0, size=(n_views, 4)) * pert.view_jitter * half
        offsets = common * (1.0 + e) + jitter
        if pert.solo_views:  # drawn after the others: solo_views 0 keeps earlier campaigns' numbers
            solo = rng.choice(n_views, size=min(pert.solo_views, n_views), replace=False)
            offsets[solo] = rng.uniform(-1.0, 1.0, size=(len(solo), 4)) * half
        return offsets
    u = unit_design_point(pert.sampler, root_seed, section.n_trials, trial_id, 4 * n_views).reshape(n_views, 4)
    return (2.0 * u - 1.0) * half


def disturbance_factors(section: CampaignSection, root_seed: int, trial_id: int, n_views: int) -> np.ndarray:
    """(n_views, 4) factors (1 + e), e ~ U(-f, f), applied to the wind-induced part of the flown offsets."""
    f = section.perturbation.flown_disturbance
    if section.perturbation.design == "physical":
        return np.ones((n_views, 4))
    rng = trial_rng(root_seed, DISTURB_STREAM, trial_id)
    e = rng.uniform(-f, f, size=(n_views, 4)) if f > 0 else np.zeros((n_views, 4))
    return 1.0 + e


@dataclass(frozen=True)
class TrialInputs:
    """Everything a trial's evaluation needs besides the campaign context (path, ship, models).

    commanded_offsets (n_views, 4): dx, dy, dz m, dyaw rad, added to the planned viewpoints before flying;
    disturbance (n_views, 4): factors on the wind-induced part of the flown offsets; flight_seed/oracle_seed:
    for randomness of the flight and the oracle."""

    trial_id: int
    wind: WindDraw
    commanded_offsets: np.ndarray
    disturbance: np.ndarray
    flight_seed: int
    oracle_seed: int
    extra: dict = field(default_factory=dict)


def trial_inputs(section: CampaignSection, root_seed: int, trial_id: int, n_views: int) -> TrialInputs:
    """All draws of one trial (pure function of its arguments)."""
    seeds = trial_rng(root_seed, FLIGHT_STREAM, trial_id).integers(2**63 - 1, size=2)
    return TrialInputs(trial_id=int(trial_id), wind=draw_wind(section, root_seed, trial_id),
                       commanded_offsets=commanded_offsets(section, root_seed, trial_id, n_views),
                       disturbance=disturbance_factors(section, root_seed, trial_id, n_views),
                       flight_seed=int(seeds[0]), oracle_seed=int(seeds[1]))
