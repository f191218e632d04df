"""Ship motion in a seaway: heave, roll, pitch and yaw of each flight's ship, batch-first.

The ship stage's ``ship.motion`` section. By default (``sea_state: from_wind``) each flight's ship swings in
the fully developed sea of that flight's own mean wind: the default experiment's 6 m/s is not a calm sea
(Pierson-Moskowitz Hs 0.87 m, WMO code 3). ``sea_state: 0`` (or None) is the ship at anchor in a calm sea, as
in the paper's static-ship experiments (experiments/paper/ set it).

```yaml
ship:
  motion:
    sea_state: 4                       # WMO code 0..6 (0 / None = no motion), or from_wind (the default)
    components: 1                      # sinusoids per degree of freedom (1 = the published table as is)
    relative_bandwidth: 0.2            # spread of the component frequencies when components > 1
    amplitude_scale: [1, 1, 1, 1]      # heave, roll, pitch, yaw multipliers of the carrier figures
```

Model (a published sinusoid table). Each degree of freedom d of flight i is a sum of K sinusoids

    q_d(t) = sum_k a_dk sin(w_dk t + phi_idk),   a_dk = A_d / sqrt(K),

with A_d and the centre frequency w_d of the sea state's row of :data:`SEA_STATE_TABLE`, the phases phi drawn
uniformly in [0, 2 pi) from flight i's own Generator and, for K > 1, the frequencies w_dk = w_d (1 + b u_k),
u_k uniform in [-1/2, 1/2] (a random-phase, equal-amplitude multi-sine: the spectral representation of
Shinozuka & Deodatis 1991, Appl. Mech. Rev. 44(4), 191-204). The table's figure A_d is the amplitude of the
sinusoid (K = 1: q oscillates between -A and +A); for every K it is sqrt(2) x the RMS of q over a long
window (sum_k a_dk^2 / 2 = A_d^2 / 2), the statistic :meth:`ShipMotion.amplitudes` returns and the tests check.

Sources of the figures (see :data:`SEA_STATE_TABLE`): sea states 4-6 are Table 2 of Ke Lu & Chunsheng Liu,
"A L1 adaptive control scheme for UAV carrier landing using nonlinear dynamic inversion", Int. J. Aerospace
Eng. 2019, 6917393 (https://doi.org/10.1155/2019/6917393), deck motion of a large aircraft carrier.

Frames and signs: the ship frame is x to the bow, y to port, z up, origin at the ship's centre on the
waterline; the world frame is earth-fixed and coincides with the ship frame at rest. Heave is positive up;
roll, pitch and yaw are right-handed rotations about the ship's x, y and z axes (roll + = starboard side
down, pitch + = bow down, yaw + = bow to port). The body-to-world rotation is R = Rz(yaw) Ry(pitch) Rx(roll)
(intrinsic z-y'-x'', the usual ship / aircraft order, Fossen 2011, Handbook of Marine Craft Hydrodynamics,
eq. 2.18) about the origin, and p_world = R p_ship + (0, 0, heave).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from wrp_eval.schema import StrictModel
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.streams import flight_generators

MAX_SEA_STATE = 6
DOF_NAMES = ("heave", "roll", "pitch", "yaw")   # the column order of every (..., 4) array here
_FT = 0.3048                                    # m per international foot

# Lu & Liu 2019, Table 2 (carrier, sinusoidal perturbations): amplitude and frequency (rad/s) per sea state.
# heave ft, roll deg, pitch deg; frequencies heave 0.3491, roll 0.2856, pitch 0.5236, surge/sway 0.3307 rad/s.
_CARRIER_ROWS = {
    4: (2.2274 * _FT, 0.6223, 0.5162),
    5: (3.5638 * _FT, 0.9829, 0.8202),
    6: (5.3528 * _FT, 1.4425, 1.2374),
}
_CARRIER_FREQ_RAD_S = (0.3491, 0.2856, 0.5236)
# WMO sea-state code: upper bound of the significant wave height (m) per code (Tupper, Introduction to Naval
# Architecture, Table 5.4). The table's rows 4-6 grow nearly as these bounds do (2.5 : 4 : 6 = 1 : 1.6 : 2.4;
# heave 1 : 1.600 : 2.403, pitch 1 : 1.589 : 2.397, roll 1 : 1.579 : 2.318), so rows 1-3 are row 4 scaled by
# the bound (linear response: motion proportional to wave height), our extrapolation.
WMO_HS_UPPER_M = {0: 0.0, 1: 0.1, 2: 0.5, 3: 1.25, 4: 2.5, 5: 4.0, 6: 6.0}
# Yaw is not in the table: ASSUMED half the pitch amplitude, at the table's horizontal-plane (surge / sway)
# frequency 0.3307 rad/s. No published per-sea-state yaw figure was found.
YAW_TO_PITCH = 0.5
YAW_FREQ_RAD_S = 0.3307


def _table() -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """{sea state: (amplitudes (4,) [m, rad, rad, rad], frequencies (4,) rad/s)} for codes 0..6."""
    freqs = np.array([*_CARRIER_FREQ_RAD_S, YAW_FREQ_RAD_S])
    out = {}
    for ss in range(MAX_SEA_STATE + 1):
        src = ss if ss in _CARRIER_ROWS else 4
        heave_m, roll_deg, pitch_deg = _CARRIER_ROWS[src]
        scale = 1.0 if ss in _CARRIER_ROWS else WMO_HS_UPPER_M[ss] / WMO_HS_UPPER_M[4]
        amps = np.array([heave_m, np.radians(roll_deg), np.radians(pitch_deg),
                         YAW_TO_PITCH * np.radians(pitch_deg)]) * scale
        out[ss] = (amps, freqs.copy())
    return out


SEA_STATE_TABLE = _table()


# Fully developed sea of a wind (Pierson & Moskowitz 1964, J. Geophys. Res. 69(24): the PM spectrum's
# significant wave height Hs = 0.21 U^2 / g, U the wind at 19.5 m above the sea); U19.5 = 1.06 U10 by the
# marine log law (Charnock roughness ~0.2 mm: ln(19.5/z0)/ln(10/z0) = 1.06).
PM_HS_COEFF = 0.21
U195_PER_U10 = 1.06
GRAVITY_M_S2 = 9.81


def wind_wave_height_m(speed_10m_m_s) -> np.ndarray:
    """Significant wave height (n,) m of the fully developed sea under a wind of ``speed_10m_m_s`` (n,) m/s at
    10 m, capped at the table's largest sea state (6: 6 m)."""
    u = U195_PER_U10 * np.asarray(speed_10m_m_s, dtype=float)
    return np.minimum(PM_HS_COEFF * u ** 2 / GRAVITY_M_S2, WMO_HS_UPPER_M[MAX_SEA_STATE])


