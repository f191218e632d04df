"""The ship's air wake: the lee of the hull box, where the mean wind drops and the turbulence rises.

The ship is its cuboid proxy (``wrp_eval.ship.proxy``: x +-L/2, y +-B/2, z 0..H), a sharp-edged bluff block
on the sea, so the model is the empirical building wake of PRIME, the building-downwash model of EPA's AERMOD
(Schulman, Strimaitis & Scire 2000, "Development and evaluation of the PRIME plume rise and building downwash
model", J. Air & Waste Manage. Assoc. 50:378-390; numbers read from AERMOD's ``prime.f``, subroutines
``wake_scales``, ``wake_dim``, ``wake_u``, ``wake_turb``, ``prime1``). Ship air-wake studies describe the
same flow behind a superstructure: a separated shear layer over a recirculation region like a backward-facing
step's (Brownell, Luznik, Kang & Snyder, APS DFD 2012, at-sea sonic anemometry on the USNA YP; Forrest & Owen
2010, Computers & Fluids 39:656, SFS2 / Type 23 DES validated against NRC wind-tunnel data), and the geometry
changes with the wind-over-deck angle, which is why every length below follows the wind.

Geometry, per row, from the horizontal direction d of that row's mean wind (the wake lies downwind of the box,
whatever the angle): s = along d, c = across (to the left), measured from the box centre. As BPIP/PRIME do
for each wind direction, the block seen by the wind has the projected width W = 2 hc and the along-wind length
Lw = 2 hs (hs = L/2 |dx| + B/2 |dy|, hc = L/2 |dy| + B/2 |dx|) and the height H. Then (PRIME):
    R   = min(H, W)^(2/3) max(H, W)^(1/3)                   Wilson (1979) scale length, H/W clipped to 1/8..8
    L_R = 1.8 W / ((Lw/H)^e (1 + 0.24 W/H))                 Fackrell (1984) cavity length behind the lee face,
          Lw/H clipped to 0.3..3, e = 0.3 (W/H >= 1), 0.3 (W/H - 0.33)/0.67 (Snyder: no L/H effect at W/H 1/3)
    H_R = H + 0.22 R                                        top of the recirculation cavity (Wilson, ASHRAE)
    h_w = 1.2 R (x/R + (H/(1.2 R))^3)^(1/3)                 wake height, x from the upwind face (Weil 1996)
    y_w = W/2 + (R/3) (x/R)^(1/3)                           wake half-width (Snyder's wind-tunnel fit)
A cube gives L_R = 1.45 H; a beam wind on a 140 x 20 x 21 m ship gives L_R = 4.7 H, a head wind 1.0 H.

Fields (all factors smooth, C1 except where a plateau meets a decay, where they stay continuous):
    deficit = D0 S(x') F(c) G_d(z)          fraction of the mean wind removed, D0 = ``lee_deficit`` (0.7)
    gain    = 1 + (K0 - 1) S(x') F(c) G_t(z)   multiplier of the turbulence, K0 = ``turbulence_ratio`` (1.7)
x' = distance past the box's lee boundary along d at the point's crosswind position (beside the box: at its
side). Streamwise S: over the footprint it ramps from 0 at the windward boundary to 1 at the lee boundary
(PRIME interpolates over the roof the same way, linearly; where the fetch over the footprint is shorter than
0.25 R, near the corners, the ramp runs on past the lee boundary); 1 through the cavity 0 <= x' <= L_R;
then ((x' - L_R + R)/R)^(-2/3), PRIME's decay of both the speed deficit and the wake turbulence, restarted at
the cavity end; tapered to 0 over the last half of ``extent_scale_lengths`` R past the cavity (PRIME caps
wake effects at 15 R). Lateral F: 1 inside
the shadow |c| <= hc, tapering to 0 at PRIME's half-width growth (R/3)(x/R)^(1/3) beyond it. Vertical: the
deficit is full up to the block height H, the turbulence gain up to the cavity top H_R (its shear layer);
both taper to 0 at the wake height h_w (not below H_R + 0.22 R: assumed, one roof-cavity height of shear
layer over the cavity, so that the taper never has zero width). Upwind of the box, beside it beyond the
half-width, above h_w and past the extent: exactly 0 deficit and gain 1.

Known limits (Petersen, Guerra & Bova 2017, J. Air & Waste Manage. Assoc. 67:826, critique of PRIME): the
enhanced turbulence is uniform up to the wake height and does not depend on the approach flow's roughness
or stability; a real superstructure (bridge, hangar, funnel) makes a more local wake than the whole-ship box.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wrp_eval.compiled import kernel

if TYPE_CHECKING:
    from wrp_eval.wind.config import AirWakeSection

# PRIME constants (AERMOD prime.f): cavity top H + 0.22 R (Wilson 1979 / ASHRAE), wake height coefficient 1.2
# (Weil 1996), far-wake decay exponent 2/3 (prime1 ``xdecay``), Fackrell's cavity-length coefficients.
CAVITY_TOP_R = 0.22
WAKE_HEIGHT_COEF = 1.2
DECAY_EXPONENT = 2.0 / 3.0
FACKRELL_COEF, FACKRELL_WIDTH_COEF, FACKRELL_LENGTH_EXP = 1.8, 0.24, 0.3
# Assumed (numerical, no source): the shortest roof ramp and the narrowest lateral taper, in R, so that no
# factor changes over a zero distance at the footprint's corners (where the fetch over it shrinks to 0, the
# ramp runs on a little past the corner instead).
MIN_RAMP_R = 0.25
MIN_LATERAL_TAPER_R = 0.1
CALM_MPS = 1e-9


@kernel
def smoothstep(u: float) -> float:
    """3u^2 - 2u^3 on [0, 1], 0 below, 1 above: a C1 ramp. This and the three length functions below take
    numbers (the wake's kernels call them row by row)."""
    u = np.minimum(np.maximum(u, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


@kernel
def wilson_scale_length(height_m: float, width_m: float) -> float:
    """Wilson (1979) wake scale length R = min(H, W)^(2/3) max(H, W)^(1/3) (m), each side limited to 8 times
    the other (beyond that the block is already two-dimensional; PRIME ``wake_scales``)."""
    h = np.minimum(height_m, 8.0 * width_m)
    w = np.minimum(width_m, 8.0 * height_m)
    scale: float = np.minimum(h, w) ** (2.0 / 3.0) * np.maximum(h, w) ** (1.0 / 3.0)
    return scale


@kernel
def cavity_length(height_m: float, width_m: float, length_m: float) -> float:
    """Recirculation cavity length behind the lee face (m): Fackrell (1984) as PRIME uses it,
    L_R = 1.8 W / ((L/H)^e (1 + 0.24 W/H)), L/H clipped to 0.3..3, e = 0.3 for W/H >= 1 and falling to 0 at
    W/H = 0.33 (Snyder: the cavity stops growing as W/H = L/H goes from 1 to 1/3)."""
    rw = width_m / height_m
    rl = np.minimum(np.maximum(length_m / height_m, 0.3), 3.0)
    exponent = np.maximum(0.0, FACKRELL_LENGTH_EXP * (rw - 0.33) / 0.67) if rw < 1.0 else FACKRELL_LENGTH_EXP
    length: float = FACKRELL_COEF * width_m / (rl**exponent * (1.0 + FACKRELL_WIDTH_COEF * rw))
    return length


@kernel
def wake_height(x_m: float, height_m: float, scale_m: float) -> float:
    """PRIME wake height (m) at x (m) downwind of the upwind face: 1.2 R (x/R + (H/(1.2 R))^3)^(1/3), = H at
    x = 0 (Wilson 1979 / Weil 1996 limits for a uniform approach wind)."""
    x = np.maximum(x_m, 0.0)
    top: float = WAKE_HEIGHT_COEF * scale_m * np.cbrt(x / scale_m + (height_m / (WAKE_HEIGHT_COEF * scale_m)) ** 3)
    return top


@kernel
def _row_geometry(wind_x: float, wind_y: float, half_length: float, half_breadth: float,
                  height: float) -> tuple[float, float, float, float, float, float, float, bool]:
    """(dx, dy, half_along, half_across, scale, cavity, cavity_top, calm) of the wake in one mean wind's
    horizontal direction (module docstring)."""
    speed = np.hypot(wind_x, wind_y)
    calm = speed < CALM_MPS
    dx, dy = (1.0, 0.0) if calm else (wind_x / speed, wind_y / speed)
    ax, ay = abs(dx), abs(dy)
    half_along = half_length * ax + half_breadth * ay
    half_across = half_length * ay + half_breadth * ax
    scale = wilson_scale_length(height, 2.0 * half_across)
    cavity = cavity_length(height, 2.0 * half_across, 2.0 * half_along)
    return dx, dy, half_along, half_across, scale, cavity, height + CAVITY_TOP_R * scale, calm


@kernel
def _geometry_rows(wind: NDArray[np.float64], half_length: float, half_breadth: float,
                   height: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """:func:`_row_geometry` of every row of ``wind`` (n, 3): (d (n, 2), (n, 5) half_along ... cavity_top,
    calm (n,))."""
    n = wind.shape[0]
    d, lengths, calm = np.empty((n, 2)), np.empty((n, 5)), np.empty(n, np.bool_)
    for row in range(n):
        dx, dy, half_along, half_across, scale, cavity, cavity_top, calm[row] = _row_geometry(
            wind[row, 0], wind[row, 1], half_length, half_breadth, height)
        d[row, 0], d[row, 1] = dx, dy
        lengths[row, 0], lengths[row, 1], lengths[row, 2] = half_along, half_across, scale
        lengths[row, 3], lengths[row, 4] = cavity, cavity_top
    return d, lengths, calm


@kernel
def footprint(c: float, dx: float, dy: float, half_length: float, half_breadth: float) -> tuple[float, float]:
    """(lee, windward): the largest / smallest s of the footprint on the line at crosswind position c (within
    the footprint's crosswind extent), for the downwind direction (dx, dy). A point s d + c n (n = d turned
    90 deg left) is inside when |s dx - c dy| <= L/2 and |s dy + c dx| <= B/2: two intervals in s, centred at
    c dy/dx and -c dx/dy with half-widths (L/2)/|dx| and (B/2)/|dy|."""
    ax, ay = abs(dx), abs(dy)
    # wind along y: no limit in s from x (and vice versa)
    mid_x, half_x = (c * dy / dx, half_length / ax) if ax > 1e-12 else (0.0, np.inf)
    mid_y, half_y = (-c * dx / dy, half_breadth / ay) if ay > 1e-12 else (0.0, np.inf)
    return np.minimum(mid_x + half_x, mid_y + half_y), np.maximum(mid_x - half_x, mid_y - half_y)


@kernel
def _factor_rows(points: NDArray[np.float64], wind: NDArray[np.float64], centre_x: float, centre_y: float,
                 half_length: float, half_breadth: float, height: float, lee_deficit: float,
                 turbulence_ratio: float, extent_scale_lengths: float
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(deficit (n,), turbulence gain (n,)) at points (n, 3) in mean winds (n, 3): :meth:`ShipAirWake.factors`."""
    n = points.shape[0]
    deficit, gain = np.empty(n), np.empty(n)
    for row in range(n):
        dx, dy, half_along, half_across, r, cavity, cavity_top, calm = _row_geometry(
            wind[row, 0], wind[row, 1], half_length, half_breadth, height)
        # along-wind distances past the footprint's lee and windward boundaries at the point's crosswind
        # position (beside the footprint: at its side), from its upwind-most point; the crosswind distance
        # beyond its side; the fetch over it (at least MIN_RAMP_R R)
        rel_x, rel_y = points[row, 0] - centre_x, points[row, 1] - centre_y
        s = rel_x * dx + rel_y * dy
        c = -rel_x * dy + rel_y * dx
        across = np.minimum(np.maximum(c, -half_across), half_across)
        lee, windward = footprint(across, dx, dy, half_length, half_breadth)
        fetch = np.maximum(lee - windward, MIN_RAMP_R * r)
        x_lee, x_wind, x_up, lateral = s - lee, s - windward, s + half_along, abs(c) - half_across
        # streamwise: ramp over the roof, cavity plateau, PRIME's (x/R)^(-2/3) decay, taper over the last half
        # of the extent; the ramp ends at the lee boundary, or a little past it where the fetch is < 0.25 R
        roof = smoothstep(x_wind / fetch)
        decay = (np.maximum(x_lee - cavity, 0.0) / r + 1.0) ** -DECAY_EXPONENT
        start = cavity + 0.5 * extent_scale_lengths * r
        taper = 1.0 - smoothstep((x_lee - start) / (0.5 * extent_scale_lengths * r))
        stream = roof * decay * taper
        # lateral: PRIME's half-width growth (R/3)(x/R)^(1/3) beyond the shadow of the footprint
        width = np.maximum(r / 3.0 * np.cbrt(np.maximum(x_up, 0.0) / r), MIN_LATERAL_TAPER_R * r)
        shape = 0.0 if calm else stream * (1.0 - smoothstep(lateral / width))
        # vertical: deficit full to H, turbulence full to the cavity top, both gone at the wake height
        top = np.maximum(wake_height(x_up, height, r), cavity_top + CAVITY_TOP_R * r)
        z = points[row, 2]
        mean_part = 1.0 - smoothstep((z - height) / (top - height))
        turb_part = 1.0 - smoothstep((z - cavity_top) / (top - cavity_top))
        deficit[row] = lee_deficit * shape * mean_part
        gain[row] = 1.0 + (turbulence_ratio - 1.0) * shape * turb_part
    return deficit, gain


@dataclass(frozen=True)
class WakeGeometry:
    """Per-row wake geometry for one wind direction each; arrays (n,), lengths in m.

    d: (n, 2) unit downwind direction; half_along, half_across: the footprint's half extents along / across d;
    scale: Wilson R; cavity: Fackrell L_R; cavity_top: H_R; calm: rows without horizontal wind (no wake)."""

    d: NDArray[np.float64]
    half_along: NDArray[np.float64]
    half_across: NDArray[np.float64]
    scale: NDArray[np.float64]
    cavity: NDArray[np.float64]
    cavity_top: NDArray[np.float64]
    calm: NDArray[np.bool_]


class ShipAirWake:
    """The air wake of the hull box ``box`` ((2, 3) min / max corners, ship frame, z from the sea) in the mean
    wind; batch-first: every method takes points (n, 3) m and the mean wind at them (n, 3) m/s (or one (3,)
    wind for all), whose horizontal direction orients the wake row by row.

    lee_deficit: fraction of the mean wind removed in the recirculation cavity (D0); turbulence_ratio: the
    turbulence multiplier there (K0); extent_scale_lengths: how far past the cavity end (in R) the wake reaches.
    The sources of every number are in the module docstring."""

    def __init__(self, box: ArrayLike, lee_deficit: float = 0.7, turbulence_ratio: float = 1.7,
                 extent_scale_lengths: float = 15.0) -> None:
        box = np.asarray(box, dtype=float)
        if box.shape != (2, 3) or not np.all(box[1] > box[0]) or box[1, 2] <= 0:
            raise ValueError(f"box must be (2, 3) min/max corners with positive sizes and top > 0, got {box}")
        if lee_deficit < 0 or turbulence_ratio < 1 or not extent_scale_lengths > 0:
            raise ValueError("need lee_deficit >= 0, turbulence_ratio >= 1, extent_scale_lengths > 0")
        self.box = box
        self.centre = box[:, :2].mean(axis=0)
        self.half_length, self.half_breadth = (box[1, :2] - box[0, :2]) / 2.0
        self.height = float(box[1, 2])
        self.lee_deficit = float(lee_deficit)
        self.turbulence_ratio = float(turbulence_ratio)
        self.extent_scale_lengths = float(extent_scale_lengths)

    @classmethod
    def from_section(cls, box: ArrayLike, section: AirWakeSection) -> ShipAirWake:
        """From a ``wind.air_wake`` section (:class:`wrp_eval.wind.config.AirWakeSection`)."""
        return cls(box, section.lee_deficit, section.turbulence_ratio, section.extent_scale_lengths)

    # --- geometry -------------------------------------------------------------------------------------
    def geometry(self, mean_wind: ArrayLike) -> WakeGeometry:
        """The wake's geometry for each row of ``mean_wind`` (n, 3) m/s (only its horizontal direction counts)."""
        wind = np.atleast_2d(np.asarray(mean_wind, dtype=float))
        d, lengths, calm = _geometry_rows(wind, self.half_length, self.half_breadth, self.height)
        half_along, half_across, scale, cavity, cavity_top = lengths.T
        return WakeGeometry(d, half_along, half_across, scale, cavity, cavity_top, calm)

    # --- fields ---------------------------------------------------------------------------------------
    def factors(self, points: ArrayLike, mean_wind: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(deficit (n,), turbulence gain (n,)) at points (n, 3) m in mean winds (n, 3) m/s: one geometry for
        both (what :class:`wrp_eval.wind.field.WindField` calls once per step); one compiled loop over the rows."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        wind = np.ascontiguousarray(np.broadcast_to(np.asarray(mean_wind, dtype=float), points.shape))
        return _factor_rows(points, wind, float(self.centre[0]), float(self.centre[1]), float(self.half_length),
                            float(self.half_breadth), self.height, self.lee_deficit, self.turbulence_ratio,
                            self.extent_scale_lengths)

    def deficit(self, points: ArrayLike, mean_wind: ArrayLike) -> NDArray[np.float64]:
        """(n,) fraction of the mean wind removed at points (n, 3): ``lee_deficit`` in the cavity, 0 outside
        the wake."""
        return self.factors(points, mean_wind)[0]

    def reference_point(self, mean_wind: ArrayLike) -> NDArray[np.float64]:
        """(3,) the lee-side reference point for one mean wind (3,): on the wind line through the box centre,
        half a cavity length behind the lee face, at half the block height; there the deficit is exactly
        ``lee_deficit`` and the gain ``turbulence_ratio``."""
        geo = self.geometry(np.asarray(mean_wind, dtype=float)[None, :])
        lee, _ = footprint(0.0, geo.d[0, 0], geo.d[0, 1], float(self.half_length), float(self.half_breadth))
        s = lee + 0.5 * geo.cavity[0]
        return np.array([*(self.centre + s * geo.d[0]), 0.5 * self.height])
