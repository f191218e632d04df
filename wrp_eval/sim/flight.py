"""Batched closed-loop flights of a :class:`FlightPath` in MuJoCo.

Design (measured, see README.md and bench.py): the batch of flights is packed ``drones_per_model``
quadrotors to a MuJoCo model (independent free bodies, no contacts), the models run in parallel in
``mujoco.rollout`` threads for a chunk of ``chunk_steps`` physics steps, and between chunks the
flight logic computes for the whole batch at once (compiled per-row kernels, wrp_eval/compiled.py):
the wind at every vehicle, the windward-area drag, the reference (jerk-limited speed profile viewpoint
to viewpoint), the position loop of the SE(3) controller, photo
triggers and failures. Motor thrusts, drag forces (world-frame force actuators on the free joint) and
the desired attitudes enter the rollout through ``control_spec = CTRL | MOCAP_QUAT`` and are held over
the chunk (zero-order hold, 50 ms by default: the position loop runs at 20 Hz); the attitude loop runs
inside MuJoCo at every physics step (200 Hz, vehicle.build_scene), so the loop between chunks can run at
the slower rate a position loop needs.

Flight logic (phases.py): in ``stop`` mode, per viewpoint TRANSIT along the straight segment at the cruise
speed (accel-limited), then SETTLE until within the tolerances (or a timeout: a waypoint mission in gusts takes
the photo anyway), then DWELL, then the photo; in ``fly-through`` mode (capture_mode.py) the reference runs
through the viewpoints and each photo is triggered when the estimated position passes its viewpoint. The
controller flies on the navigation estimate; photos are taken at the true state, through the gimbal, with
their blur, in the ship's frame at the shutter (onboard.py). A real autopilot keeps trying against the wind
(the reference waits on a leash); it turns home on its battery reserve or its wind limit (the views not
reached are not taken, the flight is not failed); a flight below the sea surface, with a non-finite state or
not finished after ``max_flight_time_s`` has failed (reason recorded).

Structure: :class:`wrp_eval.sim.flight_state.FlightState` holds what the flight logic carries between chunks
(batch-first arrays), :mod:`wrp_eval.sim.phases` the per-chunk steps on it (reference, failures, phase
transitions and photo trigger, position loop); this module owns the MuJoCo side (models, rollout buffers,
threads) and the loop that calls those steps around ``mujoco.rollout``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from functools import partial
from typing import Any, NamedTuple

import mujoco
import numpy as np
from dm_control import mjcf
from mujoco import rollout as mj_rollout
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation
from threadpoolctl import threadpool_limits

from wrp_eval.compiled import kernel
from wrp_eval.planning.path import FlightPath
from wrp_eval.sim.aero import drag_force
from wrp_eval.sim.capture_mode import shutter_offset, trigger_planes, vertex_speeds
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.controller import (
    GAIN_PRESETS,
    PositionController,
    quat_row_to_matrix,
    tilt_of,
    yaw_of,
)
from wrp_eval.sim.flight_state import (
    AWAY,
    COMPLETED,
    ENDED,
    LOST_OUTSIDE,
    RETURNED_BATTERY,
    FlightState,
    FlightTargets,
    Shot,
    TrajectoryLog,
)
from wrp_eval.sim.navigation import NavigationEstimate
from wrp_eval.sim.onboard import Onboard, ShipInScene, view_depths
from wrp_eval.sim.phases import (
    YAW_RATE_REF_RAD_S,
    Profile,
    Reference,
    advance,
    apply_endings,
    apply_transitions,
    check_failures,
    check_returns,
    control,
    no_headway,
    outcome_reasons,
    parked_pose,
    passing_views,
    reference,
    resume,
    setpoints,
    swap_batteries,
    take_photos,
    tick,
    transitions,
)
from wrp_eval.sim.results import FlightResult
from wrp_eval.sim.vehicle import PHANTOM4, QuadrotorParams, Scene, build_scene
from wrp_eval.streams import FlightRngs
from wrp_eval.wind.base import WindModel

# BLAS runs on one thread while a batch flies: OpenBLAS keeps the threads of a call it ran threaded busy-waiting for
# ~0.1 s after it returns (measured: 0.107 s of CPU burnt in a 0.3 s sleep after the navigation filter's
# solve_discrete_are), and that spinner takes a core from mujoco.rollout's threads (README.md, session 26). A
# flight's matrices are 2 x 2 to 6 x 6: BLAS threads cannot speed them up. threadpoolctl sets the loaded libraries'
# thread counts process-wide and restores them on exit (so fly() is not for several threads at once), and it cannot
# stop threads a threaded call made before fly() left spinning.
_BLAS_LIMIT = {"limits": 1, "user_api": "blas"}

# Onboard.shoot with the chunk's state bound: (rows, views, delay_s) -> the photos of those rows
_Shoot = Callable[[np.ndarray, np.ndarray, np.ndarray], Shot | None]


def _profile_and_dwell(path: FlightPath, stops: NDArray[np.bool_],
                       sec: SimSection) -> tuple[Profile, NDArray[np.float64]]:
    """The reference profile ``path`` is flown on under ``sec`` (fly-through unless every view ``stops`` (n_views,)
    bool) and the hover before each photo (n_views,) s: the dwell at its stop views, 0 elsewhere (in fly-through
    the first and last views are photographed on arrival)."""
    dwell: NDArray[np.float64] = np.where(stops, path.dwell_s if sec.dwell_s is None else sec.dwell_s, 0.0)
    return Profile.of(path.speed_m_s, sec, through=not stops.all()), dwell


def _mocap_id(model: mujoco.MjModel, name: str) -> int | None:
    """The mocap index of body ``name``, or None (no such body, or not a mocap body)."""
    try:
        mocap = int(model.body_mocapid[model.body(name).id])
    except KeyError:
        return None
    return mocap if mocap >= 0 else None


def _wind_at(wind: WindModel, points: NDArray[np.float64], t: float, batch: int) -> NDArray[np.float64]:
    """(batch, 3) wind from ``wind.velocity(points, t)``, shape-checked."""
    out = np.asarray(wind.velocity(points, t), dtype=float)
    if out.shape != (batch, 3):
        raise ValueError(f"wind model returned shape {out.shape} for {batch} flights, expected ({batch}, 3)")
    return out


def _inside_field(wind: WindModel, points: np.ndarray) -> np.ndarray:
    """(n,) bool: ``points`` (n, 3) m inside the wind model's domain (its optional ``inside(points)``; a model
    without one is everywhere)."""
    inside = getattr(wind, "inside", None)
    return np.ones(len(points), dtype=bool) if inside is None else np.asarray(inside(points), dtype=bool)


def _pad(rows: np.ndarray, padded: int) -> np.ndarray:
    """``rows`` (batch, ...) followed by zero (False) rows up to ``padded`` (``rows`` itself when full)."""
    if len(rows) == padded:
        return rows
    return np.concatenate([rows, np.zeros((padded - len(rows),) + rows.shape[1:], dtype=rows.dtype)])


def _pad_with(rows: np.ndarray, padded_rows: np.ndarray) -> np.ndarray:
    """``rows`` (batch, ...) followed by the rows of ``padded_rows`` (padded, ...) beyond them (``rows`` itself
    when the batch fills its models)."""
    if len(rows) == len(padded_rows):
        return rows
    return np.concatenate([rows, padded_rows[len(rows):]])


def _start_poses(targets: FlightTargets, padded: int, position: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Free-joint poses (padded, 7): each flight hovering level at ``position`` (batch, 3) m with heading
    ``yaw`` (batch,) rad; the fillers of the last model 50 m above the first flight's target (out of
    everyone's way)."""
    batch = targets.batch
    start = np.zeros((padded, 7))
    start[:, 3] = 1.0
    start[:batch, :3] = position
    start[batch:, :3] = targets.body[0, 0] + np.array([0.0, 0.0, 50.0])
    start[:batch, 3] = np.cos(yaw / 2)
    start[:batch, 6] = np.sin(yaw / 2)
    return start


