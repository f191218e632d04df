"""Per-view inputs of the surrogate beyond the four offsets.

The error of a path is not a function of its offsets alone: the same 1 m pushes a view off a patch only it
covers, or along a face twenty others see. Each viewpoint i therefore carries, besides (dx, dy, dz, dyaw):

* **flown geometry** (:data:`GEOMETRY_NAMES`, computed from the offsets, so the optimiser's candidates get
  them too): the standoff (m) from the flown camera to the centroid of what the planned view sees, the
  incidence (rad) of that sight line on the patch's mean normal, and the pointing error (rad) between the flown
  optical axis and the sight line (how far the patch moves off the image centre);
* **conditions at the shutter** (:data:`CONDITION_NAMES`, from the flight: motion blur px and the wind felt
  at the view, m/s, ship frame; and whether the view was taken at all: a flight that turned home leaves the
  rest of the tour, and those trials teach the network what each view's coverage is worth); the optimiser,
  which cannot know a future flight's, queries with the campaign's per-view mean blur and wind (the
  forecast's expectation, :attr:`ViewContext.condition_reference`) and every view taken;
* **coverage** (:data:`COVERAGE_NAMES`, of the planned path, from the oracle's observation model,
  :func:`wrp_eval.recon.coverage.view_coverage`): the view's unique-coverage share and its co-visible
  partner count;
* with the ``scarce`` input set, **scarce coverage lost** (:data:`SCARCE_NAMES`, computed from the offsets like
  the geometry, so every candidate gets its own): what the view flown at its offset takes away from the planned
  set's scarce coverage, the rest of the set held (:class:`wrp_eval.surrogate.scarce.ScarceCoverage`). It needs the
  ship and the oracle, which the checkpoint does not hold: whoever loads such a surrogate passes them in.

The network keeps the viewpoint order of the path (its convolution mixes path neighbours); the co-visibility
graph enters through the partner count and unique share (see README: measured against offsets-only inputs).
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np

from wrp_eval.camera import optical_axes
from wrp_eval.recon.capture_io import captures_from_path

if TYPE_CHECKING:
    from wrp_eval.surrogate.scarce import ScarceCoverage

GEOMETRY_NAMES = ("standoff_m", "incidence_rad", "pointing_rad")
CONDITION_NAMES = ("blur_px", "wind_x_mps", "wind_y_mps", "wind_z_mps", "taken")
COVERAGE_NAMES = ("unique_share", "partners")
SCARCE_NAMES = ("scarce_lost",)
# "offsets": the 4 offsets + planned pose only (the earlier model); "scarce": per_view + SCARCE_NAMES
INPUT_SETS = ("per_view", "offsets", "scarce")


def moving_features(context: ViewContext, scarce: ScarceCoverage | None, offsets: np.ndarray,
                    views: np.ndarray | slice | list[int] = slice(None),
                    taken: np.ndarray | None = None) -> np.ndarray:
    """(..., k, m) the channels computed from offsets (..., k, 4) of the viewpoints ``views`` (k of them), in the
    order :func:`moving_names` gives: the flown geometry, then with ``scarce`` the scarce coverage lost, which for a
    view not ``taken`` ((..., k) bool; None: every view taken) is the view's whole share (its ``removal``);
    unstandardised. The one layout the training statistics and every query share."""
    geometry = context.geometry(offsets, views=views)
    if scarce is None:
        return geometry
    lost = scarce.lost_views(offsets, views)
    if taken is not None:
        lost = np.where(taken, lost, scarce.removal[np.arange(len(scarce))[views]])
    return np.concatenate([geometry, lost[..., None]], axis=-1)


def moving_names(inputs: str) -> tuple[str, ...]:
    """The per-view channels besides the offsets that a candidate move changes, in input order."""
    if inputs == "offsets":
        return ()
    return GEOMETRY_NAMES + (SCARCE_NAMES if inputs == "scarce" else ())


@dataclass(frozen=True)
class ViewContext:
    """The per-view facts of one path (n views): planned position (n, 3) m, yaw (n,) rad, pitch (n,) rad; the
    planned view's target centroid (n, 3) m and unit normal (n, 3); unique_share (n,), partners (n,); and
    condition_reference (n, 5): blur px and wind m/s at each view in the forecast (the campaign's mean), and
    taken (1)."""

    position: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    target: np.ndarray
    normal: np.ndarray
    unique_share: np.ndarray
    partners: np.ndarray
    condition_reference: np.ndarray

    def __len__(self) -> int:
        return int(np.asarray(self.position).shape[0])

    def coverage(self) -> np.ndarray:
        """(n, 2) unique share, partner count."""
        return np.column_stack([self.unique_share, self.partners]).astype(float)

    def geometry(self, offsets: np.ndarray, views: np.ndarray | slice | list[int] = slice(None)) -> np.ndarray:
        """(..., k, 3) flown geometry of offsets (..., k, 4) of the viewpoints ``views`` (k of them)."""
        return flown_geometry(np.asarray(self.position)[views], np.asarray(self.yaw)[views],
                              np.asarray(self.pitch)[views], np.asarray(self.target)[views],
                              np.asarray(self.normal)[views], offsets)

    def to_json_dict(self) -> dict:
        return {k: np.asarray(v, float).tolist() for k, v in asdict(self).items()}

    @classmethod
    def from_json_dict(cls, doc: dict) -> "ViewContext":
        return cls(**{k: np.asarray(doc[k], float) for k in cls.__dataclass_fields__})


def flown_geometry(position: np.ndarray, yaw: np.ndarray, pitch: np.ndarray, target: np.ndarray,
                   normal: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Standoff (m), incidence (rad) and pointing error (rad) of views flown at planned + ``offsets``.

    position (k, 3), yaw (k,), pitch (k,), target (k, 3), normal (k, 3): the planned views and what they see;
    offsets (..., k, 4) (dx, dy, dz m, dyaw rad). Returns (..., k, 3). The gimbal holds the planned pitch.
    """
    off = np.asarray(offsets, dtype=float)
    flown = np.asarray(position, float) + off[..., :3]
    sight = np.asarray(target, float) - flown
    standoff = np.linalg.norm(sight, axis=-1)
    unit = sight / np.maximum(standoff, 1e-9)[..., None]
    cos_inc = np.abs(np.sum(unit * np.asarray(normal, float), axis=-1))
    axis = optical_axes(np.asarray(yaw, float) + off[..., 3], np.broadcast_to(pitch, off.shape[:-1]))
    cos_point = np.sum(unit * axis, axis=-1)
    return np.stack([standoff, np.arccos(np.clip(cos_inc, 0.0, 1.0)), np.arccos(np.clip(cos_point, -1.0, 1.0))],
                    axis=-1)


def reference_conditions(conditions: np.ndarray | None, n_views: int) -> np.ndarray:
    """(n, 5) the forecast's conditions at each view: the mean blur and wind of ``conditions`` (trials, n, 5) over
    the trials that took the view (0 without any), and the view taken."""
    reference = np.zeros((n_views, len(CONDITION_NAMES)))
    if conditions is not None:
        cond = np.asarray(conditions, float)[..., :-1]
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)      # a view no trial took: mean of nothing
            reference[:, :-1] = np.nan_to_num(np.nanmean(cond, axis=0))
    reference[:, -1] = 1.0
    return reference


def conditions_or_reference(conditions: np.ndarray | None, reference: np.ndarray, batch: int) -> np.ndarray:
    """(batch, n, 5) ``conditions`` (None, or (batch, n, 5) with NaN where not recorded) with the forecast
    ``reference`` (n, 5) in every gap."""
    ref = np.broadcast_to(reference, (batch, *np.shape(reference)))
    if conditions is None:
        return ref
    cond = np.asarray(conditions, float).reshape(ref.shape)
    return np.where(np.isfinite(cond), cond, ref)


def campaign_view_context(scored_ship, path, conditions: np.ndarray | None) -> ViewContext:
    """The :class:`ViewContext` of ``path`` (a :class:`wrp_eval.planning.path.FlightPath`) on ``scored_ship``
    (:class:`wrp_eval.recon.scored_ship.ScoredShip`), with the per-view mean of ``conditions`` (trials, n, 5) as the
    reference (zeros without)."""
    cover = scored_ship.coverage(captures_from_path(path))
    reference = reference_conditions(conditions, len(path))
    return ViewContext(np.asarray(path.positions, float), np.asarray(path.yaw, float), np.asarray(path.pitch, float),
                       cover.target, cover.normal, cover.unique_share, cover.partners, reference)
