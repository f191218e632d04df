"""Fixtures of the wrp tests: small untrained surrogates (the optimiser's logic does not need a good fit)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from wrp_eval.surrogate.model import Surrogate, SurrogateMeta, ViewSequenceCNN
from wrp_eval.wrp.config import WrpSection
from wrp_eval.wrp.optimize import WrpParams

torch.set_num_threads(1)


def small_surrogate(n_views: int = 6, seed: int = 0, error_std: float = 0.05, gain: float = 1.0) -> Surrogate:
    """A random network (channels 8, kernel 3, 2 layers) with pose channels; output scale error_std m; the
    first layer's offset weights multiplied by ``gain`` (a stronger dependence on the offsets)."""
    rng = np.random.default_rng(seed)
    arch = {"in_channels": 11, "channels": 8, "kernel": 3, "layers": 2, "hidden": 16, "outputs": 1}
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        net = ViewSequenceCNN(**arch)
        with torch.no_grad():
            net.convs[0].weight[:, :4] *= gain
    planned = rng.normal(size=(n_views, 7))
    meta = SurrogateMeta(n_views=n_views, path_digest=None, architecture=arch, offset_mean=[0, 0, 0, 0],
                         offset_std=[1.0, 1.0, 1.0, 0.2], error_mean=0.5, error_std=error_std,
                         pose_mean=planned.mean(0).tolist(), pose_std=planned.std(0).tolist(),
                         planned_pose=planned.tolist(), offset_low=[-1.5, -2, -2.5, -0.35],
                         offset_high=[2, 2, 2, 0.35])
    return Surrogate(net, meta)


@pytest.fixture
def surrogate():
    return small_surrogate()


def wrp_params(kind: str, threshold_m: float, e_original_m: float, sample_radius_m, *, step_m: float = 2.0,
               validated_error_m=None, neighbour_cholesky=None, base_positions=None, min_altitude_m: float = 0.0,
               no_fly_bounds=None, **settings) -> WrpParams:
    """The parameters of a ``wrp:`` section with ``settings`` (acceptance "paper", Alg. 3 as written, unless
    given) and these measured inputs."""
    return WrpParams.of(WrpSection(kind=kind, **{"acceptance": "paper", **settings}), threshold_m=threshold_m,
                        e_original_m=e_original_m, sample_radius_m=np.asarray(sample_radius_m, float), step_m=step_m,
                        validated_error_m=validated_error_m, neighbour_cholesky=neighbour_cholesky,
                        base_positions=base_positions, min_altitude_m=min_altitude_m, no_fly_bounds=no_fly_bounds)


def params_for(s: Surrogate, kind: str, threshold: float, **kw) -> WrpParams:
    e0 = float(s.predict(np.zeros((1, s.n_views, 4)))[0])
    base = dict(iterations=40, attitude_samples=5, neighbourhood_samples=4, step_m=1.5, block_iterations=8,
                stage2_batch=3)
    base.update(kw)
    return wrp_params(kind, threshold, e0, np.full(s.n_views, 0.4), **base)


def _surrogate_helpers():
    """tests/surrogate/helpers.py (make_path, make_campaign), loaded by file path: the test folders are not
    packages."""
    import importlib.util
    from pathlib import Path
    spec = importlib.util.spec_from_file_location(
        "wrp_eval_tests_surrogate_helpers", Path(__file__).parents[1] / "surrogate" / "helpers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


helpers = _surrogate_helpers()
