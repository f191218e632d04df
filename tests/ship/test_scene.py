import mujoco
import numpy as np
import trimesh

from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.meshes import procedural_mesh
from wrp_eval.ship.particulars import ShipType
from wrp_eval.ship.resolve import resolve_particulars
from wrp_eval.ship.scene import build_scene, compile_scene


def test_scene_compiles_with_sea_and_static_ship():
    mesh = procedural_mesh(resolve_particulars(ShipSection(type=ShipType.FISHING))[0])
    root = build_scene(mesh)
    model = compile_scene(root)
    assert model.nmesh == 1 and model.nbody == 2 and model.njnt == 0
    sea = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "sea")
    ship = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ship_hull")
    assert model.geom_type[sea] == mujoco.mjtGeom.mjGEOM_PLANE
    assert model.geom_type[ship] == mujoco.mjtGeom.mjGEOM_MESH
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    # a ray straight down from above the mast hits the ship, one beside the hull hits the sea at z = 0
    geomid = np.zeros(1, dtype=np.int32)
    top = mesh.bounds[1, 2]
    bridge = mesh.triangles_center[np.argmax(mesh.triangles_center[:, 2])]   # on the mast's top cap
    dist = mujoco.mj_ray(model, data, np.array([bridge[0], bridge[1], top + 10]), np.array([0, 0, -1.0]),
                         None, 1, -1, geomid)
    assert geomid[0] == ship and np.isclose(dist, 10.0)
    dist = mujoco.mj_ray(model, data, np.array([0, 30.0, 50.0]), np.array([0, 0, -1.0]), None, 1, -1, geomid)
    assert geomid[0] == sea and np.isclose(dist, 50.0)


def test_scene_accepts_attachments():
    root = build_scene(trimesh.creation.box(extents=(10, 4, 4)))
    body = root.worldbody.add("body", name="drone", pos=(0, 0, 20))
    body.add("freejoint")
    body.add("geom", type="box", size=(0.2, 0.2, 0.05), mass=1.4)
    model = compile_scene(root)
    assert model.nbody == 3 and model.njnt == 1


def test_every_procedural_ship_compiles():
    for ship_type in ShipType:
        mesh = procedural_mesh(resolve_particulars(ShipSection(type=ship_type))[0])
        model = compile_scene(build_scene(mesh))
        # MuJoCo keeps every distinct vertex of the STL (it merges only exact duplicates)
        assert model.nmesh == 1
        assert model.mesh_vertnum[0] == len(np.unique(np.asarray(mesh.vertices, np.float32), axis=0))
