"""Electrical power and battery of the quadrotor: what a sortie costs and when it must turn for home.

Power model (the classic rotorcraft power decomposition, Leishman, *Principles of Helicopter Aerodynamics*,
2nd ed., Cambridge UP 2006, Ch. 2 (momentum theory, figure of merit) and Ch. 5 (forward-flight power =
induced + profile + parasite); the same split for multirotors: Liu, Sengupta & Kurzhanskiy, "A power
consumption model for multi-rotor small unmanned aircraft systems", ICUAS 2017)::

    P_el = P_induced / (FoM * eta_drive) + |F_drag . v_rel| / eta_drive + P_avionics

* ``P_induced`` = sum over rotors of T^(3/2) / sqrt(2 rho A): momentum theory's ideal hover power
  (Leishman Ch. 2). The figure of merit FoM = ideal / actual rotor power (Leishman Ch. 2) adds the
  profile (blade drag) and non-ideal losses, so P_induced / FoM is the rotors' shaft power at hover.
* ``|F_drag . v_rel|`` = 0.5 rho C_d A |v_rel|^3: the parasite power, the work per second the rotors do
  against the airframe's drag in the *air* frame (Leishman Ch. 5). It is there whenever the vehicle
  moves relative to the air, also when it holds position in a steady wind.
* ``eta_drive`` = motor x ESC efficiency: shaft power -> battery power.
* ``P_avionics``: flight controller, gimbal, camera, video link: a constant.

This module imports no simulator code at run time (``QuadrotorParams`` only for type hints), so that the
``sim:`` schema can hold :class:`BatterySection` without pulling MuJoCo into config parsing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, ValidationInfo, field_validator

from wrp_eval.compiled import kernel
from wrp_eval.schema import StrictModel

if TYPE_CHECKING:
    from wrp_eval.sim.vehicle import QuadrotorParams

JOULES_PER_WH = 3600.0

_Value = TypeVar("_Value", float, NDArray[np.float64])


class BatterySection(StrictModel):
    """Battery and power-train settings (``sim.battery``).

    Sources of the defaults:
      - capacity_wh 89.2: DJI Phantom 4 Pro / Pro V2.0 Intelligent Flight Battery, 5870 mAh, 15.2 V LiPo 4S,
        89.2 Wh (dji.com/phantom-4-pro/info, "Intelligent Flight Battery"; the same 5870 mAh pack fits the
        Phantom 4 airframe: o-gs/dji-firmware-tools wiki "WM330 Battery Intelligent Board"). Spec-sheet
        flight time ~30 min. The original Phantom 4 pack is 5350 mAh, 15.2 V = 81.3 Wh, ~28 min
        (dji.com/phantom-4/info).
      - reserve 0.15: PX4 ``BAT_LOW_THR`` default 0.15, the charge at which PX4 reports the battery low
        (PX4-Autopilot src/lib/battery/battery_params_common.c; ``BAT_CRIT_THR`` 0.07 triggers RTL,
        ``BAT_EMERGEN_THR`` 0.05 landing). Our return is triggered by *predicted* arrival charge (like DJI's
        Smart Return-to-Home, which computes the power needed to fly home), so the reserve is the charge the
        drone should still have when it lands at home; the low threshold, not the critical one, leaves a
        margin for the simple return model and the landing.
      - figure_of_merit 0.65: "in practice usually between 0.5-0.7" for real rotors (Leishman Ch. 2;
        S. Kumar, HeliAeroNotes, "Figure of Merit"); small rotors at low Reynolds number sit in the lower
        half ("Comparison of the hovering efficiency of rotating wing and flapping wing micro air
        vehicles", J. AHS 55, 025001, 2010).
      - drive_efficiency 0.85: combined brushless motor + ESC efficiency, 0.8-0.9 near the hover operating
        point of quality multirotor drives (Bershadsky, Haviland & Johnson, "Electric multirotor propulsion
        system sizing for performance prediction and design optimization", AIAA SciTech 2016: eta_M, eta_E;
        thrust-stand data as combined motor+ESC efficiency: Tyto Robotics/RCbenchmark).
      - avionics_w 10: *assumed* (no published Phantom 4 figure found): flight controller, vision sensors,
        4K camera, 3-axis gimbal and the Lightbridge video link, a few percent of the ~140 W hover power.
    """

    enabled: bool = Field(True, description="track energy and end sorties at the reserve")
    capacity_wh: float = Field(89.2, gt=0.0, le=10_000.0, description="usable battery energy (Wh)")
    start_charge: float = Field(1.0, ge=0.0, le=1.0, description="state of charge at take-off (fraction)")
    reserve: float = Field(0.15, ge=0.0, le=1.0,
                           description="charge (fraction) still held when the drone lands back home: the "
                                       "sortie ends when charge - return energy reaches it")
    figure_of_merit: float = Field(0.65, gt=0.0, le=1.0, description="rotor hover figure of merit")
    drive_efficiency: float = Field(0.85, gt=0.0, le=1.0, description="motor x ESC efficiency")
    avionics_w: float = Field(10.0, ge=0.0, le=1000.0,
                              description="constant draw of flight controller, gimbal, camera, video link (W)")

    @field_validator("reserve")
    @classmethod
    def _reserve_below_start(cls, reserve: float, info: ValidationInfo) -> float:
        start = info.data.get("start_charge")      # absent when start_charge itself failed validation
        if start is not None and reserve >= start:
            raise ValueError(f"must be below start_charge ({start}): the drone would have to return at once")
        return reserve

    @property
    def capacity_j(self) -> float:
        return self.capacity_wh * JOULES_PER_WH


def rotor_disk_area_m2(params: QuadrotorParams) -> float:
    """Area (m^2) swept by one rotor, pi r^2."""
    return float(np.pi * params.rotor_radius_m ** 2)


@kernel
def _induced_row(thrust: NDArray[np.float64], rotor_area_m2: float, air_density: float) -> float:
    """Induced power W of one vehicle's rotors ``thrust`` (n_rotors,) N (:func:`induced_power_w`)."""
    total = 0.0
    for k in range(thrust.size):
        total += np.maximum(thrust[k], 0.0) ** 1.5
    root: float = np.sqrt(2.0 * air_density * rotor_area_m2)
    return total / root


@kernel
def _parasite_row(drag: NDArray[np.float64], rel_air: NDArray[np.float64]) -> float:
    """|F_drag . v_rel| W of one vehicle (:func:`parasite_power_w`)."""
    power: float = abs(drag[0] * rel_air[0] + drag[1] * rel_air[1] + drag[2] * rel_air[2])
    return power


@kernel
def _power_rows(thrust: NDArray[np.float64], drag: NDArray[np.float64], rel_air: NDArray[np.float64],
                rotor_area_m2: float, air_density: float, figure_of_merit: float, drive_efficiency: float,
                avionics_w: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(induced (n,), parasite (n,), electrical (n,)) W of :func:`electrical_power_w`, row by row."""
    n = thrust.shape[0]
    induced, parasite, electrical = np.empty(n), np.empty(n), np.empty(n)
    for row in range(n):
        induced[row] = _induced_row(thrust[row], rotor_area_m2, air_density)
        parasite[row] = _parasite_row(drag[row], rel_air[row])
        electrical[row] = (induced[row] / figure_of_merit + parasite[row]) / drive_efficiency + avionics_w
    return induced, parasite, electrical


def _powers(thrust_per_motor_n: ArrayLike, drag_force_n: ArrayLike | None, rel_air_m_s: ArrayLike | None,
            rotor_area_m2: float, air_density: float,
            section: BatterySection | None = None) -> tuple[NDArray[np.float64], ...]:
    thrust = np.asarray(thrust_per_motor_n, dtype=float)
    flat = thrust.reshape(-1, thrust.shape[-1])
    n = len(flat)
    drag = np.zeros((n, 3)) if drag_force_n is None else np.asarray(drag_force_n, float).reshape(n, 3)
    rel = np.zeros((n, 3)) if rel_air_m_s is None else np.asarray(rel_air_m_s, float).reshape(n, 3)
    fom, eta, avionics = (1.0, 1.0, 0.0) if section is None else (section.figure_of_merit, section.drive_efficiency,
                                                                   section.avionics_w)
    out = _power_rows(flat, drag, rel, float(rotor_area_m2), float(air_density), float(fom), float(eta),
                      float(avionics))
    return tuple(x.reshape(thrust.shape[:-1])[()] for x in out)    # [()]: a number for one vehicle


def induced_power_w(thrust_per_motor_n: np.ndarray, rotor_area_m2: float, air_density: float) -> np.ndarray:
    """Ideal induced power (n,) W of the rotors: sum over rotors of T^(3/2) / sqrt(2 rho A).

    ``thrust_per_motor_n`` (n, n_rotors) N (negative values count as zero: a fixed-pitch rotor cannot push);
    ``rotor_area_m2`` one rotor's disk area; ``air_density`` kg/m^3. Momentum theory at hover (Leishman
    Ch. 2). In forward flight (or in a wind) the through-flow lowers the induced velocity and with it the
    induced power (Glauert's v_i = T / (2 rho A sqrt(V^2 + v_i^2)), Leishman Ch. 2 and 5); we neglect that,
    which over-estimates the power and is the conservative side for an energy reserve.
    """
    return _powers(thrust_per_motor_n, None, None, rotor_area_m2, air_density)[0]


def parasite_power_w(drag_force_n: np.ndarray, rel_air_m_s: np.ndarray) -> np.ndarray:
    """Parasite power (n,) W = |F_drag . v_rel|: drag (n, 3) N times the relative air velocity (n, 3) m/s.

    For the drag of :func:`wrp_eval.sim.aero.drag_force` this is 0.5 rho C_d A |v_rel|^3 (Leishman Ch. 5).
    """
    drag = np.asarray(drag_force_n, float)
    return _powers(np.zeros((len(drag), 1)), drag, rel_air_m_s, 1.0, 1.0)[1]


def electrical_power_w(thrust_per_motor_n: np.ndarray, drag_force_n: np.ndarray, rel_air_m_s: np.ndarray,
                       params: QuadrotorParams, section: BatterySection, air_density: float) -> np.ndarray:
    """Battery power (n,) W of a batch: P_ind / (FoM eta) + |F_drag . v_rel| / eta + P_avionics.

    ``thrust_per_motor_n`` (n, 4) N (the motor commands; in a wind they already include the tilt that
    balances the drag), ``drag_force_n`` (n, 3) N and ``rel_air_m_s`` (n, 3) m/s (wind - vehicle velocity),
    ``air_density`` kg/m^3. Decomposition: Leishman Ch. 5, Liu et al. (ICUAS 2017); see the module docstring.
    The parasite power is divided by the drive efficiency only (the figure of merit is a hover quantity).
    One compiled loop over the vehicles (:mod:`wrp_eval.compiled`).
    """
    return _powers(thrust_per_motor_n, drag_force_n, rel_air_m_s, rotor_disk_area_m2(params), air_density, section)[2]


def hover_power_w(params: QuadrotorParams, section: BatterySection, air_density: float) -> float:
    """Battery power (W) at hover in still air: 4 (mg/4)^(3/2) / sqrt(2 rho A) / (FoM eta) + P_avionics."""
    thrust = np.full((1, 4), params.weight_n / 4.0)
    return float(electrical_power_w(thrust, np.zeros((1, 3)), np.zeros((1, 3)), params, section, air_density)[0])


def return_energy_j(distance_home_m: np.ndarray, speed_m_s: ArrayLike, cruise_power_w: ArrayLike) -> np.ndarray:
    """Energy (n,) J to fly home: straight line at constant ground speed and constant power, E = P d / V.

    ``distance_home_m`` (n,) m, ``speed_m_s`` float or (n,) m/s ground speed towards home (> 0; pass the
    cruise airspeed minus the head-wind component for a wind-aware estimate), ``cruise_power_w`` float or
    (n,) W (e.g. the present power, or :func:`level_flight_power_w` at the cruise speed). A simple model:
    no acceleration, climb or landing phase (the reserve covers them), like the distance/speed estimate of
    DJI's Smart RTH and PX4's RTL time estimate.
    """
    speed = np.asarray(speed_m_s, dtype=float)
    if np.any(speed <= 0.0):
        raise ValueError("return speed must be positive")
    return straight_home_energy_j(np.asarray(distance_home_m, dtype=float), speed, np.asarray(cruise_power_w, float))


@kernel
def straight_home_energy_j(distance_home_m: _Value, speed_m_s: _Value, cruise_power_w: _Value) -> _Value:
    """E = P d / V (:func:`return_energy_j` without its check), numbers or arrays."""
    return cruise_power_w * distance_home_m / speed_m_s


def level_flight_power_w(airspeed_m_s: np.ndarray, params: QuadrotorParams, section: BatterySection,
                         drag_coefficient: float, air_density: float) -> np.ndarray:
    """Battery power (n,) W in steady level flight, nose first, at ``airspeed_m_s`` (n,) m/s.

    Trim: the thrust vector balances weight and drag, so each motor gives sqrt(W^2 + D^2) / 4; the drag is
    the windward-area drag of :mod:`wrp_eval.sim.aero` with the air coming head-on.
    """
    # aero imports vehicle (MuJoCo): imported here so that the sim schema can import this module cheaply
    from wrp_eval.sim.aero import drag_force

    speed = np.atleast_1d(np.asarray(airspeed_m_s, dtype=float))
    rel_air = np.stack([-speed, np.zeros_like(speed), np.zeros_like(speed)], axis=1)
    drag = drag_force(rel_air, np.zeros_like(speed), params, drag_coefficient, air_density)
    per_motor = np.hypot(params.weight_n, np.linalg.norm(drag, axis=1)) / 4.0
    return electrical_power_w(np.repeat(per_motor[:, None], 4, axis=1), drag, rel_air, params, section,
                              air_density)


class Battery:
    """Remaining energy of a batch of flights (state ``energy_j`` (n,) J, from ``start_charge``).

    Energy is counted in joules, linear in the drawn power (no Peukert effect, no voltage sag, no
    temperature: a constant-capacity energy reservoir, as in Liu et al. 2017's endurance estimate).
    """

    def __init__(self, section: BatterySection, n_flights: int):
        self.section = section
        self.capacity_j = section.capacity_j
        self.reserve_j = section.reserve * self.capacity_j
        self.energy_j = np.full(n_flights, section.start_charge * self.capacity_j)

    def drain(self, power_w: np.ndarray, dt_s: float, active: np.ndarray | None = None) -> None:
        """Draw ``power_w`` (n,) W for ``dt_s`` s on the flights where ``active`` (n,) bool (default all);
        the energy stops at zero (an empty battery: see :attr:`depleted`)."""
        drawn = np.asarray(power_w, dtype=float) * dt_s
        if active is not None:
            drawn = np.where(active, drawn, 0.0)
        self.energy_j = np.maximum(self.energy_j - drawn, 0.0)

    @property
    def charge(self) -> np.ndarray:
        """(n,) state of charge, fraction of the capacity."""
        return self.energy_j / self.capacity_j

    @property
    def depleted(self) -> np.ndarray:
        """(n,) bool: the battery is empty (the flight fell short of home)."""
        return self.energy_j <= 0.0

    def needs_return(self, return_energy_j: np.ndarray) -> np.ndarray:
        """(n,) bool: energy - return energy <= reserve, i.e. turning now lands home with just the reserve.

        ``return_energy_j`` (n,) J or float (:func:`return_energy_j`; 0 for a pure reserve check). Always
        False when the section is disabled."""
        due: NDArray[np.bool_] = self.energy_j - np.asarray(return_energy_j, dtype=float) <= self.reserve_j
        return due & self.section.enabled

    def endurance_s(self, power_w: ArrayLike) -> np.ndarray:
        """(n,) s until the reserve at constant ``power_w`` (W): (energy - reserve) / P, at least 0."""
        endurance: NDArray[np.float64] = (np.maximum(self.energy_j - self.reserve_j, 0.0)
                                          / np.asarray(power_w, dtype=float))
        return endurance
