"""The drone's navigation estimate: what the controller believes (GNSS + IMU + barometer + compass), batch-first.

The controller flies on :meth:`NavigationEstimator.estimate` (once per 20 Hz control chunk); captures happen
at the true state. Two estimators (``NavigationSection.estimator``):

* ``fused`` (default): a GNSS + IMU navigation filter like PX4's EKF2 or DJI's flight controller.
  The filter is linear in its errors, so only its **error state** is simulated (the truth cancels): per axis
  (position error, velocity error), driven between fixes by the IMU's white acceleration error (the preset's
  ``accel_noise_density``) and corrected at every GNSS fix by the filter's steady-state Kalman gain
  (:func:`fusion_gain`, from ``scipy.linalg.solve_discrete_are``) for EKF2's process noise (EKF2_ACC_NOISE
  0.35 m/s^2 per 10 ms prediction, EKF2_PREDICT_US) and observation noise (``max(receiver accuracy,
  EKF2_GPS_P_NOISE 0.5 m)``, vertical ``1.5 x``; velocity ``max(., EKF2_GPS_V_NOISE 0.3 m/s)``, vertical
  ``1.5 x``). The fixes it fuses carry the preset's GNSS errors (below): the slow GM part passes the filter
  (it is indistinguishable from a position offset), the per-fix white parts are smoothed. Heading: one error
  state driven by the gyro's rate error and corrected at each fix by the compass (EKF2_GYR_NOISE,
  EKF2_HEAD_NOISE 0.3 rad); the compass biases pass it. The filter starts from the first fix (EKF2 resets
  position and velocity to the GNSS when it starts fusing it). Fix delays up to EKF2_GPS_DELAY are
  compensated (fusion on a delayed horizon).
* ``raw-fix``: the estimate is the truth plus the last fix's errors, held between fixes: the controller sees a
  step at every fix (a receiver's raw output fed to the loop without a filter; kept as the comparison).

GNSS / compass error model per flight (all SI, radians), the same for both:

* horizontal / vertical GNSS error: a first-order Gauss-Markov (GM) process with stationary std sigma and
  correlation time tau, advanced every chunk with the exact discretisation
  ``x[k+1] = exp(-dt/tau) x[k] + sigma sqrt(1 - exp(-2 dt/tau)) n[k]``, plus a per-fix white noise; sampled
  at the GNSS update rate. Velocity: a per-fix white noise.
* latency: an uncompensated fix delay L makes the estimate lag the truth by ``-v L``.
* barometer: a per-flight linear altitude drift ``rate * (t - t0)`` added to the vertical error (far slower
  than the filter: it passes it unchanged).
* compass: a per-flight constant heading bias, a white heading noise per fix and, near the steel hull,
  an extra per-flight bias scaled by :func:`near_hull_taper` of the distance to the hull.

Presets (``ideal``, ``rtk``, ``consumer``, ``px4-sitl``) with their sources are in ``_PRESETS``; every
field of :class:`NavigationSection` overrides its preset's value. ``ideal`` gives estimate == truth bit for
bit and draws no random numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from statistics import NormalDist
from typing import Any, Literal, NamedTuple, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field
from scipy.linalg import solve_discrete_are

from wrp_eval.compiled import as_rows, contiguous, kernel
from wrp_eval.schema import StrictModel
from wrp_eval.streams import BlockNormals, FlightRngs, flight_generators

# 95 % radius of a 2-D isotropic Gaussian (Rayleigh): P(r <= k sigma) = 1 - exp(-k^2/2) = 0.95
K95_2D = math.sqrt(-2.0 * math.log(0.05))           # 2.4477
# 95 % two-sided bound of a 1-D Gaussian
K95_1D = NormalDist().inv_cdf(0.975)                 # 1.95996

# Hypsometric equation near sea level: dz/dp = R T / (g p) = 287.05 * 288.15 / (9.80665 * 1013.25) m/hPa
# = 8.3 m/hPa (ISA sea level, ICAO Doc 7488).
M_PER_HPA = 287.05 * 288.15 / (9.80665 * 1013.25)

_Distance = TypeVar("_Distance", float, NDArray[np.float64])


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


# The fused estimator: PX4 EKF2 defaults (PX4/PX4-Autopilot src/modules/ekf2/module.yaml and
# params_gnss.yaml): EKF2_ACC_NOISE 0.35 m/s^2 and EKF2_GYR_NOISE 0.015 rad/s ("noise for covariance
# prediction"), applied as a variance (noise * dt)^2 per prediction step (EKF/covariance.cpp) of
# EKF2_PREDICT_US = 10000 us: a white rate error of power spectral density noise^2 * 0.01 s.
# EKF2_GPS_P_NOISE 0.5 m and EKF2_GPS_V_NOISE 0.3 m/s are lower bounds of the GNSS observation noise: the
# filter uses max(receiver accuracy, parameter) (aid_sources/gnss/gps_control.cpp: pos_noise =
# max(hacc, gps_pos_noise); gnss_velocity: vel_var = max(sacc, gps_vel_noise)^2, vertical x 1.5^2;
# gnss_height_control.cpp: max(vacc, 1.5 * gps_pos_noise), "1.5 as a typical ratio of vacc/hacc").
# EKF2_HEAD_NOISE 0.3 rad: magnetic heading fusion. EKF2_GPS_DELAY 110 ms: the fix delay EKF2 compensates by
# fusing on a delayed horizon.
EKF2_PREDICT_S = 0.010
EKF2_ACC_NOISE_M_S2 = 0.35
EKF2_GYR_NOISE_RAD_S = 0.015
EKF2_GPS_P_NOISE_M = 0.5
EKF2_GPS_V_NOISE_M_S = 0.3
EKF2_VERTICAL_RATIO = 1.5
EKF2_HEAD_NOISE_RAD = 0.3
EKF2_GPS_DELAY_S = 0.110
FILTER_ACCEL_PSD = EKF2_ACC_NOISE_M_S2**2 * EKF2_PREDICT_S      # (m/s^2)^2/Hz, the filter's process noise
FILTER_GYRO_PSD = EKF2_GYR_NOISE_RAD_S**2 * EKF2_PREDICT_S      # (rad/s)^2/Hz
# The IMU errors that drive the fused estimate's error (white acceleration / rate errors, densities):
# consumer, rtk: what EKF2's defaults describe, sqrt(0.35^2 x 0.01) = 0.035 m/s^2/sqrt(Hz) and 0.0015
# rad/s/sqrt(Hz) (the filter matched to its vehicle: EKF2_ACC_NOISE covers sensor noise, vibration and the
# gravity leak of attitude errors; a bare MEMS accelerometer is ~20x quieter, e.g. Bosch BMI088 175
# ug/sqrt(Hz) = 0.0017 m/s^2/sqrt(Hz)). px4-sitl: PX4-SITL_gazebo-classic include/gazebo_imu_plugin.h
# (commit 0859997e) kDefaultAdisAccelerometerNoiseDensity 2 x 2.0e-3 m/s^2/sqrt(Hz),
# kDefaultAdisGyroscopeNoiseDensity 2 x 35 / 3600 deg/s/sqrt(Hz) (bias random walks not modelled: EKF2
# estimates the biases).
_IMU = {"accel_noise_density": EKF2_ACC_NOISE_M_S2 * math.sqrt(EKF2_PREDICT_S),
        "gyro_noise_density_deg_s": math.degrees(EKF2_GYR_NOISE_RAD_S * math.sqrt(EKF2_PREDICT_S)),
        "gnss_position_floor_m": EKF2_GPS_P_NOISE_M, "gnss_velocity_floor_m_s": EKF2_GPS_V_NOISE_M_S}
_SITL_IMU = {**_IMU, "accel_noise_density": 2 * 2.0e-3, "gyro_noise_density_deg_s": 2 * 35.0 / 3600.0}
# RTK: the GNSS noise floors a PX4 RTK set-up flies with, EKF2_GPS_P_NOISE = EKF2_GPS_V_NOISE = 0.2 (CTU-MRS
# "PX4 RTK Knowledge Base", ctu-mrs.github.io/docs/hardware/px4/px4_rtk, u-blox F9P); DJI does not publish its
# P4 RTK filter.
_RTK_IMU = {**_IMU, "gnss_position_floor_m": 0.2, "gnss_velocity_floor_m_s": 0.2}
_NO_IMU = {"accel_noise_density": 0.0, "gyro_noise_density_deg_s": 0.0,
           "gnss_position_floor_m": EKF2_GPS_P_NOISE_M, "gnss_velocity_floor_m_s": EKF2_GPS_V_NOISE_M_S}


def _preset(**values: Any) -> dict[str, Any]:
    """One preset: every NavigationSection field (section units: m, s, Hz, deg, m/min) + spec_source."""
    return values


_PRESETS: dict[str, dict[str, Any]] = {
    # Today's behaviour: the controller sees the true state.
    "ideal": _preset(horizontal_sigma_m=0.0, vertical_sigma_m=0.0, correlation_time_s=_TAU_BEARD_MCLAIN_S,
                     update_rate_hz=20.0, latency_s=0.0, white_noise_m=0.0, vertical_white_noise_m=0.0,
                     velocity_noise_m_s=0.0, baro_drift_m_per_min=0.0, compass_bias_deg=0.0,
                     compass_noise_deg=0.0, near_hull_bias_deg=0.0, near_hull_distance_m=20.0,
                     spec_source="ideal: estimate == truth", **_NO_IMU),
    # DJI Phantom 4 without vision positioning (over water): hover accuracy +-1.5 m horizontal, +-0.5 m
    # vertical with GPS positioning (DJI Phantom 4 spec sheet), read as 95 % bounds: sigma_h from the 2-D
    # radius, sigma_v from the 1-D bound, net of the white part. Rate 10 Hz: assumed, upper end of consumer
    # multi-GNSS receivers (5-10 Hz). Latency 0: the EKF fuses the fix on a delayed time horizon and predicts
    # forward with the IMU (PX4 ECL EKF docs, EKF2_GPS_DELAY), so no lag is left uncompensated.
    "consumer": _preset(horizontal_sigma_m=gm_sigma_from_p95(1.5, K95_2D, _CONSUMER_WHITE_H),
                        vertical_sigma_m=gm_sigma_from_p95(0.5, K95_1D, _CONSUMER_WHITE_V),
                        correlation_time_s=_TAU_BEARD_MCLAIN_S, update_rate_hz=10.0, latency_s=0.0,
                        white_noise_m=_CONSUMER_WHITE_H, vertical_white_noise_m=_CONSUMER_WHITE_V,
                        velocity_noise_m_s=0.05, baro_drift_m_per_min=_BARO_CONSUMER_M_PER_MIN, **_COMPASS, **_IMU,
                        spec_source="DJI Phantom 4 spec sheet: hover accuracy +-1.5 m H / +-0.5 m V (GPS "
                                    "positioning), read as 95 % bounds; tau 1100 s (Beard & McLain 2012, 7.5)"),
    # DJI Phantom 4 RTK: hover accuracy with RTK enabled +-0.1 m vertical and horizontal (DJI Phantom 4 RTK
    # spec sheet), same derivation. tau: Beard & McLain's (assumed to hold for the RTK residual); 5 Hz:
    # assumed; velocity 0.02 m/s: assumed; baro drift 0: the RTK height dominates the vertical estimate.
    "rtk": _preset(horizontal_sigma_m=gm_sigma_from_p95(0.1, K95_2D, _RTK_WHITE_H),
                   vertical_sigma_m=gm_sigma_from_p95(0.1, K95_1D, _RTK_WHITE_V),
                   correlation_time_s=_TAU_BEARD_MCLAIN_S, update_rate_hz=5.0, latency_s=0.0,
                   white_noise_m=_RTK_WHITE_H, vertical_white_noise_m=_RTK_WHITE_V, velocity_noise_m_s=0.02,
                   baro_drift_m_per_min=0.0, **_COMPASS, **_RTK_IMU,
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
                        near_hull_distance_m=20.0, **_SITL_IMU,
                        spec_source="PX4-SITL_gazebo-classic gazebo_gps_plugin defaults as implemented (bias "
                                    "recursion per 4 ms physics step: sigma 2.8 mm, tau 0.24 s), 5 Hz, 120 ms"),
}


def _sigma(description: str) -> Any:
    return Field(None, ge=0.0, description=description + "; None: the preset's value")


class NavigationSection(StrictModel):
    """``sim.navigation``: the error model of the state the controller flies on (degrees at this edge)."""

    preset: Literal["ideal", "rtk", "consumer", "px4-sitl"] = Field(
        "consumer", description="ideal (truth), rtk (DJI P4 RTK), consumer (DJI P4, GNSS only), px4-sitl")
    horizontal_sigma_m: float | None = _sigma("stationary std per horizontal axis of the GM GNSS error, m")
    vertical_sigma_m: float | None = _sigma("stationary std of the vertical GM GNSS error, m")
    correlation_time_s: float | None = Field(None, gt=0.0, description="GM correlation time, s; None: preset")
    update_rate_hz: float | None = Field(None, gt=0.0, description="GNSS fix rate, Hz; None: preset")
    latency_s: float | None = _sigma("fix delay, s: the raw-fix estimate lags by -v * latency; the fused one by "
                                     "-v * (latency - EKF2_GPS_DELAY 0.11 s), what EKF2 leaves uncompensated")
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
    estimator: Literal["fused", "raw-fix"] = Field(
        "fused", description="fused: GNSS + IMU navigation filter (EKF2-like, steady-state gains); raw-fix: the "
                             "last fix's errors held between fixes (no filter; the comparison)")
    accel_noise_density: float | None = _sigma("white acceleration error of the IMU driving the fused estimate, "
                                               "m/s^2/sqrt(Hz)")
    gyro_noise_density_deg_s: float | None = _sigma("white rate error of the gyro driving the fused heading, "
                                                    "deg/s/sqrt(Hz)")
    gnss_position_floor_m: float | None = Field(None, gt=0.0, description="the fused filter's floor of the GNSS "
                                                "position noise (EKF2_GPS_P_NOISE; vertical 1.5x), m; None: preset")
    gnss_velocity_floor_m_s: float | None = Field(None, gt=0.0, description="the fused filter's floor of the GNSS "
                                                  "velocity noise (EKF2_GPS_V_NOISE; vertical 1.5x), m/s; None: preset")


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
    estimator: str = "fused"              # "fused" or "raw-fix"
    accel_noise_density: float = 0.0      # IMU white acceleration error, m/s^2/sqrt(Hz)
    gyro_noise_density: float = 0.0       # gyro white rate error, rad/s/sqrt(Hz)
    gnss_position_floor_m: float = EKF2_GPS_P_NOISE_M
    gnss_velocity_floor_m_s: float = EKF2_GPS_V_NOISE_M_S

    @property
    def fused(self) -> bool:
        """True for the GNSS + IMU filter, False for the held raw fixes."""
        return self.estimator == "fused"

    @property
    def uncompensated_latency_s(self) -> float:
        """The fix delay the estimate lags by: all of it for raw fixes; for the fused filter what exceeds
        EKF2_GPS_DELAY (EKF2 fuses each fix at its own time on a delayed horizon and predicts forward)."""
        return max(self.latency_s - EKF2_GPS_DELAY_S, 0.0) if self.fused else self.latency_s

    @property
    def filter_noise(self) -> tuple[float, float, float, float, float]:
        """The fused filter's assumed observation noise, EKF2's rule ``max(receiver accuracy, floor)``:
        (horizontal position m, vertical position m, horizontal velocity m/s, vertical velocity m/s, heading
        rad). The receiver's accuracy is taken as the preset's own per-axis 1-sigma fix error (GM + white)."""
        h = max(math.hypot(self.horizontal_sigma_m, self.white_noise_m), self.gnss_position_floor_m)
        v = max(math.hypot(self.vertical_sigma_m, self.vertical_white_noise_m),
                EKF2_VERTICAL_RATIO * self.gnss_position_floor_m)
        vel = max(self.velocity_noise_m_s, self.gnss_velocity_floor_m_s)
        return h, v, vel, EKF2_VERTICAL_RATIO * vel, EKF2_HEAD_NOISE_RAD

    @property
    def is_ideal(self) -> bool:
        """True when every error term is zero: the estimate is the truth and nothing is drawn."""
        return not any((self.horizontal_sigma_m, self.vertical_sigma_m, self.latency_s, self.white_noise_m,
                        self.vertical_white_noise_m, self.velocity_noise_m_s, self.baro_drift_rate_m_s,
                        self.compass_bias_rad, self.compass_noise_rad, self.near_hull_bias_rad,
                        self.fused and self.accel_noise_density, self.fused and self.gyro_noise_density))


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
        near_hull_distance_m=values["near_hull_distance_m"], spec_source=values["spec_source"],
        estimator=section.estimator, accel_noise_density=values["accel_noise_density"],
        gyro_noise_density=math.radians(values["gyro_noise_density_deg_s"]),
        gnss_position_floor_m=values["gnss_position_floor_m"],
        gnss_velocity_floor_m_s=values["gnss_velocity_floor_m_s"])


def hover_p95_spec_m(params: NavigationParams) -> float:
    """95th percentile of the horizontal hover error radius the error process implies, m.

    At hover (v = 0) the horizontal error per axis is the held GM sample plus the held white noise, two
    independent zero-mean Gaussians: per-axis variance sigma_h^2 + white^2, isotropic, so the radius is
    Rayleigh and its 95th percentile is K95_2D * sqrt(sigma_h^2 + white^2). Compass errors do not move a
    hover's position (the position loop is in the world frame).
    """
    return K95_2D * math.hypot(params.horizontal_sigma_m, params.white_noise_m)


def near_hull_taper(distance_m: ArrayLike, reach_m: float) -> NDArray[np.float64]:
    """Weight (n,) of the near-hull heading bias: 1 at the hull, 0 at and beyond ``reach_m``.

    Shape (1 - d/D)^3 for d < D: the cubic fall-off of a dipole-like anomaly (|dB| ~ 1/r^3; Michael 2011,
    arXiv:1105.3136) made compact, so that it reaches exactly 0 at the configured distance. Negative
    distances (inside the hull's safety margin) count as 0. ``distance_m``: an array, a list or a number.
    """
    return _taper(np.asarray(distance_m, dtype=float), float(reach_m))


@kernel
def _taper(distance_m: _Distance, reach_m: float) -> _Distance:
    """:func:`near_hull_taper` of a number or an array."""
    d: _Distance = np.minimum(np.maximum(distance_m / reach_m, 0.0), 1.0)
    return (1.0 - d) ** 3


def inertial_error_step(psd: float, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(F (2, 2), Q (2, 2)) of one axis's (position m, velocity m/s) error over ``dt_s`` s when a white
    acceleration error of power spectral density ``psd`` (m/s^2)^2/Hz drives it (the exact discretisation of
    p' = v, v' = w: F = [[1, dt], [0, 1]], Q = psd [[dt^3/3, dt^2/2], [dt^2/2, dt]])."""
    f = np.array([[1.0, dt_s], [0.0, 1.0]])
    q = psd * np.array([[dt_s**3 / 3.0, dt_s**2 / 2.0], [dt_s**2 / 2.0, dt_s]])
    return f, q


def fusion_gain(psd: float, interval_s: float, position_noise: float,
                velocity_noise: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Steady-state Kalman gain K (2, 2) and prior covariance P (2, 2) of one axis's (position, velocity)
    filter fusing a position and a velocity fix (1-sigma ``position_noise`` m, ``velocity_noise`` m/s) every
    ``interval_s`` s, the IMU driving it between fixes (white acceleration error, PSD ``psd``): P solves the
    discrete algebraic Riccati equation P = F (P - P (P + R)^-1 P) F^T + Q (H = I), K = P (P + R)^-1. The
    correction is x += K (z - x). With psd = 0 the gain is 0 (an inertial estimate needs no fix)."""
    f, q = inertial_error_step(psd, interval_s)
    r = np.diag([position_noise**2, velocity_noise**2])
    if psd <= 0.0:
        return np.zeros((2, 2)), np.zeros((2, 2))
    p = solve_discrete_are(f.T, np.eye(2), q, r)
    return p @ np.linalg.inv(p + r), p


def heading_gain(psd: float, interval_s: float, heading_noise: float) -> tuple[float, float]:
    """Steady-state Kalman gain and prior variance (rad^2) of a heading error driven by a white gyro rate
    error (PSD ``psd`` (rad/s)^2/Hz) and corrected by a compass heading (1-sigma ``heading_noise`` rad) every
    ``interval_s`` s (the scalar Riccati equation, solved by ``solve_discrete_are``)."""
    if psd <= 0.0:
        return 0.0, 0.0
    p = float(solve_discrete_are(np.eye(1), np.eye(1), np.array([[psd * interval_s]]),
                                 np.array([[heading_noise**2]]))[0, 0])
    return p / (p + heading_noise**2), p


@cache
def _filter_gains(interval_s: float, horizontal_m: float, vertical_m: float, velocity_h_m_s: float,
                  velocity_v_m_s: float, heading_rad: float) -> tuple[NDArray[np.float64], float]:
    """The fused filter's steady-state gains for a fix every ``interval_s`` s and the filter's observation noise
    (:attr:`NavigationParams.filter_noise`): ((2, 2, 2) horizontal, vertical position / velocity gains (read-only),
    heading gain). Solved once per setting: the Riccati solutions are constants of the preset."""
    gains = np.stack([fusion_gain(FILTER_ACCEL_PSD, interval_s, horizontal_m, velocity_h_m_s)[0],
                      fusion_gain(FILTER_ACCEL_PSD, interval_s, vertical_m, velocity_v_m_s)[0]])
    gains.flags.writeable = False
    return gains, heading_gain(FILTER_GYRO_PSD, interval_s, heading_rad)[0]


@kernel
def _navigation_steps(rows: NDArray[np.float64], fixes: NDArray[np.bool_], first: bool, fused: bool, dt_s: float,
                      gm: NDArray[np.float64], pos_err: NDArray[np.float64], vel_err: NDArray[np.float64],
                      yaw_noise: NDArray[np.float64], gm_phi: float, gm_drive: NDArray[np.float64],
                      white: NDArray[np.float64], vel_sigma: NDArray[np.float64], compass_noise: float,
                      accel_chol: NDArray[np.float64], gyro_step: float, gains: NDArray[np.float64],
                      yaw_gain: float) -> None:
    """Advance every flight's error state over the m steps of ``rows`` (n, m, _WIDTH) standard normals (column
    layout: :class:`NavigationEstimator`), in place: gm, pos_err, vel_err (n, 3) m, m/s; yaw_noise (n,) rad.
    Per step: the GM moves (not on the very first step, ``first``), the fused error propagates on the IMU
    (accel_chol (2, 2): Cholesky factor of Q per step; gyro_step: rad per normal), and on a fix step
    (``fixes`` (m,) bool) the fix errors are drawn: raw-fix (or the first fix) takes them as the error,
    fused corrects towards them with ``gains`` (2, 2, 2): [horizontal, vertical] K, and ``yaw_gain``."""
    n, m = rows.shape[0], rows.shape[1]
    for row in range(n):
        for j in range(m):
            start = first and j == 0
            if not start:
                for d in range(3):
                    gm[row, d] = gm_phi * gm[row, d] + gm_drive[d] * rows[row, j, d]
                if fused:
                    for d in range(3):
                        n1, n2 = rows[row, j, 10 + 2 * d], rows[row, j, 11 + 2 * d]
                        p = pos_err[row, d] + dt_s * vel_err[row, d] + accel_chol[0, 0] * n1
                        v = vel_err[row, d] + accel_chol[1, 0] * n1 + accel_chol[1, 1] * n2
                        pos_err[row, d], vel_err[row, d] = p, v
                    yaw_noise[row] = yaw_noise[row] + gyro_step * rows[row, j, 16]
            if fixes[j]:
                for d in range(3):
                    zp = gm[row, d] + white[d] * rows[row, j, 3 + d]
                    zv = vel_sigma[d] * rows[row, j, 6 + d]
                    if fused and not start:
                        a = 0 if d < 2 else 1
                        yp, yv = zp - pos_err[row, d], zv - vel_err[row, d]
                        pos_err[row, d] = pos_err[row, d] + gains[a, 0, 0] * yp + gains[a, 0, 1] * yv
                        vel_err[row, d] = vel_err[row, d] + gains[a, 1, 0] * yp + gains[a, 1, 1] * yv
                    else:
                        pos_err[row, d], vel_err[row, d] = zp, zv
                zy = compass_noise * rows[row, j, 9]
                if fused and not start:
                    yaw_noise[row] = yaw_noise[row] + yaw_gain * (zy - yaw_noise[row])
                else:
                    yaw_noise[row] = zy


@kernel
def _estimate_rows(position: NDArray[np.float64], velocity: NDArray[np.float64], yaw: NDArray[np.float64],
                   err_pos: NDArray[np.float64], err_vel: NDArray[np.float64], yaw_noise: NDArray[np.float64],
                   compass_bias: NDArray[np.float64], hull_bias: NDArray[np.float64],
                   hull_distance: NDArray[np.float64], reach_m: float, baro_rate: NDArray[np.float64],
                   elapsed_s: float, latency_s: float,
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                              NDArray[np.float64]]:
    """(position, velocity (n, 3), yaw (n,), position error (n, 3), yaw error (n,)) of the estimate: the
    filter's (or the held fix's) errors ``err_pos``, ``err_vel`` (n, 3), ``yaw_noise`` (n,), the latency lag
    -v * latency, the baro drift and the compass biases (the near-hull one tapered by ``hull_distance`` (n,)
    m; empty: far from any hull)."""
    n = position.shape[0]
    est_pos, est_vel, pos_err = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    est_yaw, yaw_err = np.empty(n), np.empty(n)
    for row in range(n):
        for d in range(3):
            pos_err[row, d] = err_pos[row, d] - velocity[row, d] * latency_s
        pos_err[row, 2] += baro_rate[row] * elapsed_s
        for d in range(3):
            est_pos[row, d] = position[row, d] + pos_err[row, d]
            est_vel[row, d] = velocity[row, d] + err_vel[row, d]
        yaw_err[row] = compass_bias[row] + yaw_noise[row]
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


# per step and flight: GM driving noise (3), white position (3), velocity (3), heading (1), IMU acceleration
# error (2 per axis: x, y, z), gyro (1)
_WIDTH = 17


class NavigationEstimator:
    """Batched navigation errors for ``n_flights`` flights, one Generator per flight, stepping ``dt_s``.

    Flight i's draws, in its own stream order: first 6 normals (compass bias, near-hull bias, baro drift
    rate, initial GM state x/y/z from the stationary distribution), then 17 normals per time step
    (:class:`wrp_eval.streams.BlockNormals`; columns 0-2 GM drive, 3-5 white fix position, 6-8 fix velocity,
    9 compass, 10-15 the IMU's acceleration error (two per axis: the exact (position, velocity) increment of
    white acceleration over the step), 16 gyro), whether or not the step brings a fix and whichever the
    estimator, so row i never depends on the batch, and the GM path does not depend on the fix rate or the
    estimator. With an ideal ``params`` nothing is drawn. ``block_steps``: the largest stacked draw, in steps
    (memory n_flights x block_steps x 17 doubles; 256 x 1024 flights = 36 MB; :class:`wrp_eval.streams.BlockNormals`).

    Fused: the gains are the steady state of the fix interval 1 / update_rate (:func:`fusion_gain`); the
    IMU error propagates every ``dt_s`` step between fixes (the filter's own predictions at 100 Hz in
    between change nothing at the fix instants: the process noise over the interval is the same).
    """

    def __init__(self, params: NavigationParams, rngs: FlightRngs, n_flights: int, dt_s: float,
                 block_steps: int = 256) -> None:
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
        # the fused filter: the IMU's true error per step (the preset's densities) and the steady-state gains of
        # the fix interval from EKF2's process noise (FILTER_ACCEL_PSD, FILTER_GYRO_PSD) and observation noise
        _, q_step = inertial_error_step(p.accel_noise_density**2, self.dt_s)
        self._accel_chol = np.linalg.cholesky(q_step) if p.accel_noise_density > 0 else np.zeros((2, 2))
        self._gyro_step = p.gyro_noise_density * math.sqrt(self.dt_s)
        gains, self.yaw_gain = _filter_gains(1.0 / p.update_rate_hz, *p.filter_noise)
        self.gains = contiguous(gains)      # a writeable copy of the cached read-only array: one kernel signature
        self._fix_index = -1
        self._pos_err = np.zeros((n_flights, 3))
        self._vel_err = np.zeros((n_flights, 3))
        self._yaw_noise = np.zeros(n_flights)

    def _fix_steps(self, k0: int, m: int) -> np.ndarray:
        """(m,) bool: which of the steps k0 .. k0 + m - 1 start a new fix interval (updates the fix index)."""
        fixes = np.zeros(m, np.bool_)
        for j in range(m):
            index = math.floor((k0 + j) * self.dt_s * self.params.update_rate_hz + 1e-9)
            if index != self._fix_index:
                self._fix_index, fixes[j] = index, True
        return fixes

    def _advance(self, t_s: float) -> int:
        """Move the error state to the step of ``t_s`` (each step in turn); returns the step index."""
        if self._k is None:
            self._t0, k, k0 = float(t_s), 0, 0
            rows = self._noise.draw(1)                                 # step 0: the first fix only
        else:
            k = round((t_s - self._t0) / self.dt_s)
            if k < self._k:
                raise ValueError(f"time went backwards: t={t_s} before step {self._k}")
            k0 = self._k + 1
            rows = self._noise.draw(k - self._k)
        if rows.shape[1]:
            p = self.params
            _navigation_steps(rows, self._fix_steps(k0, rows.shape[1]), self._k is None, p.fused, self.dt_s,
                              self._gm, self._pos_err, self._vel_err, self._yaw_noise, self._phi, self._gm_drive,
                              self._white, self._vel_sigma, p.compass_noise_rad, self._accel_chol,
                              self._gyro_step, self.gains, self.yaw_gain)
        self._k = k
        return k

    def estimate(self, t_s: float, position: ArrayLike, velocity: ArrayLike, yaw: ArrayLike,
                 hull_distance_m: ArrayLike | None = None) -> NavigationEstimate:
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
        position, velocity = (contiguous(as_rows(name, value, (n, 3)))
                              for name, value in (("position", position), ("velocity", velocity)))
        yaw = contiguous(as_rows("yaw", yaw, (n,)))
        hull = np.empty(0) if hull_distance_m is None else contiguous(as_rows("hull_distance_m", hull_distance_m, (n,)))
        self._advance(t_s)
        p = self.params
        return NavigationEstimate(*_estimate_rows(position, velocity, yaw, self._pos_err, self._vel_err,
                                                  self._yaw_noise, self._compass_bias, self._hull_bias, hull,
                                                  float(p.near_hull_distance_m), self._baro_rate,
                                                  float(t_s - self._t0), float(p.uncompensated_latency_s)))
