"""The flyable path: ordered viewpoints, the value type planning hands to the simulator and the exporters.

Inside the code angles are radians; ``path.json`` stores degrees (the edge of the system).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from wrp_eval.atomic import write_text_atomic
from wrp_eval.camera import Camera
from wrp_eval.errors import InputError

KIND_SURFACE = 0
KIND_TRANSITION = 1
KIND_NAMES = ("surface", "transition")
PATH_FORMAT_VERSION = 1
# a view's capture mode: the names of wrp_eval.sim.capture_mode (STOP, FLY_THROUGH); planning does not import the
# simulator
CAPTURE_MODES = ("stop", "fly-through")


@dataclass(frozen=True)
class FlightPath:
    """Ordered viewpoints of one tour.

    positions (n, 3) m in the ship frame; yaw (n,) rad; pitch (n,) rad (gimbal, negative looks down);
    face_id (n,) int, the proxy face a view photographs (-1 for transition views between faces);
    kind (n,) int, KIND_SURFACE or KIND_TRANSITION; sortie (n,) int, the battery sortie of each view.
    speed_m_s: cruise speed between views; dwell_s: hover time per photo.
    view_id (n,) int or None: which viewpoint of the plan each view is when the tour is flown in another order
    (:meth:`reversed`) or has views inserted (numbered after the plan's, the redundant lever); None: view i is
    viewpoint i. The oracle keys each view's random draws by it, so the same
    viewpoint keeps its draws whatever its place in the tour (common random numbers).
    noise_draw: which draw of a flight's own random errors the mission meets: its navigation errors, the ship's
    motion and its wind's turbulence and gusts (the mean wind, the weather, is the trial's whatever the draw).
    0: the campaign trial's own; k > 0: the same mission flown again in the same weather with other errors
    (:meth:`redrawn`; the placebo of a tour flown in another order, :mod:`wrp_eval.wrp.direction`). The
    campaign's flight evaluator applies it to the trial's seeds (:func:`wrp_eval.streams.redrawn_seed`; ``wrp-eval
    fly`` and the envelope, which seed their flights themselves, do not); it is not part of a mission file.
    capture (n,) str or None: each view's capture mode, ``stop`` or ``fly-through``
    (:mod:`wrp_eval.sim.capture_mode`), overriding the mission's ``sim.capture.mode`` (a fly-through mission
    that stops where a view needs a sharp, level photo; the evaluation's capture lever,
    ``wrp.evaluate.capture_stops``); None: every view as the mission's mode says. Written per viewpoint in
    path.json and in every exported mission.
    leg_speed_m_s (n - 1,) m/s or None: the cruise speed of each leg (leg i from view i to view i + 1; the
    evaluation's speed lever, ``wrp.evaluate.slow_legs``); None: ``speed_m_s`` on every leg. Written per
    viewpoint (the leg leaving it) in path.json and in every exported mission.
    """

    positions: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    face_id: np.ndarray
    kind: np.ndarray
    sortie: np.ndarray
    camera: Camera = Camera()
    speed_m_s: float = 5.0
    dwell_s: float = 2.0
    method: str = "ours"
    metadata: dict = field(default_factory=dict)
    view_id: np.ndarray | None = None
    noise_draw: int = 0
    capture: tuple[str, ...] | None = None
    leg_speed_m_s: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.capture is not None and (len(self.capture) != len(self.positions)
                                         or not set(self.capture) <= set(CAPTURE_MODES)):
            raise ValueError(f"capture must give one of {CAPTURE_MODES} for each of the {len(self.positions)} "
                             f"views, got {self.capture!r}")
        legs = self.leg_speed_m_s
        if legs is not None and (np.shape(legs) != (max(len(self.positions) - 1, 0),)
                                 or not np.all(np.isfinite(legs) & (np.asarray(legs) > 0))):
            raise ValueError(f"leg_speed_m_s must give a finite speed > 0 for each of the {len(self.positions) - 1} "
                             f"legs, got {legs!r}")

    def leg_speeds(self) -> np.ndarray:
        """(n - 1,) m/s: the cruise speed of each leg (:attr:`leg_speed_m_s`, else ``speed_m_s``)."""
        if self.leg_speed_m_s is not None:
            return np.asarray(self.leg_speed_m_s, dtype=float)
        return np.full(max(len(self) - 1, 0), float(self.speed_m_s))

    def with_leg_speeds(self, speeds: np.ndarray) -> FlightPath:
        """This path with the legs' cruise speeds ``speeds`` (n - 1,) m/s (None kept where every leg flies at
        ``speed_m_s``)."""
        speeds = np.asarray(speeds, dtype=float)
        return replace(self, leg_speed_m_s=None if np.all(speeds == self.speed_m_s) else speeds)

    def __len__(self) -> int:
        return int(self.positions.shape[0])

    @property
    def segment_lengths_m(self) -> np.ndarray:
        """(n - 1,) straight-line lengths between consecutive views."""
        return np.linalg.norm(np.diff(self.positions, axis=0), axis=1)

    @property
    def length_m(self) -> float:
        return float(self.segment_lengths_m.sum())

    @property
    def flight_time_s(self) -> float:
        """Cruise time at the legs' speeds plus one dwell per photo."""
        if self.leg_speed_m_s is None:      # one speed: the same float as it always was
            return self.length_m / self.speed_m_s + self.dwell_s * len(self)
        return float((self.segment_lengths_m / self.leg_speeds()).sum()) + self.dwell_s * len(self)

    def stops(self, mission_mode: str) -> np.ndarray:
        """(n,) bool: the views shot stop-and-shoot when the mission's capture mode is ``mission_mode`` (``stop``
        or ``fly-through``; :attr:`capture` overrides it per view)."""
        if mission_mode not in CAPTURE_MODES:
            raise ValueError(f"capture mode {mission_mode!r} is not one of {CAPTURE_MODES}")
        modes = self.capture if self.capture is not None else (mission_mode,) * len(self)
        return np.array([mode == CAPTURE_MODES[0] for mode in modes], dtype=bool)

    def with_stops(self, stop: np.ndarray, mission_mode: str) -> FlightPath:
        """This path with the views of the (n,) bool mask ``stop`` shot stop-and-shoot and the others flown
        through, as per-view modes (:attr:`capture`); None when they all follow ``mission_mode``."""
        stop = np.asarray(stop, dtype=bool)
        if stop.shape != (len(self),):
            raise ValueError(f"stop must be ({len(self)},) bool, got shape {stop.shape}")
        capture = tuple(CAPTURE_MODES[0] if s else CAPTURE_MODES[1] for s in stop.tolist())
        return replace(self, capture=None if set(capture) == {mission_mode} else capture)

    def view_ids(self) -> np.ndarray:
        """(n,) int: the plan's viewpoint of each view (:attr:`view_id`, or 0 .. n - 1)."""
        return np.arange(len(self)) if self.view_id is None else np.asarray(self.view_id, dtype=int)

    def view_ids_of(self, views: np.ndarray) -> np.ndarray | None:
        """The plan's viewpoints (m,) of ``views`` (m,) int or bool mask, None for a path in plan order (what a
        capture set of those views carries as its ``view_id``)."""
        return None if self.view_id is None else self.view_ids()[views]

    def reversed(self) -> FlightPath:
        """The same tour flown the other way round: the same viewpoints, legs and transition views, each view
        keeping its :attr:`view_id`; the sorties renumbered in flying order."""
        order = np.arange(len(self))[::-1]
        sortie = np.asarray(self.sortie)[order]
        view_id = self.view_ids()[order]
        in_plan_order = bool(np.all(view_id == np.arange(len(self))))
        return replace(self, positions=np.asarray(self.positions)[order], yaw=np.asarray(self.yaw)[order],
                       capture=None if self.capture is None else self.capture[::-1],
                       leg_speed_m_s=None if self.leg_speed_m_s is None else np.asarray(self.leg_speed_m_s)[::-1],
                       pitch=np.asarray(self.pitch)[order], face_id=np.asarray(self.face_id)[order],
                       kind=np.asarray(self.kind)[order], sortie=sortie.max(initial=0) - sortie + sortie.min(initial=0),
                       view_id=None if in_plan_order else view_id,
                       metadata={**self.metadata, "reversed": not self.metadata.get("reversed", False)})

    def redrawn(self, noise_draw: int) -> FlightPath:
        """The same mission meeting draw ``noise_draw`` (>= 0) of its flights' own errors (:attr:`noise_draw`)."""
        if noise_draw < 0:
            raise ValueError(f"noise_draw must be >= 0, got {noise_draw}")
        return replace(self, noise_draw=int(noise_draw))

    def to_json_dict(self) -> dict:
        doc = self._json_dict()
        # written only when set: a path in plan order meeting its own errors (noise_draw 0) keeps its document
        # and its digest
        if self.view_id is not None:
            for viewpoint, view in zip(doc["viewpoints"], self.view_ids().tolist(), strict=True):
                viewpoint["view_id"] = view
        if self.noise_draw:
            doc["noise_draw"] = self.noise_draw
        if self.capture is not None:
            for viewpoint, mode in zip(doc["viewpoints"], self.capture, strict=True):
                viewpoint["capture"] = mode
        if self.leg_speed_m_s is not None:
            for viewpoint, speed in zip(doc["viewpoints"], self.leg_speeds().tolist(), strict=False):
                viewpoint["leg_speed_m_s"] = speed
        return doc

    def _json_dict(self) -> dict:
        return {
            "format_version": PATH_FORMAT_VERSION,
            "method": self.method,
            "speed_m_s": self.speed_m_s,
            "dwell_s": self.dwell_s,
            "camera": {"focal_mm": self.camera.focal_mm, "sensor_width_mm": self.camera.sensor_width_mm,
                       "image_width_px": self.camera.image_width_px,
                       "image_height_px": self.camera.image_height_px},
            "length_m": self.length_m,
            "flight_time_s": self.flight_time_s,
            "metadata": self.metadata,
            "viewpoints": [
                {"index": i,
                 "x_m": float(p[0]), "y_m": float(p[1]), "z_m": float(p[2]),
                 "yaw_deg": float(np.degrees(y)), "gimbal_pitch_deg": float(np.degrees(q)),
                 "face_id": int(f), "kind": KIND_NAMES[int(k)], "sortie": int(s)}
                for i, (p, y, q, f, k, s) in enumerate(zip(self.positions, self.yaw, self.pitch,
                                                            self.face_id, self.kind, self.sortie, strict=True))
            ],
        }

    def save(self, file: str | Path) -> None:
        """Write path.json atomically (:func:`wrp_eval.atomic.write_text_atomic`)."""
        write_text_atomic(file, json.dumps(self.to_json_dict(), indent=1))

    def digest(self) -> str:
        """16-hex content hash of what a flight depends on (viewpoints and their ids, camera, speed, dwell, the noise
        draw): the key that ties a campaign, a surrogate checkpoint and a WRP to the path they were made for."""
        return digest_of_document(self.to_json_dict())

    @classmethod
    def load(cls, file: str | Path) -> "FlightPath":
        """Read a path.json; anything malformed is an :class:`InputError` naming the file."""
        file = Path(file)
        try:
            doc = json.loads(file.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise InputError(file, "no such path file") from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
            raise InputError(file, f"not a readable JSON path file: {err}") from None
        return cls.from_json_dict(doc, source=file)

    @classmethod
    def from_json_dict(cls, doc: dict, source: str | Path = "path") -> "FlightPath":
        """The path of a path.json document (as :meth:`to_json_dict` writes it); anything malformed is an
        :class:`InputError` naming ``source``."""
        try:
            if not isinstance(doc, dict):
                raise ValueError("the document is not a JSON object")
            if doc.get("format_version") != PATH_FORMAT_VERSION:
                raise ValueError(f"format_version {doc.get('format_version')!r} is not {PATH_FORMAT_VERSION}")
            vps = doc["viewpoints"]
            if not isinstance(vps, list) or not vps:
                raise ValueError("'viewpoints' must be a non-empty list")
            positions = np.array([[v["x_m"], v["y_m"], v["z_m"]] for v in vps], dtype=float)
            yaw = np.radians(np.array([v["yaw_deg"] for v in vps], dtype=float))
            pitch = np.radians(np.array([v["gimbal_pitch_deg"] for v in vps], dtype=float))
            face_id = np.array([v["face_id"] for v in vps], dtype=int)
            kind = np.array([KIND_NAMES.index(v["kind"]) for v in vps], dtype=int)
            sortie = np.array([v["sortie"] for v in vps], dtype=int)
            cam = doc["camera"]
            camera = Camera(float(cam["focal_mm"]), float(cam["sensor_width_mm"]),
                            int(cam["image_width_px"]), int(cam["image_height_px"]))
            speed, dwell = float(doc["speed_m_s"]), float(doc["dwell_s"])
            view_id = _view_ids(vps)
            noise_draw = int(doc.get("noise_draw", 0))
            capture = _capture_modes(vps)
            leg_speed = _leg_speeds(vps)
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            what = f"missing field {err}" if isinstance(err, KeyError) else str(err)
            raise InputError(source, f"bad path file: {what}") from None
        if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(yaw)) and np.all(np.isfinite(pitch))):
            raise InputError(source, "bad path file: non-finite viewpoint coordinates")
        if speed <= 0 or dwell < 0 or noise_draw < 0:
            raise InputError(source, "bad path file: speed_m_s must be > 0, dwell_s and noise_draw >= 0")
        return cls(positions, yaw, pitch, face_id, kind, sortie, camera, speed, dwell,
                   str(doc.get("method", "ours")), dict(doc.get("metadata", {})), view_id, noise_draw, capture,
                   leg_speed)


