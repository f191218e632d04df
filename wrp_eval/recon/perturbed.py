"""Perturbed capture sets of ONE planned path: do the two oracles rank small, realistic
capture errors of the same path alike?

``validate-oracle`` compares the oracles on capture sets that differ grossly (good, degraded, broken paths);
this module builds capture sets that differ from one path's unperturbed captures by the errors a flight makes,
each kind known by construction (all deterministic from ``seed``, one numpy stream per kind):

* ``reference``: the path flown exactly (``unperturbed``);
* ``single_view`` (6): ONE view moved, 1.5-2 m in a random 3-D direction and 10-20 deg of yaw (random sign);
  the views are spread over the path (one drawn from each sixth of the view order);
* ``nav_drift`` (3): the drone flies on a navigation estimate that drifts: the TRUE positions are the plan
  plus a smooth drift along the path, the recorded ``prior_positions`` (what the GNSS believed) the plan.
  The drift is a stationary first-order Gauss-Markov walk over the view order (correlation length
  ``NAV_DRIFT_CORRELATION_VIEWS`` views, ~50 s of the quickstart path at ~5 s per view), the vertical
  component at half the horizontal standard deviation (altitude is held on the barometer as well); ONE
  drift shape scaled to 0.5 / 1.5 / 3 m RMS (of the 3-D drift over the views), so the three sets are doses
  of the same error;
* ``heading_bias`` (2): a constant yaw bias of 5 and 10 deg on every view (a compass error);
* ``blur`` (6): synthetic motion blur of 5, 15 and 30 px (pixels of the capture camera,
  ``CaptureSet.blur_px``) on 10 % and on 50 % of the views, the views drawn at random (one draw per share,
  the same views at every length, so each share is a dose series; 0 px is the reference);
* ``drop`` (6): ONE view left out (one drawn from each sixth of the view order), the photo a flight loses;
* ``flight`` (``FLIGHTS_PER_SPEED`` per speed and capture mode): the path flown by the simulator with the
  config's ``sim:`` section (navigation errors, gimbal, ship motion, air wake; the wind-limit return rules
  off, ``sim.mission`` ``px4_wind_limit_m_s`` / ``operator_wind_limit_m_s`` None, so the flights complete: the
  question is the capture errors) through the config's synthetic wind at U10 = 0, 8, 12 m/s, each flight's
  wind direction drawn uniformly (as ``wrp-eval bench --only capture`` does), once in ``stop`` and once in
  ``fly-through`` capture mode under the same random numbers (wind, navigation, ship motion): the two modes'
  sets differ by the mode alone; :func:`flight_capture_sets`. A flight that still misses views keeps the
  views it took, and its name ends in ``_partial<taken>of<n>``;
* ``navigation`` (per preset): flights at U10 ``NAV_PRESET_SPEED_M_S`` in the config's capture mode with each
  navigation preset of ``NAV_PRESETS`` (ideal, rtk, consumer), again under the same random numbers; a preset
  equal to the config's own is the ``flight`` set already and is not flown twice;
* ``recorded_blur`` (per fly-through flight at U10 >= 8): the planned poses with the blur that flight
  recorded per view: the flight's blur alone, without its pose errors.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from wrp_eval.errors import InputError
from wrp_eval.planning.path import FlightPath
from wrp_eval.recon.capture_io import captures_from_path
from wrp_eval.sim.captures import CaptureSet

REFERENCE = "unperturbed"
JITTER_SETS = 3   # the reference under an ideal flight's pose noise: each oracle's noise from image content
SINGLE_VIEW_SETS = 6
SINGLE_VIEW_OFFSET_M = (1.5, 2.0)
SINGLE_VIEW_YAW_DEG = (10.0, 20.0)
NAV_DRIFT_RMS_M = (0.5, 1.5, 3.0)
NAV_DRIFT_CORRELATION_VIEWS = 10.0
NAV_DRIFT_VERTICAL_SCALE = 0.5
HEADING_BIAS_DEG = (5.0, 10.0)
BLUR_PX = (5.0, 15.0, 30.0)
BLUR_SHARES = (0.1, 0.5)
DROP_SETS = 6
FLIGHT_SPEEDS_M_S = (0.0, 8.0, 12.0)
FLIGHT_MODES = ("stop", "fly-through")
FLIGHTS_PER_SPEED = 2
NAV_PRESETS = ("ideal", "rtk", "consumer")
NAV_PRESET_SPEED_M_S = 8.0
RECORDED_BLUR_MIN_SPEED_M_S = 8.0
MIN_ALTITUDE_M = 1.0
_STREAMS = ("single_view", "nav_drift", "flight", "jitter", "blur", "drop")


def _stream(seed: int, kind: str) -> np.random.Generator:
    """The generator of one kind of perturbation: changing one kind's draws never changes another's."""
    return np.random.default_rng([int(seed), _STREAMS.index(kind)])


def _above_sea(offsets: np.ndarray, path: FlightPath) -> np.ndarray:
    """Offsets whose moved views would fly below ``MIN_ALTITUDE_M`` get their dz mirrored (then clipped)."""
    z = np.asarray(path.positions, dtype=float)[:, 2]
    low = z + offsets[:, 2] < MIN_ALTITUDE_M
    offsets[low, 2] = np.maximum(-offsets[low, 2], MIN_ALTITUDE_M - z[low])
    return offsets


def jitter_sets(path: FlightPath, seed: int, count: int = JITTER_SETS) -> list[tuple[str, str, CaptureSet]]:
    """``count`` copies of the reference with every view jittered by 2 cm per axis and 0.1 deg of yaw (the
    response yardstick's jitter, :mod:`wrp_eval.recon.response`): not perturbations but the noise floor of
    each oracle against which the perturbations' changes are read (a seed repeat of COLMAP re-maps the same
    images; a jitter re-renders and re-matches slightly different ones)."""
    from wrp_eval.recon.response import jitter

    rng = _stream(seed, "jitter")
    return [(f"jitter_{k + 1}", "jitter", captures_from_path(path, jitter(len(path), rng))) for k in range(count)]


def single_view_sets(path: FlightPath, seed: int) -> list[tuple[str, str, CaptureSet]]:
    """``SINGLE_VIEW_SETS`` sets, each with ONE view moved (one view drawn from each sixth of the path)."""
    rng = _stream(seed, "single_view")
    n = len(path)
    bounds = np.linspace(0, n, SINGLE_VIEW_SETS + 1).round().astype(int)
    sets = []
    for k in range(SINGLE_VIEW_SETS):
        lo, hi = bounds[k], max(bounds[k + 1], bounds[k] + 1)
        view = int(rng.integers(lo, hi)) % n
        direction = rng.standard_normal(3)
        direction /= np.linalg.norm(direction)
        offsets = np.zeros((n, 4))
        offsets[view, :3] = direction * rng.uniform(*SINGLE_VIEW_OFFSET_M)
        offsets[view, 3] = np.radians(rng.uniform(*SINGLE_VIEW_YAW_DEG)) * rng.choice([-1.0, 1.0])
        sets.append((f"single_view_{view:02d}", "single_view", captures_from_path(path, _above_sea(offsets, path))))
    return sets


def drift_shape(n: int, rng: np.random.Generator, correlation_views: float = NAV_DRIFT_CORRELATION_VIEWS,
                vertical_scale: float = NAV_DRIFT_VERTICAL_SCALE) -> np.ndarray:
    """(n, 3) a stationary Gauss-Markov (AR(1)) walk over ``n`` views, correlation exp(-1/correlation_views)
    between neighbours, unit variance horizontally and ``vertical_scale`` vertically (scipy's lfilter runs
    the recursion x_k = a x_(k-1) + sqrt(1 - a^2) e_k, x_0 = e_0)."""
    a = float(np.exp(-1.0 / correlation_views))
    b = float(np.sqrt(1.0 - a * a))
    e = rng.standard_normal((n, 3))
    e[0] /= b  # so that x_0 = e_0: the walk starts in its stationary distribution
    walk = lfilter([b], [1.0, -a], e, axis=0)
    return walk * [1.0, 1.0, vertical_scale]


def nav_drift_sets(path: FlightPath, seed: int) -> list[tuple[str, str, CaptureSet]]:
    """The true positions = plan + one drift shape scaled to each RMS of ``NAV_DRIFT_RMS_M``; priors = plan."""
    n = len(path)
    shape = drift_shape(n, _stream(seed, "nav_drift"))
    shape /= max(float(np.sqrt(np.mean(np.sum(shape ** 2, axis=1)))), 1e-12)  # unit RMS of the 3-D drift
    plan = np.asarray(path.positions, dtype=float)
    sets = []
    for rms in NAV_DRIFT_RMS_M:
        offsets = np.zeros((n, 4))
        offsets[:, :3] = rms * shape
        cs = captures_from_path(path, _above_sea(offsets, path), prior_positions=plan)
        sets.append((f"nav_drift_{rms:g}m", "nav_drift", cs))
    return sets


def heading_bias_sets(path: FlightPath) -> list[tuple[str, str, CaptureSet]]:
    """A constant yaw bias on every view, one set per ``HEADING_BIAS_DEG``."""
    sets = []
    for bias in HEADING_BIAS_DEG:
        offsets = np.zeros((len(path), 4))
        offsets[:, 3] = np.radians(bias)
        sets.append((f"heading_bias_{bias:g}deg", "heading_bias", captures_from_path(path, offsets)))
    return sets


def blur_sets(path: FlightPath, seed: int) -> list[tuple[str, str, CaptureSet]]:
    """Synthetic motion blur: each length of ``BLUR_PX`` on each share of ``BLUR_SHARES`` of the views (at least
    one view); per share ONE random choice of views, shared by its lengths."""
    rng = _stream(seed, "blur")
    n = len(path)
    sets = []
    for share in BLUR_SHARES:
        chosen = np.zeros(n, dtype=bool)
        chosen[rng.choice(n, size=max(1, round(share * n)), replace=False)] = True
        for px in BLUR_PX:
            sets.append((f"blur_{px:g}px_{100 * share:g}pct", "blur",
                         captures_from_path(path, blur_px=np.where(chosen, px, 0.0))))
    return sets


def drop_sets(path: FlightPath, seed: int) -> list[tuple[str, str, CaptureSet]]:
    """``DROP_SETS`` sets, each without ONE view (one drawn from each sixth of the view order)."""
    rng = _stream(seed, "drop")
    n = len(path)
    if n < 2:
        return []
    bounds = np.linspace(0, n, DROP_SETS + 1).round().astype(int)
    views = sorted({int(rng.integers(lo, max(hi, lo + 1))) % n for lo, hi in zip(bounds[:-1], bounds[1:], strict=True)})
    full = captures_from_path(path)
    return [(f"drop_{view:03d}", "drop", full.subset(np.arange(n) != view)) for view in views]


def flight_capture_sets(ctx, path: FlightPath, seed: int, speeds=FLIGHT_SPEEDS_M_S, per_speed: int = FLIGHTS_PER_SPEED,
                        mode: str | None = None, preset: str | None = None, kind: str = "flight",
                        prefix: str = "flight") -> list[tuple[str, str, CaptureSet]]:
    """Fly ``path`` ``per_speed`` times at each U10 of ``speeds`` (m/s), in ONE batch of the simulator, and
    return each flight's capture set (``FlightResult.captures``: true poses, gimbal pitch and roll, the
    navigation's positions as priors, motion blur) as ``("<prefix>_u<U>_<k>", kind, captures)``; a flight
    that missed views is named ``..._partial<taken>of<n>``.

    ``ctx``: the :class:`wrp_eval.experiment.ExperimentContext` (its ``sim:`` section with the wind return rules
    off, its synthetic ``wind:`` section with U10 and a uniformly drawn direction per flight, its ship mesh,
    motion and particulars), as ``wrp-eval fly`` builds them; ``mode`` / ``preset`` replace
    ``sim.capture.mode`` / ``sim.navigation.preset`` (None: the config's). The random numbers (wind directions,
    turbulence, navigation errors, ship motion) depend on ``seed``, ``speeds`` and ``per_speed`` only, so calls
    that differ in ``mode`` or ``preset`` fly the same draws."""
    from wrp_eval.sim.flight import FlightSimulator  # lazily: MuJoCo loads only when flying
    from wrp_eval.sim.onboard import ShipInScene
    from wrp_eval.wind.field import build_wind_field

    config = ctx.config
    if per_speed < 1 or not len(speeds):
        return []
    if config.wind.source != "synthetic":
        raise InputError("wind", f"the perturbed flights set U10 on the synthetic wind, not {config.wind.source}")
    rng = _stream(seed, "flight")
    speed_of = np.repeat(np.asarray(speeds, dtype=float), per_speed)
    directions = rng.uniform(0.0, 360.0, len(speed_of))
    sections = [config.wind.model_copy(update={"speed_10m_m_s": float(u), "direction_deg": float(d)})
                for u, d in zip(speed_of, directions, strict=True)]
    sim = _flight_sim_section(config.sim, mode, preset)
    wind_seed, flight_seed = np.random.SeedSequence(int(rng.integers(2 ** 63 - 1))).spawn(2)
    dt = sim.timestep_s * sim.chunk_steps  # the wind is stepped at the controller rate (wrp-eval fly)
    wind = build_wind_field(sections, ctx.particulars, wind_seed, dt, ctx.config_dir)
    ship = ShipInScene.of(ctx.ship.mesh, config.ship.motion, ctx.particulars, wind.speed_10m_at_ship(len(sections)))
    with FlightSimulator(sim) as simulator:
        result = simulator.fly(path, wind, len(sections), ship=ship, flight_rngs=flight_seed)
    sets = []
    for i, (u, captures) in enumerate(zip(speed_of, result.captures, strict=True)):
        name = f"{prefix}_u{u:g}_{i % per_speed + 1}"
        if len(captures) < len(path):
            name += f"_partial{len(captures)}of{len(path)}"
        sets.append((name, kind, captures))
    return sets


def _flight_sim_section(sim, mode: str | None, preset: str | None):
    """The ``sim:`` section the perturbed flights fly: the wind-limit return rules off, ``mode`` and ``preset``
    in place of the configured capture mode and navigation preset where given."""
    update = {"mission": sim.mission.model_copy(update={"px4_wind_limit_m_s": None, "operator_wind_limit_m_s": None})}
    if mode is not None:
        update["capture"] = sim.capture.model_copy(update={"mode": mode})
    if preset is not None:
        update["navigation"] = sim.navigation.model_copy(update={"preset": preset})
    return sim.model_copy(update=update)


def flown_capture_sets(ctx, path: FlightPath, seed: int, per_speed: int = FLIGHTS_PER_SPEED
                       ) -> list[tuple[str, str, CaptureSet]]:
    """Every flown set of the validation, all under the same random numbers (the module docstring): the
    ``flight`` sets in each capture mode of ``FLIGHT_MODES`` (``flight_<mode>_u<U>_<k>``), the ``navigation``
    sets (``nav_<preset>_u<U>_<k>``) and the ``recorded_blur`` sets (``recorded_blur_u<U>_<k>``: the planned
    poses with a fly-through flight's blur). ``per_speed`` < 1: none."""
    if per_speed < 1:
        return []
    sets = []
    for mode in FLIGHT_MODES:
        sets += flight_capture_sets(ctx, path, seed, per_speed=per_speed, mode=mode, prefix=f"flight_{mode}")
    own = ctx.config.sim.navigation.preset
    for preset in (p for p in NAV_PRESETS if p != own):
        sets += flight_capture_sets(ctx, path, seed, speeds=(NAV_PRESET_SPEED_M_S,), per_speed=per_speed,
                                    preset=preset, kind="navigation", prefix=f"nav_{preset}")
    return sets + recorded_blur_sets(path, sets)


def recorded_blur_sets(path: FlightPath,
                       flights: list[tuple[str, str, CaptureSet]]) -> list[tuple[str, str, CaptureSet]]:
    """The planned poses with the per-view blur of each fly-through ``flight`` set flown at U10 >=
    ``RECORDED_BLUR_MIN_SPEED_M_S`` (views the flight did not take: sharp)."""
    sets = []
    for name, kind, cs in flights:
        parts = name.split("_")
        if kind != "flight" or parts[1] != "fly-through" or float(parts[2][1:]) < RECORDED_BLUR_MIN_SPEED_M_S:
            continue
        blur = np.zeros(len(path))
        blur[np.asarray(cs.planned_index, dtype=int)] = cs.blur()
        sets.append((f"recorded_blur_{parts[2]}_{parts[3]}", "recorded_blur", captures_from_path(path, blur_px=blur)))
    return sets


def perturbed_capture_sets(path: FlightPath, seed: int = 0, flights=None) -> list[tuple[str, str, CaptureSet]]:
    """(name, kind, capture set) triples: the unperturbed reference (name ``unperturbed``, kind ``reference``)
    first, then its jitter copies (each oracle's noise floor), then the single_view, drop, nav_drift,
    heading_bias and blur sets of ``path`` (deterministic from ``seed``), then ``flights``: the flown sets
    (:func:`flown_capture_sets`, which needs the experiment's simulator and wind; None / empty: no flights)."""
    if len(path) == 0:
        raise InputError("path", "has no viewpoints to perturb")
    return ([(REFERENCE, "reference", captures_from_path(path))] + jitter_sets(path, seed)
            + single_view_sets(path, seed) + drop_sets(path, seed) + nav_drift_sets(path, seed)
            + heading_bias_sets(path) + blur_sets(path, seed) + list(flights or []))
