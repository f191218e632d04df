"""The flyable path: ordered viewpoints, the value type planning hands to the simulator and the exporters.

Inside the code angles are radians; ``path.json`` stores degrees (the edge of the system).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wrp_eval.atomic import write_text_atomic
from wrp_eval.camera import Camera
from wrp_eval.errors import InputError

KIND_SURFACE = 0
KIND_TRANSITION = 1
KIND_NAMES = ("surface", "transition")
PATH_FORMAT_VERSION = 1


@dataclass(frozen=True)
class FlightPath:
    """Ordered viewpoints of one tour.

    positions (n, 3) m in the ship frame; yaw (n,) rad; pitch (n,) rad (gimbal, negative looks down);
    face_id (n,) int, the proxy face a view photographs (-1 for transition views between faces);
    kind (n,) int, KIND_SURFACE or KIND_TRANSITION; sortie (n,) int, the battery sortie of each view.
    speed_m_s: cruise speed between views; dwell_s: hover time per photo.
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
        """Cruise time at ``speed_m_s`` plus one dwell per photo."""
        return self.length_m / self.speed_m_s + self.dwell_s * len(self)

    def to_json_dict(self) -> dict:
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
        """16-hex content hash of what a flight depends on (viewpoints, camera, speed, dwell): the key that
        ties a campaign, a surrogate checkpoint and a WRP to the path they were made for."""
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
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            what = f"missing field {err}" if isinstance(err, KeyError) else str(err)
            raise InputError(source, f"bad path file: {what}") from None
        if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(yaw)) and np.all(np.isfinite(pitch))):
            raise InputError(source, "bad path file: non-finite viewpoint coordinates")
        if speed <= 0 or dwell < 0:
            raise InputError(source, "bad path file: speed_m_s must be > 0 and dwell_s >= 0")
        return cls(positions, yaw, pitch, face_id, kind, sortie, camera, speed, dwell,
                   str(doc.get("method", "ours")), dict(doc.get("metadata", {})))


def digest_of_document(doc: dict) -> str:
    """16-hex content hash of a path.json document's flight-relevant fields (viewpoints, camera, speed,
    dwell). A stored file's own document may differ in the last float digit from a reloaded path's
    :meth:`FlightPath.to_json_dict` after a round trip through degrees, so callers matching a file hash both."""
    key = {k: doc[k] for k in ("viewpoints", "camera", "speed_m_s", "dwell_s")}
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]