def _every_or_none(viewpoints: list, key: str, last: bool = True) -> tuple[list | None, bool]:
    """(the viewpoints' ``key`` values, those of all but the last when not ``last``; whether exactly those
    viewpoints give one), or (None, True) when no viewpoint gives one. A missing value is None."""
    have = [key in v for v in viewpoints]
    if not any(have):
        return None, True
    complete = all(have) if last else all(have[:-1]) and not have[-1]
    return [v.get(key) for v in (viewpoints if last else viewpoints[:-1])], complete


def _leg_speeds(viewpoints: list) -> np.ndarray | None:
    """The legs' ``leg_speed_m_s`` (n - 1,) m/s, given on every viewpoint but the last (finite, > 0), or None
    when no viewpoint gives one."""
    values, complete = _every_or_none(viewpoints, "leg_speed_m_s", last=False)
    if values is None:
        return None
    speeds = np.array(values, dtype=float)
    if not complete or not np.all(np.isfinite(speeds) & (speeds > 0)):
        raise ValueError("'leg_speed_m_s' must be > 0 on every viewpoint but the last (the leg leaving it) or on "
                         "none")
    return speeds


def _capture_modes(viewpoints: list) -> tuple[str, ...] | None:
    """The viewpoints' ``capture`` modes (every viewpoint has one of :data:`CAPTURE_MODES`), or None when none has
    one."""
    values, complete = _every_or_none(viewpoints, "capture")
    if values is None:
        return None
    if not complete or not set(values) <= set(CAPTURE_MODES):
        raise ValueError(f"'capture' must be one of {list(CAPTURE_MODES)} for every viewpoint or none")
    return tuple(values)


def _view_ids(viewpoints: list) -> np.ndarray | None:
    """The viewpoints' ``view_id`` (n,) int (every viewpoint has one, distinct), or None when none has one."""
    values, complete = _every_or_none(viewpoints, "view_id")
    if values is None:
        return None
    ids = np.array(values if complete else [], dtype=int)
    if ids.size != len(viewpoints) or ids.min() < 0 or np.unique(ids).size != ids.size:
        raise ValueError("'view_id' must be given for every viewpoint or none, distinct and >= 0")
    return ids


def digest_of_document(doc: dict) -> str:
    """16-hex content hash of a path.json document's flight-relevant fields (viewpoints with their view ids,
    camera, speed, dwell, the noise draw where set). A stored file's own document may differ in the last float
    digit from a reloaded path's :meth:`FlightPath.to_json_dict` after a round trip through degrees, so callers
    matching a file hash both."""
    key = {k: doc[k] for k in ("viewpoints", "camera", "speed_m_s", "dwell_s", "noise_draw") if k in doc}
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]
