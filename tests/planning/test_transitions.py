import numpy as np
import pytest

from wrp_eval.planning.path import KIND_TRANSITION
from wrp_eval.planning.transitions import best_chain, proxy_axis_targets
from wrp_eval.planning.visibility import ProxyRaycaster, overlap_ratio, visibility


def test_best_chain_hand_case():
    # A, c1, c2, B along a segment: A-B 0.1 (too little), A-c1 0.9 (redundant), A-c2 0.5, c2-B 0.6
    ov = np.array([[1.0, 0.9, 0.5, 0.1],
                   [0.9, 1.0, 0.7, 0.3],
                   [0.5, 0.7, 1.0, 0.6],
                   [0.1, 0.3, 0.6, 1.0]])
    assert best_chain(ov, 0.4, 0.8) == ([2], 0)
    assert best_chain(np.array([[1, 0.95], [0.95, 1]]), 0.4, 0.8) == ([], 0)   # surface pair: no t_max
    assert best_chain(np.array([[1, 0.1, 0.0], [0.1, 1, 0.1], [0.0, 0.1, 1]]), 0.4, 0.8)[1] == 1


def test_axis_targets(stylized_proxy):
    t = proxy_axis_targets(stylized_proxy, np.array([[100.0, 30, 50], [10.0, -40, 0]]))
    np.testing.assert_allclose(t, [[70.0, 0, 12.5], [10.0, 0, 12.5]])


@pytest.mark.parametrize("ship", ["stylized", "cruise"])
def test_osmc_holds_on_every_transition_pair(plans, proxies, ship):
    r = plans[(ship, "ours")]
    path, proxy = r.path, proxies[ship]
    assert r.metrics["osmc_violations"] == 0
    trans = np.flatnonzero(path.kind == KIND_TRANSITION)
    assert trans.size > 0
    rad = np.array([r.metrics["per_face"][n]["radius_m"] for n in proxy.face_names])
    obs = visibility(r.samples.points, r.samples.normals, path.positions, path.yaw, path.pitch, path.camera,
                     ProxyRaycaster(proxy), r.metrics["d_max_m"], np.radians(85.0))
    weights = rad[r.samples.face] ** 2
    pairs = sorted({(i - 1, i) for i in trans if i > 0} | {(i, i + 1) for i in trans if i + 1 < len(path)})
    ov = overlap_ratio(obs[[p[0] for p in pairs]], obs[[p[1] for p in pairs]], weights)
    assert np.all(ov >= 0.4 - 1e-9) and np.all(ov <= 0.8 + 1e-9), ov


def test_zhou2020_has_no_transition_views(plans):
    for ship in ("stylized", "cruise"):
        assert not np.any(plans[(ship, "zhou2020")].path.kind == KIND_TRANSITION)
