"""wrp-eval: wind-resistant UAV photo-flight planning around ships, evaluated by Monte Carlo flights in MuJoCo.

Stages (one sub-package each, meeting through small value types):
ship -> planning -> wind -> sim -> recon -> campaign -> surrogate -> wrp -> export.
"""

import os

# dm_control and mujoco pick an OpenGL back end at import; without a display GLFW prints a warning on
# every command. Offscreen rendering on a CPU machine uses OSMesa (installed by the set-up); a user who
# has a GPU can still set MUJOCO_GL=egl before running.
os.environ.setdefault("MUJOCO_GL", "osmesa")
if os.environ["MUJOCO_GL"] in ("osmesa", "egl"):
    os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])

__version__ = "0.1.0"