@kernel
def _body_rows(state: NDArray[np.float64], qpos_flat: NDArray[np.intp], qvel_flat: NDArray[np.intp],
               ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(position (n, 3), velocity (n, 3), rot (n, 3, 3), yaw (n,)) of the drones whose free joints sit at flat
    indices ``qpos_flat`` (n, 7) and ``qvel_flat`` (n, 6) of the rollout ``state``."""
    n = qpos_flat.shape[0]
    position, velocity, rot = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3, 3))
    quat = np.empty(4)
    for row in range(n):
        for d in range(3):
            position[row, d] = state[qpos_flat[row, d]]
            velocity[row, d] = state[qvel_flat[row, d]]
        for d in range(4):
            quat[d] = state[qpos_flat[row, 3 + d]]
        quat_row_to_matrix(quat, rot[row])
    return position, velocity, rot, yaw_of(rot)


def _mission_horizon(sec: SimSection, dt: float) -> tuple[float, int]:
    """(the cap on a flight's time away between sorties s, the loop's last chunk): the simulator's guard, every
    sortie within ``max_flight_time_s`` and every time away within its cap."""
    m = sec.mission
    away_cap_s = m.swap_time_s + 2.0 * sec.max_flight_time_s
    return away_cap_s, int(np.ceil((m.max_sorties * sec.max_flight_time_s + (m.max_sorties - 1) * away_cap_s) / dt))


def _next_sorties(state: FlightState, targets: FlightTargets, onboard: Onboard, position: np.ndarray,
                  nav: NavigationEstimate, t: float, profile: Profile) -> None:
    """The flights due back at ``t`` s start their next sortie: a fresh battery, from the breakpoint (their true
    ``position`` (batch, 3) m; the reference from the navigation's ``nav``)."""
    back = np.flatnonzero(state.resume_at <= t + 1e-9)
    onboard.fresh_battery(back, position[back])
    resume(state, targets, back, nav.position[back], nav.yaw[back], t, profile)


def _predicted_points(wind: WindModel, position: np.ndarray, velocity: np.ndarray, dt: float, inside: np.ndarray,
                      home: np.ndarray) -> np.ndarray:
    """(batch, 3) m where the next chunk's wind is sampled ahead of time: p + v dt (the vehicle moves < 0.5 m per
    chunk, the prediction is off by 0.5 a dt^2 < 1 cm, and the wind field varies over metres); a prediction
    outside the field falls back to where the vehicle is now (``inside`` (batch,) bool), else home (the flight
    has ended)."""
    ahead = position + velocity * dt
    return np.where(_inside_field(wind, ahead)[:, None], ahead, np.where(inside[:, None], position, home))


class Body(NamedTuple):
    """Vehicles of the padded batch at the start of a chunk: position, velocity (padded, 3) m, m/s world;
    rot (padded, 3, 3) world from body; yaw (padded,) rad (Z-Y-X heading)."""

    position: np.ndarray
    velocity: np.ndarray
    rot: np.ndarray
    yaw: np.ndarray


@dataclass
class _Batch:
    """The MuJoCo side of one batch of flights: ``padded`` drones (the ``batch`` flights, then fillers)
    in ``n_models`` models. state (n_models, nstate): the rollout state; qpos_flat (padded, 7), qvel_flat
    (padded, 6), motor_flat (padded, 4), drag_flat (padded, 3), mocap_flat (padded, 4): each drone's flat
    indices into the state and into control_vec (n_models, ncontrol); controls (n_models, chunk_steps,
    ncontrol) and out (n_models, chunk_steps, nstate): the rollout's buffers; park (padded, 7) the start
    poses, where failed flights are held level."""

    batch: int
    padded: int
    qpos_flat: np.ndarray
    qvel_flat: np.ndarray
    motor_flat: np.ndarray
    drag_flat: np.ndarray
    mocap_flat: np.ndarray
    state: np.ndarray
    control_vec: np.ndarray
    controls: np.ndarray
    out: np.ndarray
    park: np.ndarray
    models: list[mujoco.MjModel]
    task_size: int

    def body(self) -> Body:
        """The drones' state as the last rollout left it."""
        return Body(*_body_rows(self.state.reshape(-1), self.qpos_flat, self.qvel_flat))

    def hold(self, drones: np.ndarray, qpos: np.ndarray) -> None:
        """Put ``drones`` (padded,) bool at ``qpos`` (n, 7), at rest."""
        flat = self.state.reshape(-1)
        flat[self.qpos_flat[drones]] = qpos
        flat[self.qvel_flat[drones]] = 0.0

    def set_controls(self, motors: np.ndarray, drag: np.ndarray, quat: np.ndarray) -> None:
        """Hold motor thrusts (padded, 4) N, drag (padded, 3) N and attitude targets (padded, 4) over the
        chunk (skip_checks rollout: no singleton expansion, so they are tiled over its steps)."""
        flat = self.control_vec.reshape(-1)
        flat[self.motor_flat] = motors
        flat[self.drag_flat] = drag
        flat[self.mocap_flat] = quat
        self.controls[:] = self.control_vec[:, None, :]


class FlightSimulator:
    """Owns the compiled scene, the rollout thread pool and the controller settings.

    ``scene_root``: optional PyMJCF root (e.g. the ship scene) the drones are attached to.
    """

    def __init__(self, section: SimSection = SimSection(), params: QuadrotorParams = PHANTOM4,
                 scene_root: mjcf.RootElement | None = None) -> None:
        self.section = section
        self.params = params
        self.gains = GAIN_PRESETS[section.gains]
        g = self.gains
        self.scene: Scene = build_scene(
            section.drones_per_model, params, section.timestep_s, root=scene_root,
            attitude_bandwidth_rad_s=(g.attitude_bandwidth_rad_s, g.attitude_bandwidth_rad_s,
                                      g.yaw_bandwidth_rad_s), attitude_damping=g.attitude_damping)
        model = self.scene.model
        self.nstate = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        # a scene with a moving ship (ship.scene.build_scene(..., moving=True)): its mocap pose is a control too
        self.ship_mocap = _mocap_id(model, "ship")
        spec = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_MOCAP_QUAT
        if self.ship_mocap is not None:
            spec |= mujoco.mjtState.mjSTATE_MOCAP_POS
        self.control_spec = int(spec)
        self.ncontrol = mujoco.mj_stateSize(model, self.control_spec)
        self.nthread = section.threads or (os.cpu_count() or 1)
        self._pool = mj_rollout.Rollout(nthread=self.nthread)
        # one Python thread that calls the rollout while the main thread samples the next chunk's wind
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="wrp-sim-rollout")
        self._datas = [mujoco.MjData(model) for _ in range(max(1, self.nthread))]
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        self._initial_state = np.zeros(self.nstate)
        mujoco.mj_getState(model, data, self._initial_state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        self._initial_control = np.zeros(self.ncontrol)      # the mocap bodies' own poses where not set
        mujoco.mj_getState(model, data, self._initial_control, self.control_spec)

    def close(self) -> None:
        self._worker.shutdown(wait=True)
        self._pool.close()

    def __enter__(self) -> FlightSimulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- layout of a batch in the rollout arrays ------------------------------------------------------
    def _layout(self, batch: int) -> tuple[int, int, NDArray[np.intp], NDArray[np.intp], NDArray[np.intp],
                                           NDArray[np.intp], NDArray[np.intp]]:
        d = self.section.drones_per_model
        n_models = -(-batch // d)
        padded = n_models * d
        flight = np.arange(padded)
        model_of, drone_of = flight // d, flight % d
        sc = self.scene
        # state = [time, qpos, qvel, ...]: flat indices into the (n_models, nstate) array
        qpos_flat = model_of[:, None] * self.nstate + 1 + sc.qpos_index[drone_of]
        qvel_flat = model_of[:, None] * self.nstate + 1 + self.scene.model.nq + sc.qvel_index[drone_of]
        nu = self.scene.model.nu
        motor_flat = model_of[:, None] * self.ncontrol + sc.actuator_index[drone_of]
        drag_flat = model_of[:, None] * self.ncontrol + sc.drag_index[drone_of]
        # control vector = [ctrl (nu), (mocap_pos (nmocap x 3) with a moving ship), mocap_quat (nmocap x 4)]
        quat0 = nu + (3 * self.scene.model.nmocap if self.ship_mocap is not None else 0)
        mocap_flat = model_of[:, None] * self.ncontrol + quat0 + 4 * sc.mocap_index[drone_of][:, None] + np.arange(4)
        return n_models, padded, qpos_flat, qvel_flat, motor_flat, drag_flat, mocap_flat

    def _start_batch(self, targets: FlightTargets, sec: SimSection, position: np.ndarray, yaw: np.ndarray) -> _Batch:
        """Rollout state and buffers for ``targets.batch`` flights, every drone at its start pose (centre of
        mass at ``position`` (batch, 3) m, heading ``yaw`` (batch,) rad)."""
        n_models, padded, qpos_flat, qvel_flat, motor_flat, drag_flat, mocap_flat = self._layout(targets.batch)
        state = np.tile(self._initial_state, (n_models, 1))
        park = _start_poses(targets, padded, position, yaw)
        state.reshape(-1)[qpos_flat] = park
        # ~4 tasks per thread: with chunks of a few steps the default (10 per thread) costs more in dispatch
        # than it gains in balance (measured, README.md)
        task_size = max(1, n_models // (4 * max(1, self.nthread)))
        return _Batch(targets.batch, padded, qpos_flat, qvel_flat, motor_flat, drag_flat, mocap_flat, state,
                      np.tile(self._initial_control, (n_models, 1)),
                      np.zeros((n_models, sec.chunk_steps, self.ncontrol)),
                      np.empty((n_models, sec.chunk_steps, self.nstate)), park, [self.scene.model] * n_models,
                      task_size)

    def _run_chunk(self, run: _Batch, sec: SimSection,
                   sample_wind: Callable[[], NDArray[np.float64]] | None = None) -> NDArray[np.float64] | None:
        """Advance ``run`` by one chunk under its held controls. ``sample_wind`` (optional, no arguments) is
        called while the rollout runs (it releases the GIL); its value is returned."""
        args: tuple[Any, ...] = (run.models, self._datas, run.state, run.controls)
        kw: dict[str, Any] = dict(control_spec=self.control_spec, skip_checks=True, nstep=sec.chunk_steps,
                                  state=run.out, chunk_size=run.task_size)
        wind = None
        if sample_wind is None:
            self._pool.rollout(*args, **kw)
        else:
            job = self._worker.submit(self._pool.rollout, *args, **kw)
            try:
                wind = sample_wind()
            finally:
                job.result()
        run.state = np.ascontiguousarray(run.out[:, -1])
        return wind

    def _commands(self, run: _Batch, controller: PositionController, body: Body, nav: NavigationEstimate,
                  ref: Reference, state: FlightState, wind_b: np.ndarray, dt: float, sec: SimSection,
                  nav_is_truth: bool, through: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Motor thrusts (padded, 4) N, attitude targets (padded, 4) and drag (padded, 3) N for the next
        chunk, from the wind ``wind_b`` (batch, 3) m/s at the flights (calm at the fillers); the position
        loop flies on the navigation estimate ``nav`` (the fillers on their true state; ``nav_is_truth``:
        the estimate is the truth, no copies). Ended flights are parked (held still, no forces): they take no
        further photos."""
        par = self.params
        drag = drag_force(_pad(wind_b, run.padded) - body.velocity, body.yaw, par, sec.drag_coefficient,
                          sec.air_density_kg_m3)
        position, velocity = body.position, body.velocity
        if not nav_is_truth:        # the fillers (if any) fly on their true state
            position, velocity = _pad_with(nav.position, position), _pad_with(nav.velocity, velocity)
        motors, quat_d = control(controller, position, velocity, body.rot,
                                 setpoints(ref, state.phase, run.park[run.batch:, :3], nav.yaw_error, through), dt,
                                 par)
        dead = _pad(state.phase >= ENDED, run.padded)          # ended, or away for a battery swap
        if np.any(dead):
            run.hold(dead, parked_pose(body.position[dead], run.park[dead]))
            motors[dead] = par.weight_n / 4.0
            quat_d[dead] = run.park[dead, 3:]
            drag[dead] = 0.0
            controller.reset(dead)
        return motors, quat_d, drag

    # -- flights --------------------------------------------------------------------------------------
    def fly(self, path: FlightPath, wind: WindModel, batch: int, view_offsets: np.ndarray | None = None,
            start_time_s: float = 0.0, *, ship: ShipInScene | None = None,
            flight_rngs: FlightRngs = None) -> FlightResult:
        """Fly ``path`` ``batch`` times through ``wind`` (anything with ``velocity(points (n,3), t)``,
        row i = flight i). ``view_offsets`` (batch, n_views, 4): commanded (dx, dy, dz m, dyaw rad) added to
        the plan per flight; the recorded offsets are always measured against the unperturbed plan.
        ``ship``: the ship flown around (its box for the compass and the views' depth, its motion); None:
        open sea. ``flight_rngs``: one Generator per flight (or a seed they are spawned from) for the
        navigation errors and the ship's motion; None: seed 0. BLAS runs on one thread meanwhile (``_BLAS_LIMIT``).
        """
        with threadpool_limits(**_BLAS_LIMIT):
            return self._fly(path, wind, batch, view_offsets, start_time_s, self.section, ship, flight_rngs)

    def _targets(self, path: FlightPath, batch: int, view_offsets: np.ndarray | None, ship: ShipInScene | None,
                 profile: Profile, sec: SimSection, stop: NDArray[np.bool_]) -> FlightTargets:
        targets = FlightTargets.from_path(path, batch, view_offsets, self.params.camera_offset_m,
                                          view_depths(path, None if ship is None else ship.box))
        if not profile.through:
            return replace(targets, stop=stop)
        speeds = vertex_speeds(targets.body, targets.yaw, path.leg_speeds(), sec.acceleration_m_s2, YAW_RATE_REF_RAD_S,
                               sec.capture.corner_radius_m, window_s=profile.jerk_window_s, stop=stop)
        return targets.flown_through(*speeds, *trigger_planes(targets.body), stop=stop)

    def _fly(self, path: FlightPath, wind: WindModel, batch: int, view_offsets: np.ndarray | None,
             start_time_s: float, sec: SimSection, ship: ShipInScene | None = None,
             flight_rngs: FlightRngs = None) -> FlightResult:
        """:meth:`fly` under the settings ``sec``: per chunk the sensing and phase steps (onboard.py,
        phases.py) on the flight state, then the commands, the record and the rollout."""
        par = self.params
        dt = sec.timestep_s * sec.chunk_steps
        stops = path.stops(sec.capture.mode)
        profile, dwell = _profile_and_dwell(path, stops, sec)
        targets = self._targets(path, batch, view_offsets, ship, profile, sec, stops)
        onboard, run = self._launch(path, targets, ship, flight_rngs, dt, start_time_s, sec)
        state = FlightState.start(targets)
        controller = PositionController(par, self.gains, run.padded)
        log = TrajectoryLog()
        record_every = max(1, int(round(sec.record_interval_s / dt)))
        away_cap_s, max_chunks = _mission_horizon(sec, dt)
        home = targets.home
        wind_next = None
        for chunk in range(max_chunks + 1):
            t = chunk * dt
            body = run.body()
            p_b, v_b, yaw, rot_b = body.position[:batch], body.velocity[:batch], body.yaw[:batch], body.rot[:batch]
            nav = onboard.sense(start_time_s + t, p_b, v_b, yaw)
            if state.resume_at.min() <= t + 1e-9:
                _next_sorties(state, targets, onboard, p_b, nav, t, profile)
            ref = reference(state, nav.position, profile, sec.leash_m)
            inside = _inside_field(wind, p_b)
            if wind_next is None:
                wind_b = _wind_at(wind, np.where(inside[:, None], p_b, home), start_time_s + t, batch)
            else:
                wind_b = wind_next
            self._endings(state, onboard, nav, p_b, v_b, wind_b, inside, t, chunk == max_chunks, sec, away_cap_s)
            shoot = partial(onboard.shoot, t=t, position=p_b, velocity=v_b, rot=rot_b, nav=nav,
                            attitude=onboard.point_camera(rot_b, yaw, targets.plan_pitch[np.minimum(
                                state.photo, targets.n_views - 1)]), targets=targets)
            self._photos_and_phases(state, targets, nav, shoot, dt, sec, dwell, profile)
            motors, quat_d, drag = self._commands(run, controller, body, nav, ref, state, wind_b, dt, sec,
                                                  onboard.navigation.ideal, profile.through)
            power = onboard.spend(motors[:batch], drag[:batch], wind_b - v_b, state.flying)
            if chunk % record_every == 0:
                log.append(t, position=p_b, reference=ref.position, yaw=yaw, tilt=tilt_of(rot_b),
                           thrust=motors[:batch].sum(axis=1), wind=wind_b, drag=drag[:batch], power=power,
                           charge=onboard.battery.charge)
            # the loop ends on a recorded chunk at or after every flight's last shutter (a photo's shutter opens
            # the trigger latency after its chunk), so a flight's record up to its end does not depend on whether
            # other flights of its batch are still flying
            if chunk % record_every == 0 and not state.active.any() and t >= state.flight_time.max() - 1e-9:
                break
            run.set_controls(motors, drag, quat_d)
            if self.ship_mocap is not None and onboard.motion is not None:
                self._move_ship(run, onboard, start_time_s + t + dt)
            # prefetch: the wind of the next chunk is sampled while this one's rollout runs (README.md)
            sample = (partial(_wind_at, wind, _predicted_points(wind, p_b, v_b, dt, inside, home),
                              start_time_s + t + dt, batch) if sec.prefetch_wind else None)
            wind_next = self._run_chunk(run, sec, sample)
            tick(state, ref, dt)
        stranded = state.phase == AWAY      # only past the simulator's guard: home on energy for good
        apply_endings(state, np.where(stranded, RETURNED_BATTERY, COMPLETED), t)
        return self._result(state, path, log, sec)

    @staticmethod
    def _endings(state: FlightState, onboard: Onboard, nav: NavigationEstimate, position: np.ndarray,
                 velocity: np.ndarray, wind_b: np.ndarray, inside: np.ndarray, t: float, last_chunk: bool,
                 sec: SimSection, away_cap_s: float) -> None:
        """End the flights that fail now (crash, a sortie past the time limit, out of the wind field ``inside``
        (batch,) bool), then apply the autopilot's decisions (:meth:`_mission_rules`)."""
        out_of_time = last_chunk or t - state.sortie_start.min() >= sec.max_flight_time_s
        if out_of_time:     # rare: the sorties past the simulator's limit
            out_of_time = ((t - state.sortie_start) >= sec.max_flight_time_s) | last_chunk
        apply_endings(state, check_failures(state, position, velocity, out_of_time), t)
        if not inside.all():
            apply_endings(state, np.where(state.flying & ~inside, LOST_OUTSIDE, COMPLETED), t)
        FlightSimulator._mission_rules(state, onboard, nav, position, wind_b, t, sec, away_cap_s)

    @staticmethod
    def _photos_and_phases(state: FlightState, targets: FlightTargets, nav: NavigationEstimate, shoot: _Shoot,
                           dt: float, sec: SimSection, dwell: np.ndarray, profile: Profile) -> None:
        """This chunk's photos (fly-through triggers, or the photo after the dwell) and phase moves."""
        if profile.through:
            FlightSimulator._passing_photos(state, targets, nav, shoot, dt, sec)
        moves = transitions(state, nav.position, nav.velocity, nav.yaw, targets, sec, dwell, profile.through)
        if not (moves.trigger.any() or moves.chain.any() or moves.to_settle.any() or moves.to_dwell.any()):
            return      # most chunks: no flight changes phase
        if profile.through:     # a view taken at rest (a stop, the last): the views still pending before it were missed
            state.photo = np.where(moves.trigger, np.maximum(state.photo, state.index), state.photo)
        due = np.flatnonzero(moves.trigger & (state.photo == state.index))
        take_photos(state, targets, due, shoot(due, state.photo[due], np.full(due.size, sec.capture.trigger_latency_s)))
        advance(state, targets, np.flatnonzero(moves.trigger | moves.chain), profile)
        apply_transitions(state, moves)

    @staticmethod
    def _mission_rules(state: FlightState, onboard: Onboard, nav: NavigationEstimate, position: np.ndarray,
                       wind_b: np.ndarray, t: float, sec: SimSection, away_cap_s: float) -> None:
        """The autopilot's decisions this chunk (sim/mission.py): home on energy (away for a battery swap while
        sorties are left), on a wind limit, or without headway (lost when home is out of reach)."""
        m = sec.mission
        decisions = onboard.decide(position, wind_b)
        stuck = no_headway(state, nav.position, t, m.headway_timeout_s, m.headway_progress_m, sec.leash_m)
        cause = check_returns(state, decisions.battery_due, decisions.px4_wind, decisions.operator_wind, stuck,
                              decisions.home_reachable)
        away, cause = swap_batteries(state, cause, m.max_sorties)
        if away.size:
            state.resume_at[away] = t + np.minimum(onboard.away_time_s(away, position[away]), away_cap_s)
        apply_endings(state, cause, t)

    def _launch(self, path: FlightPath, targets: FlightTargets, ship: ShipInScene | None, flight_rngs: FlightRngs,
                dt: float, start_time_s: float, sec: SimSection) -> tuple[Onboard, _Batch]:
        """The instruments and the rollout state of ``targets.batch`` flights at ``start_time_s``: each vehicle
        hovers where its navigation believes it is on the first target with its first heading (it has been
        holding there before the mission starts), not at the true target with its error as a step at t = 0. The
        flight out from home to that target (none for a tour in plan order: home is its first view) comes off
        the battery, as a resumed sortie's does."""
        onboard = Onboard(sec, self.params, targets, ship, 0 if flight_rngs is None else flight_rngs, dt,
                          path.speed_m_s, path.camera)
        onboard.fresh_battery(np.arange(targets.batch), targets.body[:, 0])
        first = onboard.sense(start_time_s, targets.body[:, 0], np.zeros((targets.batch, 3)), targets.yaw[:, 0])
        run = self._start_batch(targets, sec, targets.body[:, 0] - first.position_error,
                                targets.yaw[:, 0] - first.yaw_error)
        return onboard, run

    def _move_ship(self, run: _Batch, onboard: Onboard, t: float) -> None:
        """Pose the scene's ship body of each model for the next chunk (held over it): the ship of the model's
        first flight (each flight has its own sea; the ship is not part of the physics: contacts are off)."""
        motion, ship = onboard.motion, self.ship_mocap
        if motion is None or ship is None:
            raise ValueError("no moving ship: the scene has no ship mocap body or the flights no ship motion")
        d = self.section.drones_per_model
        translation, rotation = motion.flights(np.arange(0, run.batch, d)).pose(t)
        quat = Rotation.from_matrix(rotation).as_quat()[:, [3, 0, 1, 2]]          # (w, x, y, z)
        nmocap = self.scene.model.nmocap
        base = run.control_vec[:len(translation)]
        nu = self.scene.model.nu
        base[:, nu + 3 * ship + np.arange(3)] = translation
        base[:, nu + 3 * nmocap + 4 * ship + np.arange(4)] = quat
        run.controls[:len(translation)] = base[:, None, :]

    @staticmethod
    def _passing_photos(state: FlightState, targets: FlightTargets, nav: NavigationEstimate, shoot: _Shoot, dt: float,
                        sec: SimSection) -> None:
        """Fly-through: photograph the views whose planes the flights have passed (the shutter interpolated
        back to the crossing, plus the trigger latency); views missed are moved over."""
        rows, past, normal, missed = passing_views(state, nav.position, targets, sec.capture.corner_radius_m)
        state.photo[missed] += 1
        if not rows.size:       # most chunks
            return
        delay = shutter_offset(past, (nav.velocity[rows] * normal).sum(axis=1), dt, sec.capture.trigger_latency_s)
        take_photos(state, targets, rows, shoot(rows, state.photo[rows], delay))

    def _result(self, state: FlightState, path: FlightPath, log: TrajectoryLog, sec: SimSection) -> FlightResult:
        cap = state.captures
        return FlightResult(cap.capture_sets(path.camera, path.view_id), cap.offsets, cap.estimated_offsets, cap.taken,
                            cap.time, cap.pitch, cap.roll, cap.saturated, cap.blur_px, cap.charge, cap.ship_motion,
                            state.outcome, outcome_reasons(state, sec), state.failed, state.flight_time,
                            log.trajectory(), sec.timestep_s, sec.chunk_steps, state.sortie.copy(),
                            state.view_sortie.copy())

    def hover(self, wind: WindModel, position: ArrayLike, yaw: float, duration_s: float, batch: int = 1,
              flight_rngs: FlightRngs = None) -> FlightResult:
        """Hold a hover at ``position`` (3,) m (camera position) with heading ``yaw`` rad for ``duration_s``:
        a one-view path whose dwell is the duration (the settle phase is skipped by a zero timeout; photo in
        stop mode). ``flight_rngs``: as :meth:`fly`'s (the navigation errors). BLAS on one thread, as in :meth:`fly`."""
        path = FlightPath(np.asarray(position, dtype=float)[None, :], np.array([yaw]), np.array([0.0]),
                    np.array([-1]), np.array([1]), np.array([0]), speed_m_s=5.0, dwell_s=duration_s)
        sec = self.section.model_copy(update={"settle_timeout_s": 1e-9, "dwell_s": duration_s,
                                              "capture": self.section.capture.model_copy(update={"mode": "stop"})})
        with threadpool_limits(**_BLAS_LIMIT):
            return self._fly(path, wind, batch, None, 0.0, sec, None, flight_rngs)
