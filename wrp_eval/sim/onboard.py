"""What the aircraft carries and senses besides its airframe, for a batch of flights: the navigation estimate,
the gimbal, the battery, the autopilot's wind estimate, and the ship moving under it; and the photo that
results at each shutter (:meth:`Onboard.shoot`).

The controller flies on the navigation's estimate; the photo is taken at the true state (the camera's true
pose, expressed in the ship's frame at the shutter instant: what the reconstruction sees); the image's
position prior is the estimate (what the photo's GPS tag holds).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from wrp_eval.camera import Camera, angles_near_plan, camera_angles, camera_rotations, optical_axes
from wrp_eval.compiled import as_rows
from wrp_eval.planning.path import FlightPath
from wrp_eval.ship.motion import ShipMotion, ShipMotionSection, ship_motion
from wrp_eval.ship.nofly import distance_to_box, ray_box_distance
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.sim.blur import angular_velocity, motion_blur_px
from wrp_eval.sim.config import SimSection
from wrp_eval.sim.flight_state import FlightTargets, Shot
from wrp_eval.sim.gimbal import CameraAttitude, Gimbal, GimbalParams
from wrp_eval.sim.mission import Decisions, WindEstimate, decide, travel_time_s
from wrp_eval.sim.navigation import (
    NavigationEstimate,
    NavigationEstimator,
    navigation_params,
)
from wrp_eval.sim.power import Battery, electrical_power_w, level_flight_power_w
from wrp_eval.sim.vehicle import QuadrotorParams
from wrp_eval.streams import FlightRngs, children, flight_generators


@dataclass(frozen=True)
class ShipInScene:
    """The ship the drones fly around, as the simulator needs it: box (2, 3) m, the hull's cuboid (the
    proxy's corners) in the ship frame, for the compass's distance to the hull and the views' depth;
    motion: the ``ship.motion`` section (its swing in a seaway); particulars: for the motion model;
    wind_speed_10m_m_s: scalar or (batch,) m/s, each flight's mean wind (the sea of ``sea_state: from_wind``)."""

    box: np.ndarray
    motion: ShipMotionSection = ShipMotionSection()
    particulars: ShipParticulars | None = None
    wind_speed_10m_m_s: object = None

    @classmethod
    def of(cls, mesh: Any, motion: ShipMotionSection, particulars: ShipParticulars | None = None,
           wind_speed_10m_m_s: object = None) -> ShipInScene:
        """The ship of a true ``mesh`` (trimesh, ship frame): its bounding box above the waterline."""
        box = np.array(mesh.bounds, dtype=float)
        box[0, 2] = max(box[0, 2], 0.0)
        return cls(box, motion, particulars, wind_speed_10m_m_s)


def view_depths(path: FlightPath, box: np.ndarray | None) -> np.ndarray:
    """(n_views,) m: distance along each planned optical axis to the ship's box, or, where the axis misses it
    (transition views), to its nearest point; NaN without a box and for a view inside it (no depth known)."""
    if box is None:
        return np.full(len(path), np.nan)
    positions = np.asarray(path.positions, dtype=float)
    along = ray_box_distance(positions, optical_axes(path.yaw, path.pitch), box)
    nearest = distance_to_box(positions, box)
    return np.where(np.isfinite(along), along, np.where(nearest > 0.0, nearest, np.nan))


