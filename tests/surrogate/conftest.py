"""Shared fixtures: trial data from a known function, a small trained surrogate, a ring's scarce coverage."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import trimesh

from wrp_eval.camera import Camera, yaw_pitch_towards
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.oracle import prepare_ground_truth
from wrp_eval.sim.captures import CaptureSet
from wrp_eval.surrogate.config import SurrogateSection
from wrp_eval.surrogate.data import known_function_trials
from wrp_eval.surrogate.features import ViewContext
from wrp_eval.surrogate.model import Surrogate, SurrogateMeta, ViewSequenceCNN
from wrp_eval.surrogate.scarce import ScarceCoverage, scarce_coverage

torch.set_num_threads(1)

N_VIEWS = 8
N_RING = 9


@pytest.fixture(scope="session")
def known_data():
    """600 trials of 8 viewpoints from the known quadratic function (noise 0.005 m) and its parameters."""
    return known_function_trials(600, N_VIEWS, np.random.default_rng(42), noise_m=0.005)


@pytest.fixture(scope="session")
def fast_section():
    return SurrogateSection(epochs=300, patience=40, batch_size=32, lr=3e-3, channels=32, kernel=3, hidden=64)


@pytest.fixture(scope="session")
def trained(known_data, fast_section):
    from wrp_eval.surrogate.train import train_surrogate
    data, _ = known_data
    return train_surrogate(data, fast_section, seed=3)


def random_views(n_views: int, rng: np.random.Generator) -> ViewContext:
    """Views on a ring of radius ~60 m looking in at patches ~20 m from the centre, random coverage and forecast."""
    angle = np.linspace(0, 2 * np.pi, n_views, endpoint=False)
    ring = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(n_views)])
    position = 60 * ring + [0, 0, 20]
    target = 20 * ring + rng.normal(0, 2, (n_views, 3))
    return ViewContext(position, angle + np.pi, np.full(n_views, -0.2), target, ring,
                       rng.uniform(0, 1, n_views), rng.integers(0, 8, n_views).astype(float),
                       np.column_stack([rng.normal(0, 3, (n_views, 4)), np.ones(n_views)]))


def random_surrogate(n_views: int, channels: int = 8, kernel: int = 3, layers: int = 2, seed: int = 0,
                     pose: bool = True, digest: str | None = None, per_view: bool = False,
                     scarce: ScarceCoverage | None = None) -> Surrogate:
    """An untrained network with non-trivial standardisation (for exactness and checkpoint tests); ``per_view``:
    the per-view input set with random views; ``scarce``: the scarce input set on that coverage (per_view
    implied)."""
    rng = np.random.default_rng(seed)
    per_view = per_view or scarce is not None
    n_feat = 11 if scarce is not None else 10
    arch = {"in_channels": (11 if pose else 4) + (n_feat if per_view else 0), "channels": channels,
            "kernel": kernel, "layers": layers, "hidden": 16, "outputs": 1}
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        net = ViewSequenceCNN(**arch)
    planned = rng.normal(size=(n_views, 7))
    meta = SurrogateMeta(n_views=n_views, path_digest=digest, architecture=arch,
                         offset_mean=rng.normal(0, 0.1, 4).tolist(), offset_std=rng.uniform(0.5, 2, 4).tolist(),
                         error_mean=0.7, error_std=0.2,
                         pose_mean=planned.mean(0).tolist() if pose else None,
                         pose_std=planned.std(0).tolist() if pose else None,
                         planned_pose=planned.tolist() if pose else None,
                         offset_low=[-2, -2, -2, -0.35], offset_high=[2, 2, 2, 0.35],
                         **({"inputs": "scarce" if scarce is not None else "per_view",
                             "views": random_views(n_views, rng).to_json_dict(),
                             "feature_mean": rng.normal(0, 1, n_feat).tolist(),
                             "feature_std": rng.uniform(0.2, 3, n_feat).tolist(),
                             "scarce_digest": None if scarce is None else scarce.digest} if per_view else {}))
    return Surrogate(net, meta, scarce)


def ring_mesh() -> trimesh.Trimesh:
    """A 30 m hull with a deckhouse standing on its deck (keel below the water)."""
    hull = trimesh.creation.box(extents=(30.0, 8.0, 6.0))
    hull.apply_translation((0.0, 0.0, 1.0))
    house = trimesh.creation.box(extents=(6.0, 6.0, 5.0))
    house.apply_translation((-8.0, 0.0, 6.5))
    return trimesh.util.concatenate([hull, house])


def ring_views(n: int, radius: float = 22.0) -> CaptureSet:
    """``n`` views on a ring of ``radius`` around :func:`ring_mesh`, at 3 and 9 m alternately, looking at its middle."""
    angle = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    pos = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.where(np.arange(n) % 2, 9.0, 3.0)])
    yaw, pitch = yaw_pitch_towards(pos, np.tile([0.0, 0.0, 3.0], (n, 1)))
    return CaptureSet(pos, yaw, pitch, np.arange(n), Camera())


@pytest.fixture(scope="session")
def ring_scarce() -> ScarceCoverage:
    """The scarce coverage of 9 views on a ring around :func:`ring_mesh`."""
    mesh, section = ring_mesh(), OracleSection()
    gt = prepare_ground_truth(mesh, section.gt_density_per_m2, section.gt_seed)
    return scarce_coverage(ring_views(N_RING), mesh, section, gt)
