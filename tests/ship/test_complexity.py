import numpy as np
import pytest
import trimesh

from wrp_eval.ship.complexity import assign_triangles, mesh_surface_complexity, surface_complexity
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import build_proxy

# proxy 40 x 10 x 10 m: areas bow/stern 100, port/starboard 400, top 400
PROXY = build_proxy(ShipParticulars(length_bp_m=40.0, breadth_m=10.0, depth_m=6.0,
                                    superstructure_height_m=6.0, draft_m=2.0))


def test_proxy_areas_used_by_the_tests():
    assert np.allclose(PROXY.areas, [100, 100, 400, 400, 400])


def test_hand_counted_normals():
    s = np.sqrt(0.5)
    normals = np.array([[1, 0, 0], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1],
                        [s, 0, s],                  # exactly 45 deg from bow and top: counted once (eq. 2: <=)
                        [0.5, 0.5, -np.sqrt(0.5)],  # 60 deg from bow/port: not counted
                        [0, 0, -1],                 # facing down: the bottom is excluded, not counted
                        [0, 0, 0]])                 # degenerate: no normal
    assigned = assign_triangles(normals, PROXY)
    assert assigned.tolist()[:6] == [0, 0, 1, 2, 3, 4]
    assert assigned[6] in (0, 4) and assigned[7] == -1 and assigned[8] == -1 and assigned[9] == -1
    comp = surface_complexity(normals, PROXY)
    assert comp.counts.sum() == 7
    # eq. (3): count / area, not Alg. 1 line 10's running division
    assert comp.complexity[2] == pytest.approx(1 / 400) and comp.complexity[1] == pytest.approx(1 / 100)


def test_subdivided_box_ordering():
    # a box of the proxy's size whose +x face (bow) is subdivided 4 times: 2 * 4^4 = 512 triangles
    box = trimesh.creation.box(extents=(40, 10, 10))
    box.apply_translation((0, 0, 5))
    bow = box.face_normals[:, 0] > 0.9
    bow_mesh = box.submesh([np.flatnonzero(bow)], append=True)
    for _ in range(4):
        bow_mesh = bow_mesh.subdivide()
    rest = box.submesh([np.flatnonzero(~bow)], append=True)
    mesh = trimesh.util.concatenate([bow_mesh, rest])
    comp = mesh_surface_complexity(mesh, PROXY)
    assert comp.counts.tolist() == [512, 2, 2, 2, 2]   # the 2 bottom triangles are not counted
    assert np.allclose(comp.complexity, [5.12, 0.02, 0.005, 0.005, 0.005])
    assert np.argmax(comp.complexity) == 0
    # triangles below the waterline do not count
    lowered = mesh.copy()
    lowered.apply_translation((0, 0, -20))
    assert mesh_surface_complexity(lowered, PROXY).counts.sum() == 0


def test_rotation_of_the_mesh_moves_the_counts():
    normals = np.tile([[1.0, 0.0, 0.0]], (10, 1))
    rot = trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1])[:3, :3]
    assert surface_complexity(normals, PROXY).counts.tolist() == [10, 0, 0, 0, 0]
    assert surface_complexity(normals @ rot.T, PROXY).counts.tolist() == [0, 0, 10, 0, 0]
