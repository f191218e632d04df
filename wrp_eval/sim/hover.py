"""A hover's steady state, and the analytic weight/drag balance it must reach in a steady wind.

In a steady horizontal wind W the hovering vehicle tilts until thrust balances weight and drag:
|thrust| = hypot(|F_drag|, m g) and tan(tilt) = |F_drag| / (m g), with F_drag = 0.5 rho C_d A(W) |W| W
(:func:`wrp_eval.sim.aero.drag_force`, at the hover's yaw 0).

A default hover (``wrp-eval fly --hover``) flies the config's ``sim:`` section in a constant wind: no ship air
wake and no ship motion (no ship in the scene), but the navigation estimate of the config's preset (GNSS +
IMU fused errors: the airframe answers them, a few tenths of a degree of tilt noise), so its tilt only
approaches the balance. :func:`airframe_only` is the hover of the airframe alone (ideal navigation): the
exact balance.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from wrp_eval.sim.aero import drag_force
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.controller import wrap_angle
from wrp_eval.sim.navigation import NavigationSection
from wrp_eval.sim.results import FlightResult
from wrp_eval.sim.vehicle import PHANTOM4, QuadrotorParams


def hover_statistics(result: FlightResult, settle_fraction: float = 0.5) -> dict[str, Any]:
    """Steady-state statistics (mean, std, max) over the last ``1 - settle_fraction`` of a hover, all flights
    pooled: tilt_deg, thrust_n, drag_force_n, position_error_m, yaw_error_deg; failed count and reasons."""
    tr = result.trajectory
    s = slice(int(len(tr.time) * settle_fraction), None)
    err = tr.position[:, s] - tr.reference[:, s]
    dist = np.linalg.norm(err, axis=-1)
    yaw_err = np.degrees(np.abs(wrap_angle(tr.yaw[:, s] - tr.yaw[:, :1])))
    drag = np.linalg.norm(tr.drag[:, s], axis=-1)

    def stats(x: NDArray[np.float64]) -> dict[str, float]:
        return {"mean": float(np.mean(x)), "std": float(np.std(x)), "max": float(np.max(x))}
    return {"tilt_deg": stats(np.degrees(tr.tilt[:, s])), "thrust_n": stats(tr.thrust[:, s]),
            "drag_force_n": stats(drag), "position_error_m": stats(dist), "yaw_error_deg": stats(yaw_err),
            "failed": int(result.failed.sum()), "failure_reasons": [r for r in result.failure_reason if r]}


def analytic_hover_balance(wind_m_s: np.ndarray, section: SimSection,
                           params: QuadrotorParams = PHANTOM4) -> dict[str, float]:
    """The balance of a hover at yaw 0 in the steady wind ``wind_m_s`` (3,) m/s, ship frame: drag_force_n,
    tilt_deg and thrust_n."""
    f = drag_force(np.asarray(wind_m_s, dtype=float)[None], np.zeros(1), params, section.drag_coefficient,
                   section.air_density_kg_m3)[0]
    return {"drag_force_n": float(np.linalg.norm(f)),
            "tilt_deg": float(np.degrees(np.arctan2(np.linalg.norm(f), params.weight_n))),
            "thrust_n": float(np.hypot(np.linalg.norm(f), params.weight_n))}


def airframe_only(section: SimSection) -> SimSection:
    """``section`` with ideal navigation (the controller sees the true state): with a constant wind, no air
    wake and no ship (what :meth:`FlightSimulator.hover` flies) the hover is the airframe's exact balance."""
    return section.model_copy(update={"navigation": NavigationSection(preset="ideal")})
