"""The compiled per-row kernels (wrp_eval/compiled.py): numpy's arithmetic semantics, and rows that never
depend on the batch they are computed in (what "same numbers on any batch size" rests on)."""

import numpy as np
import pytest

from wrp_eval.camera import camera_angles, camera_rotations
from wrp_eval.compiled import kernel, kernel_sources_digest
from wrp_eval.sim.aero import drag_force
from wrp_eval.sim.controller import GAIN_PRESETS, PositionController, quat_to_matrix
from wrp_eval.sim.vehicle import PHANTOM4
from wrp_eval.wind.air_wake import ShipAirWake
from wrp_eval.wind.grid import WindGrid, interpolate

BOX = np.array([[-70.0, -10.0, 0.0], [70.0, 10.0, 25.0]])


@kernel
def _ratio(a, b):
    return a / b


def test_a_kernel_divides_like_numpy_instead_of_raising():
    # numba's default error model raises ZeroDivisionError; the project's kernels must behave as the numpy
    # code they replace (an airspeed floor of 0 in calm air gives an infinite time constant, not a crash)
    assert _ratio(1.0, 0.0) == np.inf
    assert _ratio(-1.0, 0.0) == -np.inf
    assert np.isnan(_ratio(0.0, 0.0))


def _rows_alone(function, *arrays):
    """``function`` of every row alone, stacked as the batch's output."""
    outs = [function(*(a[i:i + 1] for a in arrays)) for i in range(len(arrays[0]))]
    if isinstance(outs[0], tuple):
        return tuple(np.concatenate([o[k] for o in outs]) for k in range(len(outs[0])))
    return np.concatenate(outs)


def test_wind_kernels_give_each_row_what_it_gets_alone():
    rng = np.random.default_rng(3)
    n = 40
    heights = np.sort(rng.uniform(5.0, 400.0, (3, 3, 5)), axis=2)
    grid = WindGrid(np.array([-200.0, 0.0, 300.0]), np.array([-100.0, 50.0, 200.0]), heights,
                    rng.normal(0.0, 5.0, (3, 3, 5, 3)), grid_yaw_rad=0.4)
    points = np.column_stack([rng.uniform(-100, 150, n), rng.uniform(-50, 120, n), rng.uniform(0, 450, n)])
    for method in ("idw", "trilinear"):
        batch = interpolate(grid, points, method, clamp=True)
        alone = _rows_alone(lambda p, m=method: interpolate(grid, p, m, clamp=True), points)
        np.testing.assert_array_equal(batch, alone)
    wake = ShipAirWake(BOX)
    wind = rng.normal(0.0, 6.0, (n, 3))
    wind[0] = 0.0                                                    # calm: no wake
    deficit, gain = wake.factors(points, wind)
    alone = _rows_alone(wake.factors, points, wind)
    np.testing.assert_array_equal(deficit, alone[0])
    np.testing.assert_array_equal(gain, alone[1])
    assert deficit[0] == 0.0 and gain[0] == 1.0


def test_control_kernels_give_each_row_what_it_gets_alone():
    rng = np.random.default_rng(4)
    n = 30
    quat = rng.normal(size=(n, 4))
    rot = quat_to_matrix(quat / np.linalg.norm(quat, axis=1, keepdims=True))
    args = [rng.normal(0, 3, (n, 3)), rng.normal(0, 3, (n, 3)), np.ascontiguousarray(rot[:, :, 2]),
            rng.normal(0, 3, (n, 3)), rng.normal(0, 2, (n, 3)), rng.normal(0, 9, (n, 3)), rng.uniform(-4, 4, n)]
    integrate = rng.random(n) < 0.5

    def loop(*rows):
        controller = PositionController(PHANTOM4, GAIN_PRESETS["default"], len(rows[0]))
        controller.integral[:] = 0.3
        thrust, quat_d = controller(*rows[:-1], 0.05, rows[-1])
        return thrust, quat_d, controller.integral

    batch = loop(*args, integrate)
    for got, alone in zip(batch, _rows_alone(loop, *args, integrate), strict=True):
        np.testing.assert_array_equal(got, alone)
    rel_air = rng.normal(0, 8, (n, 3))
    np.testing.assert_array_equal(drag_force(rel_air, args[-1], PHANTOM4, 1.0, 1.225),
                                  _rows_alone(lambda r, y: drag_force(r, y, PHANTOM4, 1.0, 1.225), rel_air, args[-1]))


@pytest.mark.parametrize("pitch_deg", [-90.0, -35.0, 0.0, 20.0, 90.0])
def test_camera_angles_invert_camera_rotations(pitch_deg):
    yaw = np.linspace(-3.0, 3.0, 7)
    pitch = np.full(7, np.radians(pitch_deg))
    roll = np.linspace(-0.5, 0.5, 7)
    rot = camera_rotations(yaw, pitch, roll)
    np.testing.assert_allclose(camera_rotations(*camera_angles(rot)), rot, atol=1e-12)


def test_the_kernel_cache_folder_follows_every_module_of_the_package(tmp_path):
    # numba invalidates a cached kernel only when its own file changes, but a kernel also freezes another
    # file's kernels and constants (vehicle.GRAVITY_M_S2, the phase codes): the cache folder must move with
    # any of them
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    kernels = package / "sub" / "kernels.py"
    kernels.write_text("from wrp_eval.compiled import kernel\nfrom pkg.constants import G\n\n@kernel\n"
                       "def f(x):\n    return x * G\n")
    constants = package / "constants.py"
    constants.write_text("G = 9.81\n")
    before = kernel_sources_digest(package)
    assert kernel_sources_digest(package) == before
    constants.write_text("G = 1.0\n")                  # a constant the kernel froze when it was compiled
    edited = kernel_sources_digest(package)
    assert edited != before
    kernels.write_text(kernels.read_text().replace("x * G", "x * G + 1"))
    assert kernel_sources_digest(package) not in (before, edited)


def test_contiguous_hands_every_kernel_caller_the_same_kind_of_array():
    from wrp_eval.compiled import contiguous

    rows = np.arange(12.0).reshape(4, 3)
    assert contiguous(rows) is rows                                   # already one: no copy
    column = contiguous(rows[:, 1])                                   # a strided view
    assert column.flags.c_contiguous and column.tolist() == [1.0, 4.0, 7.0, 10.0]
    frozen = rows.copy()
    frozen.flags.writeable = False
    thawed = contiguous(frozen)
    assert thawed.flags.writeable and np.array_equal(thawed, frozen)
    assert contiguous(np.broadcast_to(2.0, (3,))).flags.writeable     # a broadcast number becomes an array
    assert contiguous([1, 2]).dtype == np.float64


def test_camera_rotations_compile_one_signature_whatever_their_inputs_flags():
    from wrp_eval.camera import _rotation_rows, camera_rotations

    yaw = np.linspace(0.0, 1.0, 5)
    frozen = yaw.copy()
    frozen.flags.writeable = False
    camera_rotations(yaw, -0.3, 0.1)
    before = len(_rotation_rows.signatures)
    for y, p, r in ((frozen, -0.3, 0.1), (yaw[::-1], np.full(5, -0.3)[::-1], None), (frozen, frozen, frozen)):
        camera_rotations(y, p, r)
    assert len(_rotation_rows.signatures) == before
