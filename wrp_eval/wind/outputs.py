"""Files made from a wind field: compressed npz arrays, the quiver figure of the mean field, rerun arrows.

Every writer goes through :func:`wrp_eval.atomic.atomic_path` (a temporary beside the target, fsync'ed and
renamed), so a reader never sees half a file and a failure leaves the previous file as it was.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

from wrp_eval.atomic import atomic_path
from wrp_eval.recording import recording


def save_npz_atomic(path: Path, **arrays: ArrayLike) -> None:
    """np.savez_compressed (no pickles), written atomically."""
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]  # mypy also matches ** to allow_pickle: bool


def quiver_png(path: Path, x: NDArray[np.float64], y: NDArray[np.float64], z: NDArray[np.float64],
               velocity: NDArray[np.float64], source: str) -> None:
    """Quiver plots of the mean field at its lowest, middle and top levels, as a PNG.

    x (nx,), y (ny,), z (nz,) m: ship-frame node axes; velocity (nx, ny, nz, 3) m/s; source: for the titles."""
    levels = sorted({0, len(z) // 2, len(z) - 1})
    fig = Figure(figsize=(5 * len(levels), 4.6))
    axes = fig.subplots(1, len(levels), squeeze=False)
    step = max(1, int(np.ceil(max(len(x), len(y)) / 25)))          # at most ~25 arrows per side
    speed = np.linalg.norm(velocity, axis=-1)
    # the fastest arrow spans ~90 % of the spacing between drawn arrows (readable whatever the speeds)
    spacing = step * (float(np.min(np.diff(x))) if len(x) > 1 else 1.0)
    arrow_scale = max(float(speed.max()), 1e-6) / (0.9 * spacing)
    for ax, k in zip(axes[0], levels, strict=True):
        sl = (slice(None, None, step), slice(None, None, step), k)
        q = ax.quiver(x[::step, None] * np.ones(len(y[::step])), np.ones(len(x[::step]))[:, None] * y[None, ::step],
                      velocity[sl][..., 0], velocity[sl][..., 1], speed[sl], cmap="viridis",
                      angles="xy", scale_units="xy", scale=arrow_scale)
        fig.colorbar(q, ax=ax, label="speed (m/s)")
        ax.plot([-5, 5], [0, 0], "r-", lw=3)
        ax.annotate("bow", (5, 0), color="r")
        ax.set_title(f"{source}: z = {z[k]:.0f} m")
        ax.set_xlabel("x along the ship (m)")
        ax.set_ylabel("y to port (m)")
        ax.set_aspect("equal")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")


def log_mean_field_rerun(path: Path, points: NDArray[np.float64], vectors: NDArray[np.float64],
                         fraction: float) -> None:
    """Arrows (``wind/mean``) at a regular subset of the nodes into a .rrd recording (the paper's Fig. 4
    shows 20 %). points, vectors (n, 3): node positions (m) and mean wind (m/s); fraction: share drawn."""
    every = max(1, int(round(1.0 / max(fraction, 1e-6))))
    keep = slice(None, None, every)
    speed = np.linalg.norm(vectors[keep], axis=1)
    t = (speed - speed.min()) / max(np.ptp(speed), 1e-9)
    colors = np.stack([255 * t, 80 + 0 * t, 255 * (1 - t)], 1).astype(np.uint8)
    with recording(path, application_id="wrp_eval_wind") as rec:
        rec.log("wind/mean", rr.Arrows3D(origins=points[keep], vectors=vectors[keep], colors=colors), static=True)
