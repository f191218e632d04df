import numpy as np
import pytest
import trimesh

from wrp_eval.errors import InputError
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.meshes import cached_procedural_mesh, procedural_mesh, wigley_hull
from wrp_eval.ship.particulars import ShipType
from wrp_eval.ship.resolve import resolve_particulars
from wrp_eval.ship.user_mesh import check_mesh_against_particulars, load_user_mesh


def _particulars(t, **over):
    return resolve_particulars(ShipSection(type=t, particulars=over))[0]


def test_wigley_hull_volume_matches_the_formula():
    # Wigley: displacement 4/9 L B T; wall-sided part above water: 2/3 L B F (parabolic waterplane)
    hull = wigley_hull(100.0, 10.0, 6.0, 3.0, sections=96, levels=48)
    assert hull.is_watertight and hull.is_winding_consistent
    exact = 4 / 9 * 100 * 10 * 6 + 2 / 3 * 100 * 10 * 3
    assert hull.volume == pytest.approx(exact, rel=0.01)


@pytest.mark.parametrize("ship_type", list(ShipType))
def test_procedural_mesh_is_watertight_and_matches_particulars(ship_type):
    p = _particulars(ship_type)
    mesh = procedural_mesh(p)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    lo, hi = mesh.bounds
    assert hi[0] - lo[0] == pytest.approx(p.length_bp_m, rel=0.03)
    assert hi[1] - lo[1] == pytest.approx(p.breadth_m, rel=0.03)
    assert hi[2] == pytest.approx(p.height_above_water_m, rel=0.03)
    assert lo[2] == pytest.approx(-p.draft_m, rel=1e-6)   # keel at -draft, waterline z = 0
    check_mesh_against_particulars(mesh, p, "procedural", tolerance=0.03)


def test_types_differ_and_follow_the_particulars():
    small = procedural_mesh(_particulars(ShipType.CONTAINER, length_bp_m=200.0, breadth_m=32.0))
    large = procedural_mesh(_particulars(ShipType.CONTAINER))
    assert len(large.faces) > len(small.faces)     # more container bays
    assert small.bounds[1, 0] == pytest.approx(100.0)


def test_deterministic_and_cached(tmp_path):
    p = _particulars(ShipType.FISHING)
    a = procedural_mesh(p)
    b = procedural_mesh(p)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    first, path = cached_procedural_mesh(p, tmp_path)
    again, path2 = cached_procedural_mesh(p, tmp_path)
    assert path == path2 and path.exists() and path.parent == tmp_path
    assert np.array_equal(first.vertices, a.vertices) and np.array_equal(again.vertices, a.vertices)
    assert np.array_equal(again.faces, a.faces)
    other, path3 = cached_procedural_mesh(_particulars(ShipType.FISHING, length_bp_m=35.0), tmp_path)
    assert path3 != path


def _box_ship(tmp_path, name, transform=None):
    mesh = trimesh.creation.box(extents=(100.0, 16.0, 26.0))
    mesh.apply_translation((0, 0, 7.0))   # z from -6 to 20
    if transform is not None:
        mesh.apply_transform(transform)
    path = tmp_path / name
    mesh.export(path)
    return path


@pytest.mark.parametrize("name", ["ship.stl", "ship.obj", "ship.ply", "ship.glb"])
def test_user_mesh_formats(tmp_path, name):
    mesh = load_user_mesh(_box_ship(tmp_path, name))
    assert np.allclose(mesh.bounds, [[-50, -8, -6], [50, 8, 20]])


def test_user_mesh_scale_up_axis_offset(tmp_path):
    # stored in millimetres with y up: (x, y, z)_file = 1000 * (x, z, -y)_ship
    to_file = np.diag([1000.0, 1000.0, 1000.0, 1.0]) @ trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0])
    path = _box_ship(tmp_path, "mm_yup.stl", to_file)
    mesh = load_user_mesh(path, scale=0.001, up_axis="y", offset_m=(1.0, 0.0, -1.0))
    assert np.allclose(mesh.bounds, [[-49, -8, -7], [51, 8, 19]], atol=1e-6)
    p = _particulars(ShipType.STYLIZED, length_bp_m=100.0, breadth_m=16.0)
    check_mesh_against_particulars(mesh, p, path)   # 19 m vs 25 m is within 30 %


def test_user_mesh_refusals(tmp_path):
    p = _particulars(ShipType.STYLIZED)
    too_small = load_user_mesh(_box_ship(tmp_path, "s.stl"), scale=0.5)
    expected = r"length \(x extent\) is 50 m but the particulars say 140 m \(more than 30% off\)"
    with pytest.raises(InputError, match=expected):
        check_mesh_against_particulars(too_small, p, "s.stl")
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing\n")
    with pytest.raises(InputError, match="no triangles|cannot read"):
        load_user_mesh(empty)
    nan = tmp_path / "nan.obj"
    nan.write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    with pytest.raises(InputError, match="non-finite|no triangles"):
        load_user_mesh(nan)
    with pytest.raises(InputError, match="no such mesh file"):
        load_user_mesh(tmp_path / "missing.stl")
    with pytest.raises(InputError, match="unsupported mesh format"):
        load_user_mesh(tmp_path / "ship.dwg")
    garbage = tmp_path / "garbage.stl"
    garbage.write_bytes(b"\x00\x01 not a mesh")
    with pytest.raises(InputError):
        load_user_mesh(garbage)
