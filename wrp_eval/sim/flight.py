"""Batched closed-loop flights of a :class:`Path` in MuJoCo.

Design (measured, see README.md and bench.py): the batch of flights is packed ``drones_per_model``
quadrotors to a MuJoCo model (independent free bodies, no contacts), the models run in parallel in
``mujoco.rollout`` threads for a chunk of ``chunk_steps`` physics steps, and between chunks numpy
computes for the whole batch at once: the wind at every vehicle, the windward-area drag, the reference
(jerk-limited speed profile viewpoint to viewpoint), the position loop of the SE(3) controller, photo
triggers and failures. Motor thrusts, drag forces (world-frame force actuators on the free joint) and
the desired attitudes enter the rollout through ``control_spec = CTRL | MOCAP_QUAT`` and are held over
the chunk (zero-order hold, 50 ms by default: the position loop runs at 20 Hz); the attitude loop runs
inside MuJoCo at every physics step (200 Hz, vehicle.build_scene), so the numpy loop can run at the
slower rate a position loop needs.

Flight logic per viewpoint: TRANSIT along the straight segment at the cruise speed (accel-limited), then
SETTLE until within the tolerances (or a timeout: a waypoint mission in gusts takes the photo anyway),
then DWELL, then the photo is triggered and the capture pose recorded. A flight farther than
``fail_distance_m`` from its reference for longer than ``fail_time_s``, held back more than ``leash_m``
behind a waiting reference for longer than ``stall_time_s`` (no headway against the wind), below the sea
surface, or not finished after ``max_flight_time_s`` is a failed flight (reason recorded); its remaining
views are not taken.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from wrp_eval.planning.path import Path
from wrp_eval.sim.aero import drag_force
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.controller import GAIN_PRESETS, PositionController, quat_to_matrix, tilt_of, wrap_angle, yaw_of
from wrp_eval.sim.results import FlightResult, Trajectory
from wrp_eval.sim.vehicle import PHANTOM4, QuadrotorParams, Scene, build_scene

TRANSIT, SETTLE, DWELL, DONE, FAILED = 0, 1, 2, 3, 4
YAW_RATE_REF_RAD_S = np.radians(60.0)  # reference yaw rate when a segment is mostly a rotation


def _trapezoid(length, tau, v_max, a_max):
    """Rest-to-rest trapezoidal speed profile: distance s, speed v, acceleration a and the running integral
    of s, S = int s dt (each (n,)) at time tau (n,) s, plus the duration (n,). Before 0: at rest at 0;
    after: at rest at ``length``."""
    tri = length < v_max ** 2 / a_max
    v_peak = np.where(tri, np.sqrt(np.maximum(length, 0.0) * a_max), v_max)
    t_acc = v_peak / a_max
    t_cruise = np.where(tri, 0.0, length / v_max - t_acc)
    duration = 2.0 * t_acc + t_cruise
    s_acc = 0.5 * a_max * t_acc ** 2
    big_s_acc = a_max * t_acc ** 3 / 6.0
    big_s_end = big_s_acc + s_acc * t_cruise + 0.5 * v_peak * t_cruise ** 2 + (length * t_acc - big_s_acc)
    after = np.maximum(tau - duration, 0.0)
    moving = (tau >= 0.0) & (tau < duration)
    tau = np.clip(tau, 0.0, duration)
    t_c = tau - t_acc
    t_dec = duration - tau
    in_acc, in_dec = tau < t_acc, t_dec < t_acc
    s = np.where(in_acc, 0.5 * a_max * tau ** 2,
                 np.where(in_dec, length - 0.5 * a_max * t_dec ** 2, s_acc + v_peak * t_c))
    v = np.where(in_acc, a_max * tau, np.where(in_dec, a_max * t_dec, v_peak))
    a = np.where(moving, np.where(in_acc, a_max, np.where(in_dec, -a_max, 0.0)), 0.0)
    big_s = np.where(in_acc, a_max * tau ** 3 / 6.0,
                     np.where(in_dec, big_s_end - (length * t_dec - a_max * t_dec ** 3 / 6.0),
                              big_s_acc + s_acc * t_c + 0.5 * v_peak * t_c ** 2))
    return s, v, a, big_s + length * after, duration


def _reference_profile(length, tau, v_max, a_max, t_jerk):
    """Jerk-limited rest-to-rest profile: distance, speed, acceleration (each (n,)) at time tau, and the
    duration (n,).

    The trapezoidal speed profile averaged over a moving window of ``t_jerk`` s: the acceleration then
    ramps over t_jerk instead of jumping, i.e. the jerk is limited to a_max / t_jerk, at most twice that
    on a segment too short to reach a_max (PX4 shapes its auto-mode setpoints with a jerk limit too,
    MPC_JERK_AUTO, default 4 m/s^3). A step in the
    acceleration demand is what the attitude loop cannot follow without lag: with the trapezoid alone the
    vehicle overshot each viewpoint by ~10 cm (README.md). Exact box averages from the closed forms:
    s_j = (S(t) - S(t-T)) / T, v_j = (s(t) - s(t-T)) / T, a_j = (v(t) - v(t-T)) / T.
    """
    s1, v1, a1, big1, duration = _trapezoid(length, tau, v_max, a_max)
    if t_jerk <= 0.0:
        return s1, v1, a1, duration
    s0, v0, _, big0, _ = _trapezoid(length, tau - t_jerk, v_max, a_max)
    return (big1 - big0) / t_jerk, (s1 - s0) / t_jerk, (v1 - v0) / t_jerk, duration + t_jerk


def _wind_at(wind, points, t, batch):
    """(batch, 3) wind from ``wind.velocity(points, t)``, shape-checked."""
    out = np.asarray(wind.velocity(points, t), dtype=float)
    if out.shape != (batch, 3):
        raise ValueError(f"wind model returned shape {out.shape} for {batch} flights, expected ({batch}, 3)")
    return out


class FlightSimulator:
    """Owns the compiled scene, the rollout thread pool and the controller settings.

    ``scene_root``: optional PyMJCF root (e.g. the ship scene) the drones are attached to.
    """

    def __init__(self, section: SimSection = SimSection(), params: QuadrotorParams = PHANTOM4,
                 scene_root=None):
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
        self.control_spec = int(mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_MOCAP_QUAT)
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

    def close(self) -> None:
        self._worker.shutdown(wait=True)
        self._pool.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- layout of a batch in the rollout arrays ------------------------------------------------------
    def _layout(self, batch: int):
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
        # control vector = [ctrl (nu), mocap_quat (nmocap x 4)]
        mocap_flat = model_of[:, None] * self.ncontrol + nu + 4 * sc.mocap_index[drone_of][:, None] + np.arange(4)
        return n_models, padded, qpos_flat, qvel_flat, motor_flat, drag_flat, mocap_flat

    # -- flights --------------------------------------------------------------------------------------
    def fly(self, path: Path, wind, batch: int, view_offsets: np.ndarray | None = None,
            start_time_s: float = 0.0) -> FlightResult:
        """Fly ``path`` ``batch`` times through ``wind`` (anything with ``velocity(points (n,3), t)``,
        row i = flight i). ``view_offsets`` (batch, n_views, 4): commanded (dx, dy, dz m, dyaw rad) added to
        the plan per flight; the recorded offsets are always measured against the unperturbed plan.
        """
        return self._fly(path, wind, batch, view_offsets, start_time_s, self.section)

    def _fly(self, path, wind, batch, view_offsets, start_time_s, sec: SimSection) -> FlightResult:
        par = self.params
        n_views = len(path)
        dt = sec.timestep_s * sec.chunk_steps
        dwell = path.dwell_s if sec.dwell_s is None else sec.dwell_s
        plan_pos = np.asarray(path.positions, dtype=float)
        plan_yaw = np.asarray(path.yaw, dtype=float)
        plan_pitch = np.asarray(path.pitch, dtype=float)
        cmd_pos = np.broadcast_to(plan_pos, (batch, n_views, 3)).copy()
        cmd_yaw = np.broadcast_to(plan_yaw, (batch, n_views)).copy()
        if view_offsets is not None:
            view_offsets = np.asarray(view_offsets, dtype=float)
            if view_offsets.shape != (batch, n_views, 4):
                raise ValueError(f"view_offsets must have shape {(batch, n_views, 4)}, got {view_offsets.shape}")
            cmd_pos += view_offsets[..., :3]
            cmd_yaw += view_offsets[..., 3]
        # body targets: the camera (not the centre of mass) goes to the viewpoint, level attitude
        cam = np.asarray(par.camera_offset_m)
        cy, sy = np.cos(cmd_yaw), np.sin(cmd_yaw)
        body_tgt = cmd_pos - np.stack([cy * cam[0] - sy * cam[1], sy * cam[0] + cy * cam[1],
                                       np.full_like(cy, cam[2])], axis=-1)

        n_models, padded, qpos_flat, qvel_flat, motor_flat, drag_flat, mocap_flat = self._layout(batch)
        state = np.tile(self._initial_state, (n_models, 1))
        flat_state = state.reshape(-1)
        # start hovering level at (each flight's) first body target
        start = np.zeros((padded, 7))
        start[:, 3] = 1.0
        start[:batch, :3] = body_tgt[:, 0]
        start[batch:, :3] = body_tgt[0, 0] + np.array([0.0, 0.0, 50.0])
        start[:batch, 3] = np.cos(cmd_yaw[:, 0] / 2)
        start[:batch, 6] = np.sin(cmd_yaw[:, 0] / 2)
        flat_state[qpos_flat] = start
        park = start.copy()

        controller = PositionController(par, self.gains, padded)
        # skip_checks rollout: no singleton expansion, so the held controls are tiled over the chunk
        control_vec = np.zeros((n_models, self.ncontrol))
        flat_ctrl = control_vec.reshape(-1)
        controls = np.zeros((n_models, sec.chunk_steps, self.ncontrol))
        models = [self.scene.model] * n_models
        # ~4 tasks per thread: with chunks of a few steps the default (10 per thread) costs more in dispatch
        # than it gains in balance (measured, README.md)
        task_size = max(1, n_models // (4 * max(1, self.nthread)))
        out_buf = np.empty((n_models, sec.chunk_steps, self.nstate))

        # per-flight reference state
        idx = np.zeros(batch, dtype=int)
        phase = np.full(batch, SETTLE)
        phase_time = np.zeros(batch)
        seg_start = body_tgt[:, 0].copy()
        seg_end = body_tgt[:, 0].copy()
        seg_yaw0 = cmd_yaw[:, 0].copy()
        seg_dyaw = np.zeros(batch)
        seg_len = np.zeros(batch)
        seg_dir = np.zeros((batch, 3))
        seg_duration = np.zeros(batch)
        lost_time = np.zeros(batch)
        held_time = np.zeros(batch)
        reasons = [""] * batch
        flight_time = np.zeros(batch)

        offsets = np.full((batch, n_views, 4), np.nan)
        taken = np.zeros((batch, n_views), dtype=bool)
        cap_time = np.full((batch, n_views), np.nan)
        cap_pos = np.full((batch, n_views, 3), np.nan)
        cap_yaw = np.full((batch, n_views), np.nan)
        cap_pitch = np.full((batch, n_views), np.nan)
        resid_roll = np.full((batch, n_views), np.nan)
        saturated = np.zeros((batch, n_views), dtype=bool)

        record_every = max(1, int(round(sec.record_interval_s / dt)))
        rec = {k: [] for k in ("time", "position", "reference", "yaw", "tilt", "thrust", "wind", "drag")}
        rows = np.arange(batch)
        hover_thrust = par.weight_n / 4.0
        zeros_pad = np.zeros((padded - batch, 3))
        v_cruise, a_max = path.speed_m_s, sec.acceleration_m_s2
        t_jerk = a_max / sec.jerk_m_s3 if sec.jerk_m_s3 else 0.0
        settle_yaw = np.radians(sec.settle_yaw_deg)
        lo_pitch, hi_pitch = par.gimbal_pitch_range_rad
        lo_roll, hi_roll = par.gimbal_roll_range_rad
        max_chunks = int(np.ceil(sec.max_flight_time_s / dt))

        wind_next = None
        for chunk in range(max_chunks + 1):
            t = chunk * dt
            qpos = flat_state[qpos_flat]
            qvel = flat_state[qvel_flat]
            pos, quat = qpos[:, :3], qpos[:, 3:]
            vel = qvel[:, :3]
            rot = quat_to_matrix(quat)
            yaw_all = yaw_of(rot)
            yaw = yaw_all[:batch]
            p_b, v_b = pos[:batch], vel[:batch]

            # ---- reference along the current segment
            s, v, a, _ = _reference_profile(seg_len, phase_time, v_cruise, a_max, t_jerk)
            transit = phase == TRANSIT
            ref_pos = np.where(transit[:, None], seg_start + seg_dir * s[:, None], seg_end)
            # Leash: a vehicle held back by a head wind is not "lost"; its reference waits for it (what a
            # waypoint autopilot does: it flies towards the next waypoint as fast as it can).
            err = p_b - ref_pos
            dist2 = np.einsum("ij,ij->i", err, err)
            held = transit & (dist2 > sec.leash_m ** 2)
            moving = transit & ~held
            ref_vel = np.where(moving[:, None], seg_dir * v[:, None], 0.0)
            ref_acc = np.where(moving[:, None], seg_dir * a[:, None], 0.0)
            frac = np.where(transit, np.clip(phase_time / np.maximum(seg_duration, 1e-9), 0.0, 1.0), 1.0)
            ref_yaw = seg_yaw0 + seg_dyaw * frac

            # ---- failures: lost position, ditched, non-finite
            active = phase < DONE
            lost_time = np.where(active & (dist2 > sec.fail_distance_m ** 2), lost_time + dt, 0.0)
            held_time = np.where(held, held_time + dt, 0.0)
            bad = ~np.isfinite(p_b.sum(axis=1) + v_b.sum(axis=1))
            stalled = held_time > sec.stall_time_s
            newly = active & ((lost_time > sec.fail_time_s) | stalled | (p_b[:, 2] < 0.0) | bad)
            if chunk == max_chunks:
                newly |= active
            for i in np.flatnonzero(newly):
                if bad[i]:
                    reasons[i] = f"non-finite state at t={t:.2f}s"
                elif p_b[i, 2] < 0.0:
                    reasons[i] = f"ditched (below sea level) at t={t:.2f}s"
                elif stalled[i]:
                    reasons[i] = (f"no headway: > {sec.leash_m:g} m behind the reference for "
                                  f"> {sec.stall_time_s:g} s at t={t:.2f}s (before view {idx[i]})")
                elif lost_time[i] > sec.fail_time_s:
                    reasons[i] = (f"lost position: > {sec.fail_distance_m:g} m from the reference for "
                                  f"> {sec.fail_time_s:g} s at t={t:.2f}s (before view {idx[i]})")
                else:
                    reasons[i] = f"not finished within max_flight_time_s={sec.max_flight_time_s:g}"
                flight_time[i] = t
            phase = np.where(newly, FAILED, phase)

            # ---- phase transitions (vectorised state machine)
            to_settle = (phase == TRANSIT) & (phase_time >= seg_duration)
            yaw_err = wrap_angle(yaw - cmd_yaw[rows, idx])
            settled = ((((p_b - seg_end) ** 2).sum(axis=1) < sec.settle_position_m ** 2)
                       & ((v_b ** 2).sum(axis=1) < sec.settle_speed_m_s ** 2)
                       & (np.abs(yaw_err) < settle_yaw))
            to_dwell = (phase == SETTLE) & (settled | (phase_time >= sec.settle_timeout_s))
            trigger = (phase == DWELL) & (phase_time >= dwell - 1e-9)
            if np.any(trigger):
                f = np.flatnonzero(trigger)
                k = idx[f]
                r = rot[f]
                cam_pos = p_b[f] + r @ cam
                cam_yaw = yaw[f]
                # gimbal: joint angle = wanted world pitch - elevation of the nose, within its range
                nose_elev = np.arcsin(np.clip(r[:, 2, 0], -1, 1))
                wanted = plan_pitch[k]
                joint = np.clip(wanted - nose_elev, lo_pitch, hi_pitch)
                pitch = joint + nose_elev
                roll = np.arcsin(np.clip(r[:, 2, 1], -1, 1))
                residual = roll - np.clip(roll, lo_roll, hi_roll)
                cap_pos[f, k] = cam_pos
                cap_yaw[f, k] = cam_yaw
                cap_pitch[f, k] = pitch
                resid_roll[f, k] = residual
                saturated[f, k] = (np.abs(pitch - wanted) > 1e-9) | (residual != 0.0)
                offsets[f, k, :3] = cam_pos - plan_pos[k]
                offsets[f, k, 3] = wrap_angle(cam_yaw - plan_yaw[k])
                taken[f, k] = True
                cap_time[f, k] = t
                flight_time[f] = t
                last = k == n_views - 1
                phase[f[last]] = DONE
                nxt = f[~last]
                if nxt.size:
                    k1 = idx[nxt] + 1
                    seg_start[nxt] = seg_end[nxt]
                    seg_end[nxt] = body_tgt[nxt, k1]
                    delta = seg_end[nxt] - seg_start[nxt]
                    length = np.linalg.norm(delta, axis=1)
                    seg_len[nxt] = length
                    seg_dir[nxt] = delta / np.maximum(length, 1e-12)[:, None]
                    seg_yaw0[nxt] = cmd_yaw[nxt, k1 - 1]
                    seg_dyaw[nxt] = wrap_angle(cmd_yaw[nxt, k1] - cmd_yaw[nxt, k1 - 1])
                    dur = _reference_profile(length, np.zeros_like(length), v_cruise, a_max, t_jerk)[3]
                    seg_duration[nxt] = np.maximum(dur, np.abs(seg_dyaw[nxt]) / YAW_RATE_REF_RAD_S)
                    idx[nxt] = k1
                    phase[nxt] = TRANSIT
            phase = np.where(to_settle, SETTLE, phase)
            phase = np.where(to_dwell, DWELL, phase)
            phase_time = np.where(trigger | to_settle | to_dwell, 0.0, phase_time)
            # the last chunk is still recorded (wind, drag, control included) before the loop ends, so a
            # flight's record does not depend on whether other flights of its batch are still flying
            finished = not np.any(phase < DONE)

            # ---- wind, drag, control for the whole (padded) batch
            wind_b = _wind_at(wind, p_b, start_time_s + t, batch) if wind_next is None else wind_next
            wind_all = np.concatenate([wind_b, zeros_pad]) if padded > batch else wind_b
            drag = drag_force(wind_all - vel, yaw_all, par, sec.drag_coefficient, sec.air_density_kg_m3)
            rp = np.concatenate([ref_pos, park[batch:, :3]]) if padded > batch else ref_pos
            rv = np.concatenate([ref_vel, zeros_pad]) if padded > batch else ref_vel
            ra = np.concatenate([ref_acc, zeros_pad]) if padded > batch else ref_acc
            ryaw = np.concatenate([ref_yaw, np.zeros(padded - batch)]) if padded > batch else ref_yaw
            integrate = np.concatenate([phase != TRANSIT, np.ones(padded - batch, dtype=bool)])
            thrust, quat_d = controller(pos, vel, rot[:, :, 2], rp, rv, ra, ryaw, dt, integrate)
            motors = np.repeat(np.minimum(thrust / 4.0, par.max_thrust_per_motor_n)[:, None], 4, axis=1)
            # failed flights are parked (held still, no forces): they take no further photos
            dead = np.concatenate([phase == FAILED, np.zeros(padded - batch, dtype=bool)])
            if np.any(dead):
                qpos_dead = park[dead].copy()
                qpos_dead[:, :3] = np.where(np.isfinite(pos[dead]), pos[dead], park[dead, :3])
                qpos_dead[:, 2] = np.maximum(qpos_dead[:, 2], 1.0)
                flat_state[qpos_flat[dead]] = qpos_dead
                flat_state[qvel_flat[dead]] = 0.0
                motors[dead] = hover_thrust
                quat_d[dead] = park[dead, 3:]
                drag[dead] = 0.0
                controller.reset(dead)

            if chunk % record_every == 0:
                rec["time"].append(t)
                rec["position"].append(p_b.copy())
                rec["reference"].append(ref_pos.copy())
                rec["yaw"].append(yaw)
                rec["tilt"].append(tilt_of(rot[:batch]))
                rec["thrust"].append(motors[:batch].sum(axis=1))
                rec["wind"].append(wind_b)
                rec["drag"].append(drag[:batch].copy())
            if finished:
                break

            flat_ctrl[motor_flat] = motors
            flat_ctrl[drag_flat] = drag
            flat_ctrl[mocap_flat] = quat_d
            controls[:] = control_vec[:, None, :]
            rollout_args = (models, self._datas, state, controls)
            rollout_kw = dict(control_spec=self.control_spec, skip_checks=True, nstep=sec.chunk_steps,
                              state=out_buf, chunk_size=task_size)
            if sec.prefetch_wind:
                # the rollout releases the GIL: while it runs, the wind of the next chunk is sampled at the
                # positions predicted for the end of this one, p + v dt (the vehicle moves < 0.5 m per
                # chunk, the prediction is off by 0.5 a dt^2 < 1 cm, and the wind field varies over
                # metres; README.md). The controller itself always uses the true state.
                job = self._worker.submit(self._pool.rollout, *rollout_args, **rollout_kw)
                try:
                    wind_next = _wind_at(wind, p_b + v_b * dt, start_time_s + t + dt, batch)
                finally:
                    job.result()
            else:
                self._pool.rollout(*rollout_args, **rollout_kw)
            state = np.ascontiguousarray(out_buf[:, -1])
            flat_state = state.reshape(-1)
            phase_time = phase_time + np.where(held, 0.0, dt)

        captures = tuple(
            CaptureSet(cap_pos[i, taken[i]], cap_yaw[i, taken[i]], cap_pitch[i, taken[i]],
                       np.flatnonzero(taken[i]), path.camera) for i in range(batch))
        traj = Trajectory(np.asarray(rec["time"]), *(np.stack(rec[k], axis=1) for k in
                                                     ("position", "reference", "yaw", "tilt", "thrust",
                                                      "wind", "drag")))
        failed = np.array([bool(r) for r in reasons])
        return FlightResult(captures, offsets, taken, cap_time, cap_pitch, resid_roll, saturated, failed,
                            tuple(reasons), flight_time, traj, sec.timestep_s, sec.chunk_steps)

    def hover(self, wind, position, yaw: float, duration_s: float, batch: int = 1) -> FlightResult:
        """Hold a hover at ``position`` (3,) m (camera position) with heading ``yaw`` rad for ``duration_s``:
        a one-view path whose dwell is the duration (the settle phase is skipped by a zero timeout)."""
        path = Path(np.asarray(position, dtype=float)[None, :], np.array([yaw]), np.array([0.0]),
                    np.array([-1]), np.array([1]), np.array([0]), speed_m_s=5.0, dwell_s=duration_s)
        sec = self.section.model_copy(update={"settle_timeout_s": 1e-9, "dwell_s": duration_s})
        return self._fly(path, wind, batch, None, 0.0, sec)
