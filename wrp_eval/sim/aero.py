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

from wrp_eval.sim.vehicle import QuadrotorParams


def windward_area(rel_air: np.ndarray, yaw: np.ndarray, params: QuadrotorParams) -> np.ndarray:
    """Windward area (n,) in m^2 for relative air velocities ``rel_air`` (n, 3) m/s and body yaw (n,) rad."""
    rel_air = np.asarray(rel_air, dtype=float)
    yaw = np.asarray(yaw, dtype=float)
    horizontal = np.hypot(rel_air[:, 0], rel_air[:, 1])
    speed = np.sqrt(horizontal ** 2 + rel_air[:, 2] ** 2)
    safe_h = np.where(horizontal > 0.0, horizontal, 1.0)
    # horizontal unit normal of the wind direction (rotate the direction by +90 deg)
    nx, ny = -rel_air[:, 1] / safe_h, rel_air[:, 0] / safe_h
    cos_y, sin_y = np.cos(yaw), np.sin(yaw)
    dot1 = params.body_length_m * (nx * cos_y + ny * sin_y)          # n . x_b * L
    dot2 = params.body_width_m * (-nx * sin_y + ny * cos_y)          # n . y_b * W
    body = (np.abs(dot1) + np.abs(dot2)) * params.body_height_m
    rotors = 4.0 * np.pi * params.rotor_radius_m * params.rotor_height_m
    side = body + rotors
    top = params.body_length_m * params.body_width_m
    safe_s = np.where(speed > 0.0, speed, 1.0)
    cos_e, sin_e = horizontal / safe_s, np.abs(rel_air[:, 2]) / safe_s
    area = np.where(horizontal > 0.0, side * cos_e, 0.0) + top * sin_e
    return np.where(speed > 0.0, area, side)


def drag_force(rel_air: np.ndarray, yaw: np.ndarray, params: QuadrotorParams,
               drag_coefficient: float, air_density_kg_m3: float) -> np.ndarray:
    """Drag (n, 3) N along the relative air velocity: 0.5 rho C_d A |v_rel| v_rel."""
    rel_air = np.asarray(rel_air, dtype=float)
    area = windward_area(rel_air, yaw, params)
    speed = np.sqrt((rel_air ** 2).sum(axis=1))
    return (0.5 * air_density_kg_m3 * drag_coefficient * area * speed)[:, None] * rel_air
