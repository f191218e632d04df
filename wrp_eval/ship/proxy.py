"""The cuboid proxy above the waterline (paper Sec. 3.1, Fig. 2) and its no-fly zone.

The proxy spans x in [-L/2, L/2] (bow +x), y in [-B/2, B/2] (port +y), z in [0, freeboard + superstructure].
Its five faces (the bottom is never photographed) are the planning surfaces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wrp_eval.ship.particulars import ShipParticulars, ShipType

FACE_NAMES = ("bow", "stern", "port", "starboard", "top")

# No-fly margin r by ship type (paper Sec. 3.1: "adaptive value according to different ship types"; the
# paper gives no numbers). Our choice: clear masts, cranes, rigging and funnel plumes, larger for ships with
# tall, protruding or busy upper works.
NO_FLY_MARGIN_M = {
    ShipType.STYLIZED: 5.0,
    ShipType.CRUISE: 8.0,
    ShipType.CONTAINER: 8.0,
    ShipType.FISHING: 6.0,   # outriggers, booms and nets reach well outside the hull
    ShipType.TANKER: 6.0,
}


@dataclass(frozen=True)
class Proxy:
    """Cuboid proxy. Arrays are per face, in ``FACE_NAMES`` order (5 faces, bottom excluded).

    centers (5, 3) m; normals (5, 3) outward unit; u_axes, v_axes (5, 3) unit in-plane axes with
    u x v = normal; half_extents (5, 2) m along u and v; no_fly_margin_m: r.
    """

    length_m: float
    breadth_m: float
    height_m: float
    no_fly_margin_m: float
    centers: np.ndarray
    normals: np.ndarray
    u_axes: np.ndarray
    v_axes: np.ndarray
    half_extents: np.ndarray

    @property
    def face_names(self) -> tuple[str, ...]:
        return FACE_NAMES

    @property
    def areas(self) -> np.ndarray:
        """Face areas (5,) in m^2."""
        return 4.0 * self.half_extents[:, 0] * self.half_extents[:, 1]

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3): min and max corners of the cuboid."""
        half = np.array([self.length_m / 2, self.breadth_m / 2])
        return np.array([[-half[0], -half[1], 0.0], [half[0], half[1], self.height_m]])

    @property
    def center(self) -> np.ndarray:
        return self.bounds.mean(axis=0)

    def no_fly_bounds(self) -> np.ndarray:
        """(2, 3) corners of the no-fly box: the cuboid inflated by r (down to the sea). What is inside it,
        and what may be flown, is :mod:`wrp_eval.ship.nofly`'s."""
        b = self.bounds.copy()
        b[0, :2] -= self.no_fly_margin_m
        b[1] += self.no_fly_margin_m
        b[0, 2] = 0.0
        return b

    def face_points(self, face: int, uv: np.ndarray) -> np.ndarray:
        """Map face coordinates uv (n, 2) in metres from the face centre to world points (n, 3)."""
        uv = np.asarray(uv, dtype=float)
        return self.centers[face] + uv[:, :1] * self.u_axes[face] + uv[:, 1:2] * self.v_axes[face]

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """Closed cuboid as (vertices (8, 3), faces (12, 3)) with outward orientation (for ray casting)."""
        lo, hi = self.bounds
        v = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],   # -x, +x
                      [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],   # -y, +y
                      [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])  # -z, +z
        return v, f


def build_proxy(particulars: ShipParticulars, no_fly_margin_m: float | None = None,
                height_error: float = 0.0) -> Proxy:
    """The proxy of ``particulars``; ``no_fly_margin_m`` overrides the per-type margin; ``height_error`` (a signed
    fraction) makes the proxy's height (1 + height_error) x the true height above the waterline, the paper's
    Table 1 experiment on an inaccurate proxy (the ship itself is unchanged)."""
    length = particulars.length_bp_m
    breadth = particulars.breadth_m
    height = particulars.height_above_water_m * (1.0 + float(height_error))
    if min(length, breadth, height) <= 0:
        raise ValueError(f"proxy dimensions must be positive, got L={length}, B={breadth}, H={height}")
    margin = NO_FLY_MARGIN_M[particulars.ship_type] if no_fly_margin_m is None else float(no_fly_margin_m)
    hl, hb, hh = length / 2, breadth / 2, height / 2
    ex, ey, ez = np.eye(3)
    centers = np.array([[hl, 0, hh], [-hl, 0, hh], [0, hb, hh], [0, -hb, hh], [0, 0, height]], dtype=float)
    normals = np.array([ex, -ex, ey, -ey, ez])
    # u horizontal (or along x on top), v = n x u so that u x v = n.
    u_axes = np.array([ey, -ey, -ex, ex, ex])
    v_axes = np.cross(normals, u_axes)
    half_extents = np.array([[hb, hh], [hb, hh], [hl, hh], [hl, hh], [hl, hb]], dtype=float)
    return Proxy(length, breadth, height, margin, centers, normals, u_axes, v_axes, half_extents)
