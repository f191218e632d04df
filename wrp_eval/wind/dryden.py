"""Dryden turbulence, MIL-F-8785C low-altitude model, batched over flights.

Formulas (MIL-F-8785C Sec. 3.7.2.3 / MIL-HDBK-1797), h in feet, 10 <= h <= 1000:
    L_w = h,  L_u = L_v = h / (0.177 + 0.000823 h)^1.2
    sigma_w = 0.1 W20,  sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4      (W20: wind at 20 ft)
One-sided PSDs over temporal frequency omega (rad/s), each integrating over [0, inf) to sigma^2:
    Phi_u(omega) = sigma_u^2 (2 L_u / (pi V)) / (1 + (L_u omega / V)^2)
    Phi_v,w(omega) = sigma^2 (L / (pi V)) (1 + 3 (L omega / V)^2) / (1 + (L omega / V)^2)^2
Forming filters (|H(i omega)|^2 = Phi(omega) for a unit one-sided input PSD):
    H_u = K_u / (1 + tau s),                    K_u = sigma_u sqrt(2 L_u / (pi V)),  tau = L / V
    H_v,w = K (1 + sqrt(3) tau s) / (1 + tau s)^2,  K = sigma sqrt(L / (pi V))

Noise scaling (checked, see README): a unit one-sided PSD over omega in [0, pi/dt] means discrete white noise
of variance pi/dt held constant over each step (variance = integral of the PSD = 1 * pi/dt).

Exact zero-order-hold discretisation, in closed form (= scipy.signal.cont2discrete(..., "zoh"); a test checks
it), with r = dt / tau, a = exp(-r):
  first order   x' = (-x + e)/tau,             y = K x:     x+ = a x + (1 - a) e
  second order  x2' = (-x2 + e)/tau, x1' = (-x1 + x2)/tau,   y = K ((1 - sqrt3) x1 + sqrt3 x2):
                x1+ = a x1 + a r x2 + (1 - a (1 + r)) e,     x2+ = a x2 + (1 - a) e

Axes: u along the mean horizontal wind, v across it (horizontal, to the left), w vertical (up).
Airspeed V (frozen-field "Taylor" speed): the mean wind speed at the vehicle with a floor, since a hovering
multirotor has no airspeed of its own (Taylor's frozen-turbulence hypothesis needs a convection speed:
the mean wind carries the field past the vehicle).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter

from wrp_eval.compiled import as_rows, kernel
from wrp_eval.streams import BlockNormals, FlightRngs, flight_generators
from wrp_eval.wind.boundary_layer import log_law_factor

FT_M = 0.3048
KNOT_MPS = 1852.0 / 3600.0
MIN_ALTITUDE_FT, MAX_ALTITUDE_FT = 10.0, 1000.0
SQRT3: float = np.sqrt(3.0)

# MIL-F-8785C mean-wind shear: W(h) = W20 ln(h/z0)/ln(20 ft/z0) with z0 = 0.15 ft (Sec. 3.7.2.3)
MIL_SHEAR_Z0_M = 0.15 * FT_M
# W20 of the MIL-F-8785C / MIL-HDBK-1797 low-altitude severity levels (knots)
SEVERITY_W20_KT = {"light": 15.0, "moderate": 30.0, "severe": 45.0}
# a number or an array of them, for the kernels that take either (their result is the same kind)
_Real = TypeVar("_Real", float, NDArray[np.float64])


def severity_w20_mps(severity: str) -> float:
    """W20 (m/s) of a severity preset (light 15 kt, moderate 30 kt, severe 45 kt)."""
    return SEVERITY_W20_KT[severity] * KNOT_MPS


@kernel
def _intensity_and_scale(altitude_m: float, w20_mps: float) -> tuple[float, float, float, float]:
    """(sigma_uv, sigma_w, L_uv, L_w) in m/s and m at one altitude (clipped to 10..1000 ft) for W20 m/s."""
    h_ft = np.minimum(np.maximum(altitude_m / FT_M, MIN_ALTITUDE_FT), MAX_ALTITUDE_FT)
    base = 0.177 + 0.000823 * h_ft
    sigma_w = 0.1 * w20_mps
    return sigma_w / base**0.4, sigma_w, h_ft / base**1.2 * FT_M, h_ft * FT_M


@kernel
def _parameter_rows(altitude_m: NDArray[np.float64], w20_mps: NDArray[np.float64]
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(sigma (n, 3), L (n, 3)) of flat altitudes and W20s (n,)."""
    n = altitude_m.size
    sigma, length = np.empty((n, 3)), np.empty((n, 3))
    for row in range(n):
        sigma_uv, sigma_w, length_uv, length_w = _intensity_and_scale(altitude_m[row], w20_mps[row])
        sigma[row, 0], sigma[row, 1], sigma[row, 2] = sigma_uv, sigma_uv, sigma_w
        length[row, 0], length[row, 1], length[row, 2] = length_uv, length_uv, length_w
    return sigma, length


