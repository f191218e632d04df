"""Log a plan to a rerun recording (.rrd): proxy, samples, candidate views, chosen views as camera frusta
(``rr.Transform3D`` + ``rr.Pinhole``, OpenCV camera axes RDF), transition views and the tour."""

from __future__ import annotations

from pathlib import Path

import rerun as rr

from wrp_eval.camera import camera_rotations
from wrp_eval.planning.path import KIND_TRANSITION, FlightPath
from wrp_eval.planning.planner import PlanResult
from wrp_eval.recording import APPLICATION_ID, recording
from wrp_eval.ship.proxy import Proxy

_FRUSTUM_DEPTH_M = 4.0  # drawn image-plane distance


def _log_views(rec: rr.RecordingStream, prefix: str, path: FlightPath, colours: list[list[int]],
               tour_colour: list[int]) -> None:
    """One frustum entity per view of ``path`` under ``prefix``/views/<i> and its tour as ``prefix``/tour."""
    cam = path.camera
    rot = camera_rotations(path.yaw, path.pitch)
    for i in range(len(path)):  # one entity per view: rerun draws a frustum per Pinhole entity
        rec.log(f"{prefix}/views/{i:04d}", rr.Transform3D(translation=path.positions[i], mat3x3=rot[i]),
                static=True)
        rec.log(f"{prefix}/views/{i:04d}", rr.Pinhole(focal_length=cam.focal_px,
                                                      width=cam.image_width_px, height=cam.image_height_px,
                                                      camera_xyz=rr.ViewCoordinates.RDF,
                                                      image_plane_distance=_FRUSTUM_DEPTH_M, color=colours[i]),
                static=True)
    rec.log(f"{prefix}/tour", rr.LineStrips3D([path.positions], colors=[tour_colour]), static=True)


def save_plan_recording(result: PlanResult, proxy: Proxy, file: str | Path,
                        application_id: str = APPLICATION_ID,
                        recording_id: str | None = None, other_paths: dict[str, FlightPath] | None = None) -> Path:
    """Write ``file`` atomically (:func:`wrp_eval.recording.recording`) with entities plan/proxy,
    plan/no_fly, plan/samples, plan/candidates, plan/views/<i> (frusta), plan/tour; and each of
    ``other_paths`` (e.g. the WRP moved from this plan) as paths/<name>/views/<i> and paths/<name>/tour."""
    file = Path(file)
    with recording(file, recording_id=recording_id, application_id=application_id) as rec:
        _log_plan(rec, result, proxy, other_paths or {})
    return file


def _log_plan(rec: rr.RecordingStream, result: PlanResult, proxy: Proxy, other_paths: dict[str, FlightPath]) -> None:
    """The plan's entities and ``other_paths`` (all static; ship frame, metres) into ``rec``."""
    rec.log("plan", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    lo, hi = proxy.bounds
    rec.log("plan/proxy", rr.Boxes3D(mins=[lo], sizes=[hi - lo], colors=[[40, 200, 80]]), static=True)
    nlo, nhi = proxy.no_fly_bounds()
    rec.log("plan/no_fly", rr.Boxes3D(mins=[nlo], sizes=[nhi - nlo], colors=[[220, 60, 60]]), static=True)
    if result.samples is not None:
        rec.log("plan/samples", rr.Points3D(result.samples.points, radii=0.3,
                                            class_ids=result.samples.face), static=True)
    if result.candidates is not None:
        rec.log("plan/candidates", rr.Points3D(result.candidates.positions, radii=0.2,
                                               colors=[[150, 150, 150]]), static=True)
    path = result.path
    _log_views(rec, "plan", path, [[255, 160, 0] if k == KIND_TRANSITION else [30, 120, 255] for k in path.kind],
               [255, 255, 255])
    for name, other in other_paths.items():
        rec.log(f"paths/{name}", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        _log_views(rec, f"paths/{name}", other, [[230, 40, 200]] * len(other), [230, 40, 200])