def wmo_sea_state(wave_height_m) -> np.ndarray:
    """The WMO sea-state code (n,) int of significant wave heights (n,) m (code c covers Hs up to its bound)."""
    bounds = np.array([WMO_HS_UPPER_M[c] for c in range(MAX_SEA_STATE + 1)])
    return np.minimum(np.searchsorted(bounds, np.asarray(wave_height_m, dtype=float), side="left"), MAX_SEA_STATE)


def sea_state_figures(sea_state: int) -> tuple[np.ndarray, np.ndarray]:
    """(amplitudes (4,), frequencies (4,)) of a WMO sea state 0..6: heave m, roll / pitch / yaw rad; rad/s.
    The amplitude is the sinusoid's (sqrt(2) x RMS). Sea state 0 has zero amplitudes."""
    if sea_state not in SEA_STATE_TABLE:
        raise ValueError(f"sea_state must be an integer 0..{MAX_SEA_STATE}, got {sea_state!r}")
    amps, freqs = SEA_STATE_TABLE[sea_state]
    return amps.copy(), freqs.copy()


_Scale = Annotated[float, Field(ge=0, le=100, allow_inf_nan=False)]


class ShipMotionSection(StrictModel):
    """Ship motion in a seaway (``ship.motion``): by default the sea its wind raises; off with ``sea_state`` 0."""

    sea_state: Annotated[int, Field(ge=0, le=MAX_SEA_STATE)] | Literal["from_wind"] | None = Field(
        "from_wind", description="from_wind (the default): each flight's fully developed sea under its own mean "
        "wind (Pierson-Moskowitz Hs = 0.21 U19.5^2 / g), the motion scaled from the sea-state-4 row by Hs / 2.5 m; "
        "or a WMO sea-state code 0..6; None or 0 = the ship at anchor in a calm sea (no motion)")
    components: int = Field(1, ge=1, le=64, description="sinusoids per degree of freedom: 1 = the published "
                            "table's single sinusoid, more = a narrow-band random process of the same RMS")
    relative_bandwidth: float = Field(0.2, ge=0, lt=1, description="components > 1: the component frequencies "
                                      "are drawn uniformly in w (1 +- bandwidth / 2) (assumed 0.2)",
                                      allow_inf_nan=False)
    amplitude_scale: tuple[_Scale, _Scale, _Scale, _Scale] = Field(
        (1.0, 1.0, 1.0, 1.0), description="heave, roll, pitch, yaw multipliers of the carrier figures (a smaller "
        "ship moves more; no published scaling is applied by default)")

    @property
    def enabled(self) -> bool:
        """True when the ship moves (sea state 1..6, or from the wind)."""
        return bool(self.sea_state)


