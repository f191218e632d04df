"""The MuJoCo scene (sea plane and ship), composed with dm_control's PyMJCF.

``build_scene`` returns the ``mjcf.RootElement``: later stages attach quadrotors to it
(``root.attach(quadrotor_root)`` or ``root.worldbody.add(...)``) and compile it with ``compile_scene``.
The ship mesh travels as an in-memory binary STL asset, so no file is written.
"""

from __future__ import annotations

import mujoco
import numpy as np
import trimesh
from dm_control import mjcf

HULL_COLOUR = (0.55, 0.55, 0.58, 1.0)


def build_scene(mesh: trimesh.Trimesh, model_name: str = "wrp_scene", sea_half_size_m: float | None = None,
                timestep_s: float = 0.002, moving: bool = False) -> mjcf.RootElement:
    """Sea plane at z = 0 and ``mesh`` (ship frame, metres) as a body named "ship": static, or with ``moving`` a
    mocap body whose pose the simulator sets (the ship swinging in a seaway, ``ship.motion``)."""
    root = mjcf.RootElement(model=model_name)
    root.option.timestep = timestep_s
    root.option.gravity = (0.0, 0.0, -9.81)
    extent = float(np.max(np.abs(mesh.bounds)))
    half = sea_half_size_m if sea_half_size_m is not None else max(200.0, 4.0 * extent)
    root.asset.add("texture", name="sea_grid", type="2d", builtin="checker", rgb1=(0.1, 0.25, 0.4),
                   rgb2=(0.12, 0.3, 0.45), width=256, height=256)
    root.asset.add("material", name="sea", texture="sea_grid", texrepeat=(half / 20, half / 20))
    stl = trimesh.exchange.stl.export_stl(mesh)   # binary STL
    root.asset.add("mesh", name="ship", file=mjcf.Asset(contents=stl, extension=".stl"))
    root.worldbody.add("light", name="sun", pos=(0, 0, 10 * max(extent, 10.0)), dir=(0, 0, -1),
                       directional=True)
    root.worldbody.add("geom", name="sea", type="plane", size=(half, half, 1.0), material="sea",
                       contype=1, conaffinity=1)
    ship = root.worldbody.add("body", name="ship", mocap=moving)   # no joint: static, or moved from outside
    ship.add("geom", name="ship_hull", type="mesh", mesh="ship", rgba=HULL_COLOUR, contype=1, conaffinity=1,
             group=1)
    return root


def compile_scene(root: mjcf.RootElement) -> mujoco.MjModel:
    """Compile with the official bindings (assets passed in memory)."""
    return mujoco.MjModel.from_xml_string(root.to_xml_string(), root.get_assets())
