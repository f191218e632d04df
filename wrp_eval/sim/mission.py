"""What ends a mission and how it goes on: the ``sim.mission`` section (the autopilot's rules, the battery
swaps), and the rows of the return and headway decisions.

Every rule is one a real system has (sim/README.md, "How a mission ends"):

* energy: the autopilot turns home when the battery reaches its reserve plus the energy to fly home with
  the wind (PX4 ``COM_FLTT_LOW_ACT`` = 3, return when the remaining flight time falls below the estimated
  return time, ``src/lib/rtl/rtl_time_estimator.cpp``; DJI's Smart Return-to-Home counts the distance and the
  real-time wind). After such a return the operator swaps the battery and resumes the mission at its
  breakpoint (QGroundControl "Resume Mission"; DJI Mobile SDK v5 ``BreakPointInfo``: wayline, waypoint and
  progress in the segment; UgCS "change route's start point after battery change"): up to ``max_sorties``
  sorties, ``swap_time_s`` on deck between them, the wind evolving meanwhile.
* headway: a vehicle that makes no progress towards its waypoint for ``headway_timeout_s`` (the wind beats
  its tilt-limited airspeed) turns home; if it cannot get home either (no ground speed towards home at its
  top airspeed, or not the energy to get there), it is lost. Top airspeed ``return_airspeed_m_s`` 13.9 m/s:
  DJI Phantom 4 RTK, 50 km/h in P-mode (spec sheet).
* wind: PX4 ``COM_WIND_MAX`` (default -1: off; ``COM_WIND_MAX_ACT`` 3 = return) compares the current wind
  estimate (``HealthAndArmingChecks/checks/windCheck.cpp``); off by default here too
  (``px4_wind_limit_m_s``). The estimate is the wind at the vehicle through a first-order lag of
  ``wind_estimate_tau_s`` (EKF2 carries the wind as a slowly varying random-walk state, ``EKF2_WIND_NSD``
  0.05 m/s^2/sqrt(Hz); no time constant is published: 10 s assumed). ArduCopter has no wind failsafe; DJI only
  warns.
* ``operator_wind_limit_m_s``: an operator's own policy (not an autopilot's): go home when the
  ``operator_wind_average_s`` average of the wind estimate exceeds the limit. Off by default. Configs that
  still say ``sim.wind_limit_m_s`` / ``sim.wind_average_s`` (stored campaigns) are read as this policy.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from wrp_eval.compiled import kernel
from wrp_eval.schema import StrictModel
from wrp_eval.sim.power import straight_home_energy_j

# DJI Phantom 4 RTK spec sheet: max horizontal speed 50 km/h (P-mode) = 13.9 m/s
P4_RTK_TOP_SPEED_M_S = 50.0 / 3.6
# a vehicle is headed home only with at least this ground speed towards it (below: it cannot get home)
MIN_HOME_GROUND_SPEED_M_S = 0.5


class MissionSection(StrictModel):
    """``sim.mission``: what ends a sortie and how the mission goes on (module docstring for the sources)."""

    max_sorties: int = Field(3, ge=1, le=20, description="sorties (batteries) the operator flies the mission with; "
                                                         "after a return on energy the next one resumes at the "
                                                         "breakpoint")
    swap_time_s: float = Field(180.0, ge=0.0, le=7200.0, description="on deck between two sorties (landing, "
                                                                     "battery swap, take-off), s")
    headway_timeout_s: float = Field(30.0, gt=0.0, le=600.0, description="no progress towards the waypoint for this "
                                                                         "long: the vehicle turns home, s")
    headway_progress_m: float = Field(1.0, gt=0.0, le=50.0, description="what counts as progress towards the "
                                                                        "waypoint, m")
    return_airspeed_m_s: float = Field(P4_RTK_TOP_SPEED_M_S, gt=0.0, le=40.0,
                                       description="top airspeed on the way home (P4 RTK P-mode 50 km/h), m/s")
    wind_estimate_tau_s: float = Field(10.0, gt=0.0, le=600.0, description="lag of the autopilot's wind estimate "
                                                                           "(assumed), s")
    px4_wind_limit_m_s: float | None = Field(None, gt=0.0, description="PX4 COM_WIND_MAX: return when the wind "
                                                                       "estimate exceeds this; None: off (PX4's "
                                                                       "default -1)")
    operator_wind_limit_m_s: float | None = Field(None, gt=0.0, description="operator policy: return when the "
                                                                            "average wind estimate exceeds this; "
                                                                            "None: off")
    operator_wind_average_s: float = Field(30.0, gt=0.0, le=3600.0, description="averaging time of the operator "
                                                                                "policy, s (judged once it has run "
                                                                                "this long)")


@kernel
def _decision_rows(home: NDArray[np.float64], position: NDArray[np.float64], wind: NDArray[np.float64],
                   estimate: NDArray[np.float64], average: NDArray[np.float64], weight_estimate: float,
                   weight_average: float, judged: bool, px4_limit: float, operator_limit: float, cruise_m_s: float,
                   cruise_power_w: float, return_m_s: float, return_power_w: float, energy_j: NDArray[np.float64],
                   reserve_j: float, battery_on: bool,
                   ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_]]:
    """(battery due, PX4 wind over, operator wind over, home reachable) (n,) bool each, row by row; the
    horizontal ``estimate`` and ``average`` (n, 3) move by their weights towards ``wind`` (n, 3) in place
    (weight 1: they start there). px4_limit / operator_limit <= 0: off."""
    n = position.shape[0]
    due, px4, operator = np.zeros(n, np.bool_), np.zeros(n, np.bool_), np.zeros(n, np.bool_)
    reachable = np.zeros(n, np.bool_)
    for row in range(n):
        for d in range(3):      # the horizontal wind: z times 0 (a non-finite z stays NaN, as wind * (1, 1, 0))
            sample = wind[row, d] * (0.0 if d == 2 else 1.0)
            estimate[row, d] = estimate[row, d] + weight_estimate * (sample - estimate[row, d])
            average[row, d] = average[row, d] + weight_average * (sample - average[row, d])
        px4[row] = px4_limit > 0.0 and np.hypot(estimate[row, 0], estimate[row, 1]) > px4_limit
        operator[row] = judged and operator_limit > 0.0 and np.hypot(average[row, 0], average[row, 1]) > operator_limit
        hx, hy, hz = home[row, 0] - position[row, 0], home[row, 1] - position[row, 1], home[row, 2] - position[row, 2]
        distance = np.sqrt(hx ** 2 + hy ** 2 + hz ** 2)
        tailwind = (estimate[row, 0] * hx + estimate[row, 1] * hy + estimate[row, 2] * hz) / np.maximum(distance, 1e-9)
        ground = np.maximum(cruise_m_s + tailwind, 1.0)
        due[row] = battery_on and energy_j[row] - straight_home_energy_j(distance, ground, cruise_power_w) <= reserve_j
        fast = return_m_s + tailwind
        reachable[row] = distance < 1e-9 or (fast >= MIN_HOME_GROUND_SPEED_M_S and (
            not battery_on or energy_j[row] > straight_home_energy_j(distance, fast, return_power_w)))
    return due, px4, operator, reachable


class Decisions(NamedTuple):
    """The autopilot's decisions of one chunk, (batch,) bool each: battery due home (reserve + the energy
    home), the PX4-style wind limit exceeded, the operator's average-wind policy exceeded, home reachable
    (ground speed towards home at the top airspeed and the energy for it)."""

    battery_due: np.ndarray
    px4_wind: np.ndarray
    operator_wind: np.ndarray
    home_reachable: np.ndarray


class WindEstimate:
    """The autopilot's horizontal wind estimates of ``n`` flights stepping ``dt_s``: the current one (first-order
    lag ``mission.wind_estimate_tau_s``) and the operator's average (``operator_wind_average_s``). Each starts
    as the running mean (a new sample's weight is never below 1 / samples so far), so the first gust after
    take-off does not dominate the first time constant."""

    def __init__(self, n: int, dt_s: float, mission: MissionSection):
        self.dt_s, self.mission = float(dt_s), mission
        self.current = np.zeros((n, 3))
        self.average = np.zeros((n, 3))
        self.samples = 0
        self.elapsed_s = 0.0

    def weights(self) -> tuple[float, float, bool]:
        """(weight of the new sample in the current estimate, in the average, average judged) for this step."""
        self.samples += 1
        if self.samples > 1:
            self.elapsed_s += self.dt_s
        floor = 1.0 / self.samples
        m = self.mission
        w_now = max(1.0 - np.exp(-self.dt_s / m.wind_estimate_tau_s), floor)
        w_avg = max(1.0 - np.exp(-self.dt_s / m.operator_wind_average_s), floor)
        return float(w_now), float(w_avg), self.elapsed_s >= m.operator_wind_average_s


def decide(estimate: WindEstimate, home: np.ndarray, position: np.ndarray, wind: np.ndarray, cruise_m_s: float,
           cruise_power_w: float, return_power_w: float, energy_j: np.ndarray, reserve_j: float,
           battery_on: bool) -> Decisions:
    """This chunk's :class:`Decisions` for vehicles at ``position`` (n, 3) m in ``wind`` (n, 3) m/s, home at
    ``home`` (n, 3) m, with ``energy_j`` (n,) J left. The way home on energy is flown at the cruise airspeed
    ``cruise_m_s`` (``cruise_power_w``), its ground speed helped or hindered by the estimated wind along it (at
    least 1 m/s); reachability at the mission's top airspeed (``return_power_w``)."""
    m = estimate.mission
    w_now, w_avg, judged = estimate.weights()
    return Decisions(*_decision_rows(home, position, wind, estimate.current, estimate.average, w_now, w_avg, judged,
                                     float(m.px4_wind_limit_m_s or 0.0), float(m.operator_wind_limit_m_s or 0.0),
                                     float(cruise_m_s), float(cruise_power_w), float(m.return_airspeed_m_s),
                                     float(return_power_w), energy_j, float(reserve_j), bool(battery_on)))


def travel_time_s(start: NDArray[np.float64], end: NDArray[np.float64], wind: NDArray[np.float64],
                  airspeed_m_s: float) -> NDArray[np.float64]:
    """(n,) s to fly straight from ``start`` to ``end`` (n, 3) m at ``airspeed_m_s`` with the horizontal
    ``wind`` (n, 3) m/s along the way (ground speed airspeed + the wind's component along the leg, at least
    1 m/s, as the energy rule's estimate)."""
    delta = end - start
    distance: NDArray[np.float64] = np.linalg.norm(delta, axis=1)
    along: NDArray[np.float64] = np.einsum("ij,ij->i", wind[:, :2], delta[:, :2]) / np.maximum(distance, 1e-9)
    return distance / np.maximum(airspeed_m_s + along, 1.0)