def _euler_zyx(roll, pitch, yaw) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll), (..., 3, 3), from (...) angles in rad."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rows = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


@dataclass(frozen=True)
class ShipMotion:
    """The motion of n flights' ships: per flight, degree of freedom and component, (n, 4, K) arrays.

    amplitude (m or rad), frequency_rad_s and phase_rad of every sinusoid; ``sea_state`` (n,) int: each
    flight's WMO code.
    Build with :func:`ship_motion`. Times are seconds from the flight's start (t = 0).
    """

    sea_state: np.ndarray
    amplitude: np.ndarray
    frequency_rad_s: np.ndarray
    phase_rad: np.ndarray

    @property
    def n_flights(self) -> int:
        return self.amplitude.shape[0]

    def _times(self, t_s) -> np.ndarray:
        """t as (n, ...) : a scalar is every flight's time, else the leading axis is the flight."""
        t = np.asarray(t_s, dtype=float)
        if t.ndim == 0:
            t = np.full(self.n_flights, float(t))
        if t.shape[0] != self.n_flights:
            raise ValueError(f"t_s has {t.shape[0]} rows for {self.n_flights} flights")
        return t

    def dof(self, t_s) -> np.ndarray:
        """(heave m, roll, pitch, yaw rad) at t_s: scalar or (n,) -> (n, 4); (n, m) -> (n, m, 4)."""
        t = self._times(t_s)
        extra = (1,) * (t.ndim - 1)
        shape = (self.n_flights, *extra, 4, -1)
        amp, w, phi = (a.reshape(shape) for a in (self.amplitude, self.frequency_rad_s, self.phase_rad))
        return np.sum(amp * np.sin(w * t[..., None, None] + phi), axis=-1)

    def flights(self, rows: np.ndarray) -> ShipMotion:
        """The motion of flights ``rows`` (m,) int alone (their own sinusoids)."""
        return ShipMotion(self.sea_state[rows], self.amplitude[rows], self.frequency_rad_s[rows], self.phase_rad[rows])

    def amplitudes(self) -> np.ndarray:
        """(n, 4) nominal amplitude of each flight's motion: sqrt(sum_k a_k^2) = sqrt(2) x RMS over a long
        window; for one component the sinusoid's amplitude, i.e. the table's figure (heave m, angles rad)."""
        return np.sqrt(np.sum(self.amplitude ** 2, axis=-1))

    def frequencies(self) -> np.ndarray:
        """(n, 4) mean angular frequency sqrt(sum a_k^2 w_k^2 / sum a_k^2) (rad/s): the one that sets the mean
        zero-up-crossing rate w / (2 pi) (Rice 1944); for one component the table's frequency."""
        a2 = self.amplitude ** 2
        return np.sqrt(np.sum(a2 * self.frequency_rad_s ** 2, axis=-1) / np.maximum(np.sum(a2, axis=-1), 1e-300))

    def pose(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Ship body -> world at t_s (scalar or (n,)): (translation (n, 3), rotation (n, 3, 3)) with
        p_world = rotation @ p_ship + translation (rotation Rz(yaw) Ry(pitch) Rx(roll), heave along world z)."""
        q = self.dof(t_s)
        if q.ndim != 2:
            raise ValueError("pose takes a scalar time or one time per flight, (n,)")
        translation = np.zeros((self.n_flights, 3))
        translation[:, 2] = q[:, 0]
        return translation, _euler_zyx(q[:, 1], q[:, 2], q[:, 3])

    def to_ship_frame(self, t_s, points, rotations) -> tuple[np.ndarray, np.ndarray]:
        """World poses at t_s (n,) - points (n, 3) and rotations (n, 3, 3) (e.g. world-from-camera) - in the
        ship's frame at those instants: p_ship = R^T (p_world - t), R_ship = R^T R_world."""
        translation, rot = self.pose(t_s)
        rot_t = np.swapaxes(rot, -1, -2)
        pts = np.einsum("nij,nj->ni", rot_t, np.asarray(points, float) - translation)
        return pts, rot_t @ np.asarray(rotations, float)

    def to_world_frame(self, t_s, points, rotations) -> tuple[np.ndarray, np.ndarray]:
        """The inverse of :meth:`to_ship_frame`: ship-frame poses (n, 3), (n, 3, 3) in the world at t_s (n,)."""
        translation, rot = self.pose(t_s)
        return np.einsum("nij,nj->ni", rot, np.asarray(points, float)) + translation, rot @ np.asarray(rotations,
                                                                                                         float)


def ship_motion(section: ShipMotionSection, particulars: ShipParticulars | None, rngs,
                n_flights: int, wind_speed_10m_m_s=None) -> ShipMotion | None:
    """The motion of ``n_flights`` ships in ``section``'s sea state, or None when it is off (sea state None / 0).

    particulars: the ship (unused by the carrier table, which is not ship-specific; kept so that a
    ship-dependent model can replace it). rngs: as :func:`wrp_eval.streams.flight_generators`; flight i draws
    from its own Generator, in this order, its phases (4, K) and, for K > 1, its frequency offsets (4, K), so its
    motion does not depend on the batch it is in. wind_speed_10m_m_s: scalar or (n_flights,) m/s, each flight's
    mean wind (needed by ``sea_state: from_wind``; a flight in a calm wind gets a still ship).
    """
    del particulars
    if not section.enabled or section.sea_state is None:
        return None
    if n_flights < 1:
        raise ValueError("n_flights must be >= 1")
    k = section.components
    if section.sea_state == "from_wind":
        if wind_speed_10m_m_s is None:
            raise ValueError("ship.motion.sea_state from_wind needs each flight's wind speed")
        row4, freqs = sea_state_figures(4)
        hs = np.broadcast_to(wind_wave_height_m(wind_speed_10m_m_s), (n_flights,))
        amps = hs[:, None] / WMO_HS_UPPER_M[4] * row4[None, :]        # (n, 4): linear response, as rows 1-3
        sea_state = wmo_sea_state(hs)
    else:
        amps, freqs = sea_state_figures(section.sea_state)
        sea_state = np.full(n_flights, section.sea_state)
    amps = amps * np.asarray(section.amplitude_scale)
    gens = flight_generators(rngs, n_flights)
    phases = np.stack([g.uniform(0.0, 2.0 * np.pi, (4, k)) for g in gens])
    if k > 1:
        offsets = np.stack([g.uniform(-0.5, 0.5, (4, k)) for g in gens])
    else:
        offsets = np.zeros((n_flights, 4, 1))
    frequency = freqs[None, :, None] * (1.0 + section.relative_bandwidth * offsets)
    amplitude = np.broadcast_to(np.reshape(amps, (-1, 4))[:, :, None] / np.sqrt(k), (n_flights, 4, k)).copy()
    for array in (amplitude, frequency, phases):
        array.flags.writeable = False
    return ShipMotion(sea_state, amplitude, frequency, phases)
