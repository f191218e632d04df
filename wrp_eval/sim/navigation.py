"""The drone's navigation estimate: what the controller believes (GNSS + barometer + compass), batch-first.

The controller flies on :meth:`NavigationEstimator.estimate` (once per 20 Hz control chunk); captures happen
at the true state. Error model per flight (all SI, radians):

* horizontal / vertical GNSS error: a first-order Gauss-Markov (GM) process with stationary std sigma and
  correlation time tau, advanced every chunk with the exact discretisation
  ``x[k+1] = exp(-dt/tau) x[k] + sigma sqrt(1 - exp(-2 dt/tau)) n[k]``, plus a per-fix white noise. Both are
  sampled at the GNSS update rate and **held** between fixes: between fixes the estimate follows the truth
  plus the held error, as an EKF dead-reckoning on the IMU does (the IMU carries the motion, the fix the
  offset).
* latency: an uncompensated fix delay L makes the estimate lag the truth by ``-v L``.
* barometer: a per-flight linear altitude drift ``rate * (t - t0)`` added to the vertical error.
* compass: a per-flight constant heading bias, a held white heading noise per fix and, near the steel hull,
  an extra per-flight bias scaled by :func:`near_hull_taper` of the distance to the hull.

Presets (``ideal``, ``rtk``, ``consumer``, ``px4-sitl``) with their sources are in ``_PRESETS``; every
field of :class:`NavigationSection` overrides its preset's value. ``ideal`` gives estimate == truth bit for
bit and draws no random numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist
from typing import Literal, NamedTuple

import numpy as np
from pydantic import Field

from wrp_eval.compiled import as_rows, kernel
from wrp_eval.streams import BlockNormals, flight_generators
from wrp_eval.validation import StrictModel

# 95 % radius of a 2-D isotropic Gaussian (Rayleigh): P(r <= k sigma) = 1 - exp(-k^2/2) = 0.95
K95_2D = math.sqrt(-2.0 * math.log(0.05))           # 2.4477
# 95 % two-sided bound of a 1-D Gaussian
K95_1D = NormalDist().inv_cdf(0.975)                 # 1.95996

# Hypsometric equation near sea level: dz/dp = R T / (g p) = 287.05 * 288.15 / (9.80665 * 1013.25) m/hPa
# = 8.3 m/hPa (ISA sea level, ICAO Doc 7488).
M_PER_HPA = 287.05 * 288.15 / (9.80665 * 1013.25)


def gm_sigma_from_p95(p95_m: float, k95: float, white_m: float) -> float:
    """Stationary GM std such that k95 * sqrt(sigma^2 + white^2) equals a 95 % accuracy bound ``p95_m``."""
    total = p95_m / k95
    if white_m > total:
        raise ValueError(f"white noise {white_m} m alone exceeds the 95 % bound {p95_m} m")
    return math.sqrt(total**2 - white_m**2)


def px4_plugin_gm(random_walk: float, step_s: float, corr_steps: float) -> tuple[float, float]:
    """(stationary std m, correlation time s) of the PX4 SITL Gazebo GPS plugin's bias recursion.

    PX4/PX4-SITL_gazebo-classic ``src/gazebo_gps_plugin.cpp`` (OnUpdate / OnWorldUpdate, run every physics
    step dt) does ``rw = random_walk * sqrt(dt) * n`` and ``bias += rw * dt - bias / gps_corellation_time``.
    Quirks, reproduced as written: (1) the decay term is not multiplied by dt, so ``gps_corellation_time = 60``
    is 60 *physics steps*, not 60 s: ``bias[k+1] = a bias[k] + random_walk dt^1.5 n`` with a = 1 - 1/60;
    (2) the driving noise scales with dt^1.5 instead of sqrt(dt). This AR(1) is exactly a sampled GM process
    with tau = -dt / ln(a) and stationary variance (random_walk^2 dt^3) / (1 - a^2)
    = random_walk^2 dt^3 T^2 / (2T - 1) with T = 60. At the 4 ms physics step of PX4's worlds: sigma_xy =
    2.8 mm, tau = 0.24 s (what the ``px4-sitl`` preset uses). The same recursion run at the 5 Hz publish rate
    (dt = 0.2 s, as the PX4/px4-simulation-ignition port does) gives sigma_xy = 0.98 m, tau = 11.9 s; set
    ``horizontal_sigma_m`` / ``correlation_time_s`` to those to model that variant.
    """
    a = 1.0 - 1.0 / corr_steps
    sigma = random_walk * step_s**1.5 / math.sqrt(1.0 - a * a)
    tau = -step_s / math.log(a)
    return sigma, tau


# PX4 SITL constants (PX4/PX4-SITL_gazebo-classic include/gazebo_gps_plugin.h, commit 0b554fab:
# kDefaultUpdateRate 5 Hz, kDefaultGpsXYRandomWalk 2.0, kDefaultGpsZRandomWalk 4.0 (m/s)/sqrt(Hz),
# kDefaultGpsXYNoiseDensity 2e-4, kDefaultGpsZNoiseDensity 4e-4 m/sqrt(Hz), kDefaultGpsVXYNoiseDensity 0.2
# (m/s)/sqrt(Hz), gps_corellation_time_ 60, gps_delay_ 0.12 s) and the physics step of its worlds
# (worlds/empty.world: max_step_size 0.004 s, real_time_update_rate 250).
_PX4_STEP_S = 0.004
_PX4_SIGMA_H, _PX4_TAU_S = px4_plugin_gm(2.0, _PX4_STEP_S, 60.0)      # 2.78e-3 m, 0.238 s
_PX4_SIGMA_V, _ = px4_plugin_gm(4.0, _PX4_STEP_S, 60.0)               # 5.57e-3 m
# Quirk (3): the white noise is density * sqrt(dt) (a density should give density / sqrt(dt)); as written.
_PX4_WHITE_H = 2e-4 * math.sqrt(_PX4_STEP_S)                            # 1.26e-5 m
_PX4_WHITE_V = 4e-4 * math.sqrt(_PX4_STEP_S)
_PX4_VEL = 0.2 * math.sqrt(_PX4_STEP_S)                                 # 0.0126 m/s
# Magnetometer (PX4-SITL_gazebo-classic src/gazebo_magnetometer_plugin.cpp, commit 072aba02): white noise
# noise_density * n per axis with kDefaultNoiseDensity 0.4e-3 gauss, no bias; heading noise = 0.4e-3 / H
# with H ~ 0.21 gauss (horizontal field at the plugin's default home, Zurich; WMM, approximate).
_PX4_COMPASS_NOISE_DEG = math.degrees(0.4e-3 / 0.21)                    # 0.11 deg

# Consumer / RTK: white (per-fix, epoch-to-epoch) part of the hover error. Consumer: assumed 5 cm horizontal,
# 10 cm vertical (a filtered consumer fix jitters by centimetres between epochs; the slow GM part carries
# the metre-level error). RTK: the positioning accuracy of the DJI Phantom 4 RTK spec sheet, 1 cm + 1 ppm
# horizontal, 1.5 cm + 1 ppm vertical (RMS), baseline ppm neglected near the base.
_CONSUMER_WHITE_H, _CONSUMER_WHITE_V = 0.05, 0.10
_RTK_WHITE_H, _RTK_WHITE_V = 0.01, 0.015

# Beard & McLain, Small Unmanned Aircraft (2012) Sec. 7.5: GPS GM error with k_GPS = 1/1100 s^-1 (tau = 1100 s),
# Ts = 1 s (after Rankin 1994); their sensor parameters (uavbook mavsim) also give sigma_Vg = 0.05 m/s.
_TAU_BEARD_MCLAIN_S = 1100.0

# Compass (consumer, RTK: same single-antenna magnetometer heading). Bias: 2 deg std per flight, the upper end
# of the "1 to 2 deg heading accuracy" of a calibrated consumer magnetometer (Honeywell HMC5883L data sheet).
# Noise: 0.3 deg per fix, assumed (order of Beard & McLain's magnetometer noise; the EKF smooths raw samples).
# Near hull: assumed 10 deg std at the hull, tapering to 0 at 20 m. Reasoning: a ship's magnetic anomaly is
# ~1 uT at ~10-20 m and falls off like a dipole (1/r^3; Michael 2011, arXiv:1105.3136, "Magnetic imaging of
# shipwrecks"); against a horizontal Earth field of ~20 uT, dB = 2-4 uT near the hull gives atan(dB/H) =
# 6-11 deg. DJI user manuals warn against calibrating the compass near large metal structures (cited from the
# task brief, not re-read here). Not measured: a study parameter.
_COMPASS = {"compass_bias_deg": 2.0, "compass_noise_deg": 0.3, "near_hull_bias_deg": 10.0,
            "near_hull_distance_m": 20.0}

# Barometer: per-flight linear drift rate with std 1 hPa per 3 h. The pressure tendency of surface observations
# is the change over the preceding 3 h (AMS Glossary of Meteorology, "pressure tendency"); under 1 hPa / 3 h is
# read as steady, over 3 hPa / 3 h as a rapid (storm) change, so 1 hPa / 3 h is a typical non-storm rate
# (assumed as the std) -> 8.3 m / 180 min = 0.046 m/min. Linear, not a random walk: synoptic pressure changes
# are smooth over a flight of <= 25 min.
_BARO_CONSUMER_M_PER_MIN = 1.0 * M_PER_HPA / 180.0


def _preset(**values) -> dict:
    """One preset: every NavigationSection field (section units: m, s, Hz, deg, m/min) + spec_source."""
    return values


_PRESETS: dict[str, dict] = {
    # Today's behaviour: the controller sees the true state.
    "ideal": _preset(horizontal_sigma_m=0.0, vertical_sigma_m=0.0, correlation_time_s=_TAU_BEARD_MCLAIN_S,
                     update_rate_hz=20.0, latency_s=0.0, white_noise_m=0.0, vertical_white_noise_m=0.0,
                     velocity_noise_m_s=0.0, baro_drift_m_per_min=0.0, compass_bias_deg=0.0,
                     compass_noise_deg=0.0, near_hull_bias_deg=0.0, near_hull_distance_m=20.0,
                     spec_source="ideal: estimate == truth"),
    # DJI Phantom 4 without vision positioning (over water): hover accuracy +-1.5 m horizontal, +-0.5 m
    # vertical with GPS positioning (DJI Phantom 4 spec sheet), read as 95 % bounds: sigma_h from the 2-D
    # radius, sigma_v from the 1-D bound, net of the white part. Rate 10 Hz: assumed, upper end of consumer
    # multi-GNSS receivers (5-10 Hz). Latency 0: the EKF fuses the fix on a delayed time horizon and predicts
    # forward with the IMU (PX4 ECL EKF docs, EKF2_GPS_DELAY), so no lag is left uncompensated.
    "consumer": _preset(horizontal_sigma_m=gm_sigma_from_p95(1.5, K95_2D, _CONSUMER_WHITE_H),
                        vertical_sigma_m=gm_sigma_from_p95(0.5, K95_1D, _CONSUMER_WHITE_V),
                        correlation_time_s=_TAU_BEARD_MCLAIN_S, update_rate_hz=10.0, latency_s=0.0,
                        white_noise_m=_CONSUMER_WHITE_H, vertical_white_noise_m=_CONSUMER_WHITE_V,
                        velocity_noise_m_s=0.05, baro_drift_m_per_min=_BARO_CONSUMER_M_PER_MIN, **_COMPASS,
                        spec_source="DJI Phantom 4 spec sheet: hover accuracy +-1.5 m H / +-0.5 m V (GPS "
                                    "positioning), read as 95 % bounds; tau 1100 s (Beard & McLain 2012, 7.5)"),
    # DJI Phantom 4 RTK: hover accuracy with RTK enabled +-0.1 m vertical and horizontal (DJI Phantom 4 RTK
    # spec sheet), same derivation. tau: Beard & McLain's (assumed to hold for the RTK residual); 5 Hz:
    # assumed; velocity 0.02 m/s: assumed; baro drift 0: the RTK height dominates the vertical estimate.
    "rtk": _preset(horizontal_sigma_m=gm_sigma_from_p95(0.1, K95_2D, _RTK_WHITE_H),
                   vertical_sigma_m=gm_sigma_from_p95(0.1, K95_1D, _RTK_WHITE_V),
                   correlation_time_s=_TAU_BEARD_MCLAIN_S, update_rate_hz=5.0, latency_s=0.0,
                   white_noise_m=_RTK_WHITE_H, vertical_white_noise_m=_RTK_WHITE_V, velocity_noise_m_s=0.02,
                   baro_drift_m_per_min=0.0, **_COMPASS,
                   spec_source="DJI Phantom 4 RTK spec sheet: hover accuracy +-0.1 m H and V (RTK), read as "
                               "95 % bounds; positioning 1 cm + 1 ppm H, 1.5 cm + 1 ppm V (RMS)"),
    # PX4 SITL Gazebo GPS plugin as it runs (see px4_plugin_gm): millimetre-level GM error with tau 0.24 s,
    # fixes at 5 Hz, 120 ms delay (the raw sensor stream; EKF2 would compensate EKF2_GPS_DELAY of it).
    # Barometer plugin: baroDriftPaPerSec default 0. No hull magnetics in SITL.
    "px4-sitl": _preset(horizontal_sigma_m=_PX4_SIGMA_H, vertical_sigma_m=_PX4_SIGMA_V,
                        correlation_time_s=_PX4_TAU_S, update_rate_hz=5.0, latency_s=0.12,
                        white_noise_m=_PX4_WHITE_H, vertical_white_noise_m=_PX4_WHITE_V,
                        velocity_noise_m_s=_PX4_VEL, baro_drift_m_per_min=0.0, compass_bias_deg=0.0,
                        compass_noise_deg=_PX4_COMPASS_NOISE_DEG, near_hull_bias_deg=0.0,
                        near_hull_distance_m=20.0,
                        spec_source="PX4-SITL_gazebo-classic gazebo_gps_plugin defaults as implemented (bias "
                                    "recursion per 4 ms physics step: sigma 2.8 mm, tau 0.24 s), 5 Hz, 120 ms"),
}


def _sigma(description: str):
    return Field(None, ge=0.0, description=description + "; None: the preset's value")


class NavigationSection(StrictModel):
    """``sim.navigation``: the error model of the state the controller flies on (degrees at this edge)."""

    preset: Literal["ideal", "rtk", "consumer", "px4-sitl"] = Field(
        "consumer", description="ideal (truth), rtk (DJI P4 RTK), consumer (DJI P4, GNSS only), px4-sitl")
    horizontal_sigma_m: float | None = _sigma("stationary std per horizontal axis of the GM GNSS error, m")
    vertical_sigma_m: float | None = _sigma("stationary std of the vertical GM GNSS error, m")
    correlation_time_s: float | None = Field(None, gt=0.0, description="GM correlation time, s; None: preset")
    update_rate_hz: float | None = Field(None, gt=0.0, description="GNSS fix rate, Hz; None: preset")
    latency_s: float | None = _sigma("uncompensated fix delay (estimate lags by -v * latency), s")
    white_noise_m: float | None = _sigma("per-fix white noise per horizontal axis, m")
    vertical_white_noise_m: float | None = _sigma("per-fix white noise, vertical, m")
    velocity_noise_m_s: float | None = _sigma("per-fix white noise of the horizontal velocity estimate (vertical "
                                              "twice), m/s")
    baro_drift_m_per_min: float | None = _sigma("std of the per-flight linear barometric altitude drift rate, "
                                                "m/min")
    compass_bias_deg: float | None = _sigma("std of the per-flight constant heading bias, deg")
    compass_noise_deg: float | None = _sigma("white heading noise per fix, deg")
    near_hull_bias_deg: float | None = _sigma("std of the extra per-flight heading bias at the hull, deg")
    near_hull_distance_m: float | None = Field(None, gt=0.0, description="the near-hull bias tapers to 0 at "
                                                                         "this distance, m; None: preset")


@dataclass(frozen=True)
class NavigationParams:
    """Resolved error model (SI, radians). Stds are 1-sigma; rates per second."""

    preset: str
    horizontal_sigma_m: float
    vertical_sigma_m: float
    correlation_time_s: float
    update_rate_hz: float
    latency_s: float
    white_noise_m: float
    vertical_white_noise_m: float
    velocity_noise_m_s: float
    baro_drift_rate_m_s: float            # std of the per-flight drift rate, m/s
    compass_bias_rad: float
    compass_noise_rad: float
    near_hull_bias_rad: float
    near_hull_distance_m: float
    spec_source: str

    @property
    def is_ideal(self) -> bool:
        """True when every error term is zero: the estimate is the truth and nothing is drawn."""
        return not any((self.horizontal_sigma_m, self.vertical_sigma_m, self.latency_s, self.white_noise_m,
                        self.vertical_white_noise_m, self.velocity_noise_m_s, self.baro_drift_rate_m_s,
                        self.compass_bias_rad, self.compass_noise_rad, self.near_hull_bias_rad))


def navigation_params(section: NavigationSection | None = None) -> NavigationParams:
    """The preset's values with the section's overrides, converted to SI / radians."""
    section = section or NavigationSection()
    values = dict(_PRESETS[section.preset])
    for key, value in section.model_dump(exclude={"preset"}).items():
        if value is not None:
            values[key] = value
    return NavigationParams(
        preset=section.preset, horizontal_sigma_m=values["horizontal_sigma_m"],
        vertical_sigma_m=values["vertical_sigma_m"], correlation_time_s=values["correlation_time_s"],
        update_rate_hz=values["update_rate_hz"], latency_s=values["latency_s"],
        white_noise_m=values["white_noise_m"], vertical_white_noise_m=values["vertical_white_noise_m"],
        velocity_noise_m_s=values["velocity_noise_m_s"], baro_drift_rate_m_s=values["baro_drift_m_per_min"] / 60.0,
        compass_bias_rad=math.radians(values["compass_bias_deg"]),
        compass_noise_rad=math.radians(values["compass_noise_deg"]),
        near_hull_bias_rad=math.radians(values["near_hull_bias_deg"]),
        near_hull_distance_m=values["near_hull_distance_m"], spec_source=values["spec_source"])


def hover_p95_spec_m(params: NavigationParams) -> float:
    """95th percentile of the horizontal hover error radius the error process implies, m.

    At hover (v = 0) the horizontal error per axis is the held GM sample plus the held white noise, two
    independent zero-mean Gaussians: per-axis variance sigma_h^2 + white^2, isotropic, so the radius is
    Rayleigh and its 95th percentile is K95_2D * sqrt(sigma_h^2 + white^2). Compass errors do not move a
    hover's position (the position loop is in the world frame).
    """
    return K95_2D * math.hypot(params.horizontal_sigma_m, params.white_noise_m)


def near_hull_taper(distance_m, reach_m: float):
    """Weight (n,) of the near-hull heading bias: 1 at the hull, 0 at and beyond ``reach_m``.

    Shape (1 - d/D)^3 for d < D: the cubic fall-off of a dipole-like anomaly (|dB| ~ 1/r^3; Michael 2011,
    arXiv:1105.3136) made compact, so that it reaches exactly 0 at the configured distance. Negative
    distances (inside the hull's safety margin) count as 0. ``distance_m``: an array, a list or a number.
    """
    return _taper(np.asarray(distance_m, dtype=float), float(reach_m))


@kernel
def _taper(distance_m, reach_m: float):
    """:func:`near_hull_taper` of a number or an array."""
    d = np.minimum(np.maximum(distance_m / reach_m, 0.0), 1.0)
    return (1.0 - d) ** 3


@kernel
def _estimate_rows(position, velocity, yaw, held_pos, held_vel, held_yaw, compass_bias, hull_bias, hull_distance,
                   reach_m, baro_rate, elapsed_s, latency_s):
    """(position, velocity (n, 3), yaw (n,), position error (n, 3), yaw error (n,)) of the estimate: the held
    fix errors, the latency lag -v * latency, the baro drift and the compass biases (the near-hull one tapered
    by ``hull_distance`` (n,) m; empty: far from any hull)."""
    n = position.shape[0]
    est_pos, est_vel, pos_err = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    est_yaw, yaw_err = np.empty(n), np.empty(n)
    for row in range(n):
        for d in range(3):
            pos_err[row, d] = held_pos[row, d] - velocity[row, d] * latency_s
        pos_err[row, 2] += baro_rate[row] * elapsed_s
        for d in range(3):
            est_pos[row, d] = position[row, d] + pos_err[row, d]
            est_vel[row, d] = velocity[row, d] + held_vel[row, d]
        yaw_err[row] = compass_bias[row] + held_yaw[row]
        if hull_distance.size:
            yaw_err[row] = yaw_err[row] + hull_bias[row] * _taper(hull_distance[row], reach_m)
        est_yaw[row] = yaw[row] + yaw_err[row]
    return est_pos, est_vel, est_yaw, pos_err, yaw_err


class NavigationEstimate(NamedTuple):
    """What the controller sees: estimates and their errors (estimate - truth)."""

    position: np.ndarray        # (n, 3) m
    velocity: np.ndarray        # (n, 3) m/s
    yaw: np.ndarray             # (n,) rad (not wrapped: truth + error)
    position_error: np.ndarray  # (n, 3) m
    yaw_error: np.ndarray       # (n,) rad


# per step and flight: GM driving noise (3), white position (3), velocity (3), heading (1)
_WIDTH = 10


class NavigationEstimator:
    """Batched navigation errors for ``n_flights`` flights, one Generator per flight, stepping ``dt_s``.

    Flight i's draws, in its own stream order: first 6 normals (compass bias, near-hull bias, baro drift
    rate, initial GM state x/y/z from the stationary distribution), then 10 normals per time step
    (:class:`wrp_eval.streams.BlockNormals`), whether or not the step brings a fix, so row i never depends on
    the batch, and the GM path does not depend on the fix rate. With an ideal ``params`` nothing is drawn.
    ``block_steps``: steps per stacked draw (memory n_flights x block_steps x 10 doubles; 256 x 1024 flights
    = 21 MB).
    """

    def __init__(self, params: NavigationParams, rngs, n_flights: int, dt_s: float, block_steps: int = 256):
        if n_flights < 1 or not dt_s > 0:
            raise ValueError("need n_flights >= 1 and dt_s > 0")
        self.params, self.n_flights, self.dt_s = params, int(n_flights), float(dt_s)
        self.ideal = params.is_ideal
        self._k: int | None = None
        self._t0 = 0.0
        if self.ideal:
            return
        p = params
        gens = flight_generators(rngs, n_flights)
        first = np.stack([g.standard_normal(6) for g in gens])        # once per batch, not per call
        self._compass_bias = p.compass_bias_rad * first[:, 0]
        self._hull_bias = p.near_hull_bias_rad * first[:, 1]
        self._baro_rate = p.baro_drift_rate_m_s * first[:, 2]
        self._gm_sigma = np.array([p.horizontal_sigma_m, p.horizontal_sigma_m, p.vertical_sigma_m])
        self._gm = self._gm_sigma * first[:, 3:6]
        self._white = np.array([p.white_noise_m, p.white_noise_m, p.vertical_white_noise_m])
        self._vel_sigma = p.velocity_noise_m_s * np.array([1.0, 1.0, 2.0])   # vertical twice, as PX4's vz/vxy
        self._phi = math.exp(-self.dt_s / p.correlation_time_s)
        self._gm_drive = self._gm_sigma * math.sqrt(1 - self._phi**2)     # (3,) per-step driving std
        self._noise = BlockNormals(gens, n_flights, _WIDTH, block_steps)    # block size never changes the numbers
        self._fix_index = -1
        self._held_pos = np.zeros((n_flights, 3))
        self._held_vel = np.zeros((n_flights, 3))
        self._held_yaw = np.zeros(n_flights)

    def _advance(self, t_s: float) -> int:
        """Move the GM state to the step of ``t_s``; returns the step index."""
        if self._k is None:
            self._t0, k = float(t_s), 0
            rows = self._noise.draw(1)                                 # step 0: fix noises only
        else:
            k = round((t_s - self._t0) / self.dt_s)
            if k < self._k:
                raise ValueError(f"time went backwards: t={t_s} before step {self._k}")
            rows = self._noise.draw(k - self._k)
            m = rows.shape[1]
            if m == 1:      # the flight loop's case: one chunk
                self._gm = self._phi * self._gm + self._gm_drive * rows[:, 0, 0:3]
            elif m:
                # m exact steps at once: x_m = phi^m x_0 + s sum_j phi^(m-1-j) n_j (identical to m single steps)
                weights = self._phi ** np.arange(m - 1, -1, -1)
                drive = np.einsum("j,njc->nc", weights, rows[:, :, 0:3])
                self._gm = self._phi**m * self._gm + self._gm_drive * drive
        if rows.shape[1]:
            self._maybe_fix(k, rows[:, -1])
        self._k = k
        return k

    def _maybe_fix(self, k: int, row: np.ndarray) -> None:
        """Take a new fix if step k starts a new fix interval: sample the GM and draw the per-fix noises."""
        fix_index = math.floor(k * self.dt_s * self.params.update_rate_hz + 1e-9)
        if fix_index == self._fix_index:
            return
        self._fix_index = fix_index
        self._held_pos = self._gm + self._white * row[:, 3:6]
        self._held_vel = self._vel_sigma * row[:, 6:9]
        self._held_yaw = self.params.compass_noise_rad * row[:, 9]

    def estimate(self, t_s: float, position, velocity, yaw, hull_distance_m=None) -> NavigationEstimate:
        """The estimated state at time ``t_s`` (the first call sets t0; later ones advance by multiples of dt).

        position, velocity (n, 3) true, m and m/s; yaw (n,) true, rad; hull_distance_m (n,) distance of each
        drone to the hull, m, or None (far from any hull).
        """
        position, velocity = np.asarray(position, float), np.asarray(velocity, float)
        yaw = np.asarray(yaw, float)
        if self.ideal:
            return NavigationEstimate(position.copy(), velocity.copy(), yaw.copy(), np.zeros_like(position),
                                      np.zeros_like(yaw))
        n = self.n_flights
        position, velocity = as_rows("position", position, (n, 3)), as_rows("velocity", velocity, (n, 3))
        yaw = as_rows("yaw", yaw, (n,))
        hull = np.empty(0) if hull_distance_m is None else as_rows("hull_distance_m", hull_distance_m, (n,))
        self._advance(t_s)
        p = self.params
        return NavigationEstimate(*_estimate_rows(position, velocity, yaw, self._held_pos, self._held_vel,
                                                  self._held_yaw, self._compass_bias, self._hull_bias, hull,
                                                  float(p.near_hull_distance_m), self._baro_rate,
                                                  float(t_s - self._t0), float(p.latency_s)))
