"""Aerodynamic drag from the paper's windward area (Sec. 4.1, Fig. 5).

Paper: the windward area is the main body (a cuboid) plus four cylinders swept by the blades.
Main body: dot1 = (unit normal of the wind vector) . (UAV speed vector scaled to the body length),
dot2 = (unit normal of the wind vector) . (unit normal of the speed vector scaled to the body width);
A_body = (|dot1| + |dot2|) * body height. Each blade cylinder adds half its lateral surface,
pi r h (the "half of the surface area of the cylinder without the bottom surface").

Our reading, in terms we can compute on a moving, yawing vehicle:
  - "wind vector" = the relative air velocity v_rel = wind(at the vehicle) - vehicle velocity, the air the
    airframe actually meets (equal to the wind when hovering);
  - "UAV speed vector" = the body's forward axis x_b (the paper's UAV flies nose-first, so its speed
    vector and its heading coincide; when hovering the speed is zero and only the heading is defined).
    Its normal is the body's lateral axis y_b. Both are taken horizontal (the paper ignores tilt);
  - so with n the horizontal unit normal of v_rel: dot1 = L (n . x_b), dot2 = W (n . y_b), and
    (|dot1| + |dot2|) H = H (L |sin b| + W |cos b|), b the angle between v_rel and x_b: exactly the
    cuboid's projected area seen along v_rel. Rotors: 4 pi r h, independent of direction.
  - Extension (the paper only has horizontal wind): for a vertical component of v_rel we blend in the
    top area L W of the body, A = A_h cos(e) + L W sin(e), e = elevation of v_rel.
Drag F = 0.5 rho C_d A |v_rel| v_rel (the drag coefficient's definition C_D = D / (0.5 rho V^2 S), e.g.
Anderson, *Fundamentals of Aerodynamics*, Sec. 1.5), applied at the centre of mass.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.compiled import kernel
from wrp_eval.sim.vehicle import QuadrotorParams


@kernel
def _area_row(rx: float, ry: float, rz: float, yaw: float, length: float, width: float, height: float,
              rotor_radius: float, rotor_height: float) -> float:
    """Windward area m^2 of one vehicle: relative air (rx, ry, rz) m/s, body yaw rad, body box and rotor
    cylinder sizes m (module docstring)."""
    horizontal: float = np.hypot(rx, ry)
    speed: float = np.sqrt(horizontal ** 2 + rz ** 2)
    safe_h = horizontal if horizontal > 0.0 else 1.0
    # horizontal unit normal of the wind direction (rotate the direction by +90 deg)
    nx, ny = -ry / safe_h, rx / safe_h
    cos_y, sin_y = np.cos(yaw), np.sin(yaw)
    dot1 = length * (nx * cos_y + ny * sin_y)          # n . x_b * L
    dot2 = width * (-nx * sin_y + ny * cos_y)          # n . y_b * W
    side: float = (abs(dot1) + abs(dot2)) * height + 4.0 * np.pi * rotor_radius * rotor_height
    if not speed > 0.0:
        return side
    cos_e, sin_e = horizontal / speed, abs(rz) / speed
    return (side * cos_e if horizontal > 0.0 else 0.0) + length * width * sin_e


@kernel
def _drag_rows(rel_air: NDArray[np.float64], yaw: NDArray[np.float64], length: float, width: float, height: float,
               rotor_radius: float, rotor_height: float, drag_coefficient: float,
               air_density: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(area (n,) m^2, drag (n, 3) N) for relative air (n, 3) m/s and yaw (n,) rad."""
    n = rel_air.shape[0]
    area, drag = np.empty(n), np.empty((n, 3))
    for row in range(n):
        rx, ry, rz = rel_air[row, 0], rel_air[row, 1], rel_air[row, 2]
        area[row] = _area_row(rx, ry, rz, yaw[row], length, width, height, rotor_radius, rotor_height)
        speed = np.sqrt(rx ** 2 + ry ** 2 + rz ** 2)
        k = 0.5 * air_density * drag_coefficient * area[row] * speed
        drag[row, 0], drag[row, 1], drag[row, 2] = k * rx, k * ry, k * rz
    return area, drag


def _drag(rel_air: ArrayLike, yaw: ArrayLike, params: QuadrotorParams, drag_coefficient: float,
          air_density_kg_m3: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    rel_air = np.asarray(rel_air, dtype=float)
    yaw = np.broadcast_to(np.asarray(yaw, dtype=float), rel_air.shape[:1])
    return _drag_rows(rel_air, yaw, params.body_length_m, params.body_width_m, params.body_height_m,
                      params.rotor_radius_m, params.rotor_height_m, float(drag_coefficient), float(air_density_kg_m3))


def windward_area(rel_air: np.ndarray, yaw: np.ndarray, params: QuadrotorParams) -> np.ndarray:
    """Windward area (n,) in m^2 for relative air velocities ``rel_air`` (n, 3) m/s and body yaw (n,) rad."""
    return _drag(rel_air, yaw, params, 1.0, 1.0)[0]


def drag_force(rel_air: np.ndarray, yaw: np.ndarray, params: QuadrotorParams,
               drag_coefficient: float, air_density_kg_m3: float) -> np.ndarray:
    """Drag (n, 3) N along the relative air velocity: 0.5 rho C_d A |v_rel| v_rel (one compiled loop over the
    vehicles, :mod:`wrp_eval.compiled`)."""
    return _drag(rel_air, yaw, params, drag_coefficient, air_density_kg_m3)[1]