def dryden_parameters(altitude_m: ArrayLike, w20_mps: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Intensities sigma (..., 3) m/s and length scales L (..., 3) m for axes (u, v, w).

    altitude_m is clipped to the low-altitude model's range 10..1000 ft.
    """
    h, w20 = np.broadcast_arrays(np.asarray(altitude_m, dtype=float), np.asarray(w20_mps, dtype=float))
    sigma, length = _parameter_rows(np.ascontiguousarray(h).reshape(-1), np.ascontiguousarray(w20).reshape(-1))
    return sigma.reshape(h.shape + (3,)), length.reshape(h.shape + (3,))


@kernel
def _filters(altitude_m: float, w20_mps: float,
             airspeed_mps: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(tau_u, tau_v, tau_w) s and (K_u, K_v, K_w) of the forming filters at one altitude, W20 and airspeed
    (already floored): tau = L / V, K_u = sigma_u sqrt(2 L_u / (pi V)), K_v,w = sigma sqrt(L / (pi V))."""
    sigma_uv, sigma_w, length_uv, length_w = _intensity_and_scale(altitude_m, w20_mps)
    tau = (length_uv / airspeed_mps, length_uv / airspeed_mps, length_w / airspeed_mps)
    gain = (sigma_uv * np.sqrt(2.0 * length_uv / (np.pi * airspeed_mps)),
            sigma_uv * np.sqrt(1.0 * length_uv / (np.pi * airspeed_mps)),
            sigma_w * np.sqrt(1.0 * length_w / (np.pi * airspeed_mps)))
    return tau, gain


@kernel
def _filter_rows(altitude_m: NDArray[np.float64], w20_mps: NDArray[np.float64],
                 airspeed_mps: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(tau (n, 3), gain (n, 3)) for (n,) altitudes, W20s and floored airspeeds."""
    n = altitude_m.size
    tau, gain = np.empty((n, 3)), np.empty((n, 3))
    for row in range(n):
        t, g = _filters(altitude_m[row], w20_mps[row], airspeed_mps[row])
        tau[row, 0], tau[row, 1], tau[row, 2] = t
        gain[row, 0], gain[row, 1], gain[row, 2] = g
    return tau, gain


def dryden_psd(omega_rad_s: ArrayLike, sigma: ArrayLike, length: ArrayLike,
               airspeed_mps: float) -> NDArray[np.float64]:
    """One-sided analytic PSDs (len(omega), 3) in (m/s)^2 per rad/s for axes (u, v, w)."""
    om = np.asarray(omega_rad_s, dtype=float)[:, None]
    s, L = np.asarray(sigma, float)[None, :], np.asarray(length, float)[None, :]
    x2 = (L * om / airspeed_mps) ** 2
    first = s**2 * 2 * L / (np.pi * airspeed_mps) / (1 + x2)
    second = s**2 * L / (np.pi * airspeed_mps) * (1 + 3 * x2) / (1 + x2) ** 2
    return np.concatenate([first[:, :1], second[:, 1:]], axis=1)


def continuous_filters(sigma: Sequence[float], length: Sequence[float], airspeed_mps: float) -> list[
        tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]]:
    """State-space (A, B, C, D) of the three forming filters, in the realisation used here (for tests)."""
    out = []
    for axis in range(3):
        tau = length[axis] / airspeed_mps
        if axis == 0:
            gain = sigma[0] * np.sqrt(2 * length[0] / (np.pi * airspeed_mps))
            out.append((np.array([[-1 / tau]]), np.array([[1 / tau]]), np.array([[gain]]), np.zeros((1, 1))))
        else:
            gain = sigma[axis] * np.sqrt(length[axis] / (np.pi * airspeed_mps))
            a = np.array([[-1 / tau, 1 / tau], [0.0, -1 / tau]])
            out.append((a, np.array([[0.0], [1 / tau]]), gain * np.array([[1 - SQRT3, SQRT3]]), np.zeros((1, 1))))
    return out


@kernel
def _zoh(tau: _Real, dt: float) -> tuple[_Real, _Real, _Real, _Real]:
    """Closed-form ZOH coefficients (a, a r, 1 - a(1+r), 1 - a) for time constants tau (any shape)."""
    r = dt / tau
    a = np.exp(-r)
    return a, a * r, -np.expm1(-r) - r * a, -np.expm1(-r)


def _discrete_lyapunov_2x2(F: NDArray[np.float64], Q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Batched solution of P = F P F^T + Q for (..., 2, 2) matrices: vec(P) = (I - F kron F)^-1 vec(Q)."""
    kron = np.einsum("...ij,...kl->...ikjl", F, F).reshape(F.shape[:-2] + (4, 4))
    eye = np.eye(4)
    vec = np.linalg.solve(eye - kron, Q.reshape(Q.shape[:-2] + (4,))[..., None])[..., 0]
    P = vec.reshape(F.shape)
    return 0.5 * (P + np.swapaxes(P, -1, -2))


@kernel
def _second_order_output(x1: _Real, x2: _Real) -> _Real:
    """The v/w filter's output per unit gain, (1 - sqrt3) x1 + sqrt3 x2 (module docstring)."""
    return (1 - SQRT3) * x1 + SQRT3 * x2


@kernel
def _step_rows(points: NDArray[np.float64], mean_wind: NDArray[np.float64], w20_mps: NDArray[np.float64],
               airspeed_floor_m_s: float, dt: float, noise: NDArray[np.float64], state_u: NDArray[np.float64],
               state_vw: NDArray[np.float64]) -> NDArray[np.float64]:
    """Advance each flight ``noise.shape[1]`` steps (unit normals (n, m, 3)) with the filters of its altitude
    (``points`` (n, 3) m) and airspeed (the ``mean_wind`` (n, 3) m/s speed, floored), updating ``state_u`` (n,)
    and ``state_vw`` (n, 2, 2) in place; returns the turbulence (n, 3) m/s after them, world frame."""
    q_sqrt = np.sqrt(np.pi / dt)
    n = noise.shape[0]
    out, uvw = np.empty((n, 3)), np.empty(3)
    for row in range(n):
        mx, my, mz = mean_wind[row, 0], mean_wind[row, 1], mean_wind[row, 2]
        airspeed = np.maximum(np.sqrt(mx ** 2 + my ** 2 + mz ** 2), airspeed_floor_m_s)
        tau, gain = _filters(points[row, 2], w20_mps[row], airspeed)
        a, _, _, c2 = _zoh(tau[0], dt)
        for k in range(noise.shape[1]):
            state_u[row] = a * state_u[row] + c2 * (noise[row, k, 0] * q_sqrt)
        uvw[0] = gain[0] * state_u[row]
        for axis in range(2):       # v, w: second order
            a, ar, c1, c2 = _zoh(tau[1 + axis], dt)
            for k in range(noise.shape[1]):
                x1, x2 = state_vw[row, axis, 0], state_vw[row, axis, 1]
                e = noise[row, k, 1 + axis] * q_sqrt
                state_vw[row, axis, 0] = a * x1 + ar * x2 + c1 * e
                state_vw[row, axis, 1] = a * x2 + c2 * e
            uvw[1 + axis] = gain[1 + axis] * _second_order_output(state_vw[row, axis, 0], state_vw[row, axis, 1])
        out[row, 0], out[row, 1], out[row, 2] = _to_world(uvw[0], uvw[1], uvw[2], mx, my)
    return out


@kernel
def _to_world(u: float, v: float, w: float, mean_x: float, mean_y: float) -> tuple[float, float, float]:
    """(x, y, z) of along/across/vertical (u, v, w): u along the mean horizontal wind (x where calm), v 90 deg
    to its left, w up."""
    h = np.hypot(mean_x, mean_y)
    cx, cy = (1.0, 0.0) if h < 1e-9 else (mean_x / h, mean_y / h)
    return cx * u - cy * v, cy * u + cx * v, w


@kernel
def _rotate_rows(uvw: NDArray[np.float64], mean_wind: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, 3) along/across/vertical -> world frame (:func:`rotate_to_world`)."""
    out = np.empty_like(uvw)
    for row in range(uvw.shape[0]):
        out[row, 0], out[row, 1], out[row, 2] = _to_world(uvw[row, 0], uvw[row, 1], uvw[row, 2], mean_wind[row, 0],
                                                          mean_wind[row, 1])
    return out


class DrydenTurbulence:
    """Dryden turbulence for a batch of ``n_flights`` flights, each with its own random stream.

    State per flight: x_u (1), and (x1, x2) for v and for w. ``velocity`` moves all flights the steps of
    ``dt_s`` since its last call (one compiled loop); ``generate`` produces a whole series at fixed altitude and
    airspeed with scipy's C recursion (identical numbers to stepping with ``velocity``).

    rngs: one Generator per flight (e.g. ``np.random.default_rng(seed).spawn(n)``) or a single Generator /
    seed from which they are spawned. w20_mps: scalar or (n,). sigma_w_override_mps: if given, W20 is
    replaced by 10 * sigma_w (the intensity override). Noise is drawn per flight in blocks of up to
    ``block_steps`` steps (:class:`wrp_eval.streams.BlockNormals`), so the per-flight draws are independent of how
    the time axis is chunked.
    """

    def __init__(self, n_flights: int, dt_s: float, rngs: FlightRngs, w20_mps: ArrayLike = 0.0,
                 sigma_w_override_mps: float | None = None, airspeed_floor_m_s: float = 1.0,
                 block_steps: int = 1024) -> None:
        if n_flights < 1:
            raise ValueError("n_flights must be >= 1")
        if not dt_s > 0:
            raise ValueError("dt_s must be > 0")
        self.n_flights = n_flights
        self.dt_s = float(dt_s)
        self.rngs = flight_generators(rngs, n_flights)
        w20 = 10.0 * sigma_w_override_mps if sigma_w_override_mps is not None else w20_mps
        self.w20_mps = np.broadcast_to(np.asarray(w20, dtype=float), (n_flights,)).copy()
        self.airspeed_floor_m_s = float(airspeed_floor_m_s)
        self.block_steps = int(block_steps)
        self._noise = BlockNormals(self.rngs, n_flights, 3, self.block_steps)
        self.state_u: NDArray[np.float64] | None = None            # (n,)
        self.state_vw: NDArray[np.float64] | None = None           # (n, 2, 2): [axis v/w, (x1, x2)]
        self.t_s: float | None = None

    # --- parameters -------------------------------------------------------------------------------
    def parameters(self, altitude_m: ArrayLike, airspeed_mps: ArrayLike) -> tuple[
            NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """(sigma (n,3), length (n,3), V (n,), tau (n,3), gain (n,3)) for the flights' current conditions."""
        altitude = np.broadcast_to(np.asarray(altitude_m, float), (self.n_flights,))
        sigma, length = dryden_parameters(altitude, self.w20_mps)
        v = np.maximum(np.broadcast_to(np.asarray(airspeed_mps, float), (self.n_flights,)), self.airspeed_floor_m_s)
        tau, gain = _filter_rows(np.ascontiguousarray(altitude), self.w20_mps, v)
        return sigma, length, v, tau, gain

    # --- noise ---------------------------------------------------------------------------------------
    def _draw(self, n_steps: int) -> NDArray[np.float64]:
        """Unit normals (n, n_steps, 3) from each flight's own generator, in stream order."""
        return self._noise.draw(n_steps)

    def _initialise(self, tau: NDArray[np.float64]) -> None:
        """Draw each flight's state from the stationary distribution of its discrete filters."""
        q = np.pi / self.dt_s
        a, ar, c1, c2 = _zoh(tau, self.dt_s)
        z = self._draw(2)                                        # 6 normals per flight, stream order
        var_u = c2[:, 0] ** 2 * q / (1 - a[:, 0] ** 2)
        self.state_u = np.sqrt(var_u) * z[:, 0, 0]
        F = np.zeros((self.n_flights, 2, 2, 2))
        F[..., 0, 0] = a[:, 1:]
        F[..., 0, 1] = ar[:, 1:]
        F[..., 1, 1] = a[:, 1:]
        G = np.stack([c1[:, 1:], c2[:, 1:]], axis=-1)           # (n, 2, 2)
        Q = q * G[..., :, None] * G[..., None, :]
        P = _discrete_lyapunov_2x2(F, Q)
        chol = np.linalg.cholesky(P)
        normals = np.stack([z[:, 0, 1:3], z[:, 1, 0:2]], axis=1)  # (n, 2 axes, 2)
        self.state_vw = np.einsum("naij,naj->nai", chol, normals)

    def _states(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(state_u, state_vw), drawn by the first :meth:`velocity` or :meth:`generate`."""
        if self.state_u is None or self.state_vw is None:
            raise RuntimeError("the turbulence state is drawn by the first velocity() or generate() call")
        return self.state_u, self.state_vw

    # --- stepping --------------------------------------------------------------------------------------
    def output(self, gain: NDArray[np.float64]) -> NDArray[np.float64]:
        """Current turbulence (n, 3) along/across/vertical for gains (n, 3)."""
        state_u, state_vw = self._states()
        vw = _second_order_output(state_vw[..., 0], state_vw[..., 1])
        turbulence: NDArray[np.float64] = gain * np.concatenate([state_u[:, None], vw], axis=1)
        return turbulence

    def velocity(self, points: NDArray[np.float64], t: float,
                 mean_wind: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """Turbulence (n, 3) m/s in the world frame at flight positions ``points`` (n, 3) at time ``t`` s
        (non-decreasing across calls).

        mean_wind (n, 3): the mean wind at the points (sets the u axis and the airspeed V); None = calm
        (u along +x, V = the floor). The first call sets the time origin and draws the stationary initial
        state; later calls advance round((t - t_prev) / dt) steps with the current altitude and airspeed (one
        compiled loop over the flights, :mod:`wrp_eval.compiled`).
        """
        points = np.asarray(points, dtype=float)
        if points.shape != (self.n_flights, 3):
            raise ValueError(f"points must have shape ({self.n_flights}, 3), got {points.shape}")
        mean_wind = np.zeros_like(points) if mean_wind is None else as_rows("mean_wind", mean_wind, points.shape)
        if self.t_s is None:
            _, _, _, tau, _ = self.parameters(points[:, 2], np.linalg.norm(mean_wind, axis=1))
            self._initialise(tau)
            self.t_s, n_steps = float(t), 0
        else:
            n_steps = int(round((t - self.t_s) / self.dt_s))
            if n_steps < 0:
                raise ValueError(f"turbulence queried at t = {t} s after t = {self.t_s} s: time must not decrease")
        world = _step_rows(points, mean_wind, self.w20_mps, self.airspeed_floor_m_s, self.dt_s, self._draw(n_steps),
                           *self._states())
        self.t_s += n_steps * self.dt_s
        return world

    # --- whole series ----------------------------------------------------------------------------------
    def generate(self, n_steps: int, altitude_m: float, airspeed_mps: float) -> NDArray[np.float64]:
        """Series (n_flights, n_steps, 3) along/across/vertical at fixed altitude and airspeed.

        Sample k is the turbulence at t0 + k dt (k = 0 is the current, or freshly drawn initial, state);
        afterwards the state is at t0 + n_steps dt, exactly as after n_steps steps of ``velocity``.
        """
        _, _, _, tau, gain = self.parameters(altitude_m, airspeed_mps)
        if self.t_s is None:
            self._initialise(tau)
            self.t_s = 0.0
        state_u, state_vw = self._states()
        tau0 = tau[0]
        if not np.allclose(tau, tau0):
            raise ValueError("generate() needs the same altitude and airspeed for every flight")
        a, ar, c1, c2 = _zoh(tau0, self.dt_s)
        e = self._draw(n_steps) * np.sqrt(np.pi / self.dt_s)    # (n, T, 3)
        out = np.empty((self.n_flights, n_steps, 3))
        # x_{k+1} = a x_k + c e_k as an IIR filter along time (scipy's C loop); zi carries x_0
        xu_next, _ = lfilter([c2[0]], [1.0, -a[0]], e[:, :, 0], axis=1, zi=(a[0] * state_u)[:, None])
        xu = np.concatenate([state_u[:, None], xu_next[:, :-1]], axis=1)
        out[..., 0] = gain[:, 0:1] * xu
        self.state_u = xu_next[:, -1]
        new_vw = np.empty_like(state_vw)
        for ax in (1, 2):
            x1_0, x2_0 = state_vw[:, ax - 1, 0], state_vw[:, ax - 1, 1]
            x2_next, _ = lfilter([c2[ax]], [1.0, -a[ax]], e[:, :, ax], axis=1, zi=(a[ax] * x2_0)[:, None])
            x2 = np.concatenate([x2_0[:, None], x2_next[:, :-1]], axis=1)
            drive = ar[ax] * x2 + c1[ax] * e[:, :, ax]
            x1_next, _ = lfilter([1.0], [1.0, -a[ax]], drive, axis=1, zi=(a[ax] * x1_0)[:, None])
            x1 = np.concatenate([x1_0[:, None], x1_next[:, :-1]], axis=1)
            out[..., ax] = gain[:, ax:ax + 1] * _second_order_output(x1, x2)
            new_vw[:, ax - 1] = np.stack([x1_next[:, -1], x2_next[:, -1]], axis=-1)
        self.state_vw = new_vw
        self.t_s += n_steps * self.dt_s
        return out


def rotate_to_world(uvw: ArrayLike, mean_wind: ArrayLike) -> NDArray[np.float64]:
    """(n, 3) along/across/vertical -> world frame: u along the mean horizontal wind (x where calm),
    v 90 deg to its left, w up."""
    return _rotate_rows(np.asarray(uvw, dtype=float), np.asarray(mean_wind, dtype=float))


def turbulence_series(altitude_m: float, w20_mps: float, dt_s: float, duration_s: float, seed: int,
                      airspeed_mps: float | None = None, airspeed_floor_m_s: float = 2.0) -> dict[str, Any]:
    """One Dryden series at fixed altitude (m) for W20 (m/s), time step and duration (s), seed: t (n,) s,
    uvw (n, 3) m/s along/across/vertical, sigma_uvw (3,) m/s, length_uvw (3,) m, airspeed (m/s). Default
    airspeed: the MIL-F-8785C mean wind at that altitude, W20 ln(h/z0)/ln(20 ft/z0) with z0 = 0.15 ft
    (h >= 10 ft), floored at ``airspeed_floor_m_s`` (hover)."""
    if airspeed_mps is None:
        shear = float(log_law_factor(max(altitude_m, 10 * FT_M), MIL_SHEAR_Z0_M, 20 * FT_M))
        airspeed_mps = w20_mps * shear
    airspeed = max(airspeed_mps, airspeed_floor_m_s)
    n_steps = int(round(duration_s / dt_s))
    turb = DrydenTurbulence(1, dt_s, np.random.default_rng(seed).spawn(1), w20_mps,
                            airspeed_floor_m_s=airspeed_floor_m_s)
    uvw = turb.generate(n_steps, altitude_m, airspeed)[0]
    sigma, length = dryden_parameters(altitude_m, w20_mps)
    return {"t": dt_s * np.arange(n_steps), "uvw": uvw, "sigma_uvw": sigma, "length_uvw": length,
            "airspeed": np.float64(airspeed)}