class Onboard:
    """The instruments of ``batch`` flights (module docstring), advanced once per chunk of ``dt_s`` s."""

    def __init__(self, sec: SimSection, params: QuadrotorParams, targets: FlightTargets, ship: ShipInScene | None,
                 flight_rngs: FlightRngs, dt_s: float, cruise_m_s: float, camera: Camera) -> None:
        batch = targets.batch
        streams = [children(g, 2) for g in flight_generators(flight_rngs, batch)]
        self.sec, self.params, self.dt_s, self.camera = sec, params, dt_s, camera
        self.cruise_m_s = cruise_m_s
        self.navigation = NavigationEstimator(navigation_params(sec.navigation), [s[0] for s in streams], batch, dt_s)
        self.box = None if ship is None else np.asarray(ship.box, dtype=float)
        self.motion: ShipMotion | None = None if ship is None else ship_motion(
            ship.motion, ship.particulars, [s[1] for s in streams], batch, ship.wind_speed_10m_m_s)
        self.battery = Battery(sec.battery, batch)
        self.home = targets.home.copy()
        self.gimbal_params = GimbalParams.of(sec.gimbal)
        self.gimbal: Gimbal | None = None
        self.attitude: CameraAttitude | None = None        # the cameras now ...
        self._previous: CameraAttitude | None = None       # ... and one chunk ago (their rate: the blur)
        self.wind_estimate = WindEstimate(batch, dt_s, sec.mission)     # the autopilot's horizontal wind
        self.cruise_power_w, self.return_power_w = (float(p) for p in level_flight_power_w(
            np.array([cruise_m_s, sec.mission.return_airspeed_m_s]), params, sec.battery, sec.drag_coefficient,
            sec.air_density_kg_m3))

    def sense(self, t: float, position: np.ndarray, velocity: np.ndarray, yaw: np.ndarray) -> NavigationEstimate:
        """The navigation estimate at ``t`` s of vehicles at ``position``, ``velocity`` (batch, 3), ``yaw``."""
        hull = None if self.box is None else distance_to_box(position, self.box)
        return self.navigation.estimate(t, position, velocity, yaw, hull)

    def point_camera(self, rot: np.ndarray, yaw: np.ndarray, wanted_pitch: np.ndarray) -> CameraAttitude:
        """Advance the gimbal one chunk (airframes ``rot`` (batch, 3, 3), planned pitch of each flight's next
        view (batch,) rad) and return the cameras' attitude; the previous chunk's is kept for the blur."""
        start = self.gimbal is None
        if self.gimbal is None:
            self.gimbal = Gimbal(self.gimbal_params, rot, wanted_pitch, self.dt_s)
        attitude = self.gimbal.step(rot, yaw, wanted_pitch, advance=not start)
        self._previous = attitude if self.attitude is None else self.attitude
        self.attitude = attitude
        return attitude

    def spend(self, motors: np.ndarray, drag: np.ndarray, rel_air: np.ndarray, flying: np.ndarray) -> np.ndarray:
        """Drain the batteries over the chunk: motor thrusts (batch, 4) N, drag (batch, 3) N, relative air
        (batch, 3) m/s; returns the electrical power (batch,) W."""
        power = electrical_power_w(motors, drag, rel_air, self.params, self.sec.battery, self.sec.air_density_kg_m3)
        self.battery.drain(power, self.dt_s, flying)
        return power

    def decide(self, position: np.ndarray, wind: np.ndarray) -> Decisions:
        """The autopilot's :class:`~wrp_eval.sim.mission.Decisions` this chunk for vehicles at ``position``
        (batch, 3) m in ``wind`` (batch, 3) m/s (its wind estimates advance by one chunk)."""
        n = len(self.home)
        position, wind = as_rows("position", position, (n, 3)), as_rows("wind", wind, (n, 3))
        bat = self.battery
        return decide(self.wind_estimate, self.home, position, wind, self.cruise_m_s, self.cruise_power_w,
                      self.return_power_w, bat.energy_j, bat.reserve_j, bool(bat.section.enabled))

    def away_time_s(self, rows: np.ndarray, position: np.ndarray) -> np.ndarray:
        """(m,) s that flights ``rows`` (m,) at their breakpoints ``position`` (m, 3) m spend away: home at the
        cruise airspeed with the estimated wind, the swap on deck, back to the breakpoint."""
        wind, home = self.wind_estimate.current[rows], self.home[rows]
        return (travel_time_s(position, home, wind, self.cruise_m_s) + self.sec.mission.swap_time_s
                + travel_time_s(home, position, wind, self.cruise_m_s))

    def fresh_battery(self, rows: np.ndarray, position: np.ndarray) -> None:
        """Flights ``rows`` (m,) get a full battery at home, less the energy to fly back to their breakpoints
        ``position`` (m, 3) m at the cruise airspeed with the estimated wind."""
        wind, home = self.wind_estimate.current[rows], self.home[rows]
        back = travel_time_s(home, position, wind, self.cruise_m_s) * self.cruise_power_w
        bat = self.battery
        bat.energy_j[rows] = np.maximum(bat.section.start_charge * bat.capacity_j - back, 0.0)

    def shoot(self, rows: np.ndarray, views: np.ndarray, delay_s: np.ndarray, t: float, position: np.ndarray,
              velocity: np.ndarray, rot: np.ndarray, nav: NavigationEstimate, attitude: CameraAttitude,
              targets: FlightTargets) -> Shot | None:
        """The photos of flights ``rows`` (m,) of ``views`` (m,) whose shutters open ``delay_s`` (m,) s from ``t``
        (negative: earlier in the last chunk): the true vehicle state (batch arrays: ``position``,
        ``velocity`` (batch, 3), ``rot`` (batch, 3, 3)) and the estimate ``nav`` are carried to the shutter
        instant at constant velocity; ``attitude``: the cameras' now (:meth:`point_camera`'s). None when no
        flight takes a photo."""
        if not rows.size:
            return None
        offset = rot[rows] @ np.asarray(self.params.camera_offset_m)
        cam_pos = position[rows] + velocity[rows] * delay_s[:, None] + offset
        # the navigation puts the camera's lever arm on its own (estimated) heading
        c, s = np.cos(nav.yaw_error[rows]), np.sin(nav.yaw_error[rows])
        arm = np.stack([c * offset[:, 0] - s * offset[:, 1], s * offset[:, 0] + c * offset[:, 1], offset[:, 2]], 1)
        estimated = nav.position[rows] + nav.velocity[rows] * delay_s[:, None] + arm
        before = self._previous
        if before is None:
            raise ValueError("shoot before point_camera: no camera attitude of the last chunk")
        cam_rot = camera_rotations(attitude.yaw[rows], attitude.pitch[rows], attitude.roll[rows])
        omega = angular_velocity(camera_rotations(before.yaw[rows], before.pitch[rows], before.roll[rows]), cam_rot,
                                 self.dt_s)
        blur = motion_blur_px(velocity[rows], cam_rot, omega, targets.depth[views], self.sec.capture.exposure_s,
                              self.camera.focal_px)
        shutter = t + delay_s
        yaw, pitch, roll = attitude.yaw[rows], attitude.pitch[rows], attitude.roll[rows]
        turned = np.any(delay_s != 0.0)
        if turned:     # the camera keeps turning at its rate until the shutter (or back to it)
            cam_rot = cam_rot @ Rotation.from_rotvec(omega * delay_s[:, None]).as_matrix()
            yaw = np.arctan2(cam_rot[:, 1, 2], cam_rot[:, 0, 2])      # the optical axis's heading
        estimated_yaw = yaw + nav.yaw_error[rows]       # the navigation's heading at the shutter
        swing = np.zeros((len(rows), 4))
        if self.motion is not None:
            ship = self.motion.flights(rows)
            cam_pos, cam_rot = ship.to_ship_frame(shutter, cam_pos, cam_rot)
            swing = ship.dof(shutter)
        if turned or self.motion is not None:
            yaw, pitch, roll = angles_near_plan(*camera_angles(cam_rot), targets.plan_yaw[views],
                                                targets.plan_pitch[views])
        return Shot(shutter, cam_pos, yaw, pitch, roll, attitude.saturated[rows], estimated, estimated_yaw, blur,
                    self.battery.charge[rows], swing)
