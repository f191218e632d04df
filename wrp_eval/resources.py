"""Where the package finds its data files and where it caches what it generates.

Two lookups, one place:

- :func:`models_dir`: the MJCF models. They live in the repository's top-level ``models/`` folder (the
  product's layout); pyproject.toml maps that folder into the wheel as the package data folder
  ``wrp_eval/models`` (setuptools ``package-dir``), so a non-editable install carries it inside the package,
  while a source checkout or an editable install (which links the package folder, not the repository) finds
  it next to the package folder.
- :func:`source_experiments_dir`: the repository's ``experiments/`` configs (a source checkout only; the benches
  read them).
- :func:`cache_dir`: where generated files (procedural ship meshes) are cached: ``$WRP_EVAL_CACHE_DIR`` when
  set, else the user's cache folder of the platform (``platformdirs.user_cache_dir``, e.g.
  ``~/.cache/wrp-eval`` on Linux), never the source tree or the installed package.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

import platformdirs

APP_NAME = "wrp-eval"
CACHE_ENV = "WRP_EVAL_CACHE_DIR"
_PACKAGE = "wrp_eval"
_MODELS = "models"


def models_dir() -> Path:
    """The folder holding the MJCF models (``quadrotor/quadrotor.xml``).

    Looked up first inside the installed package (``wrp_eval/models``, a wheel's package data), then as the
    repository's top-level ``models/`` beside the package folder (source checkout, editable install).
    Raises FileNotFoundError naming both places when neither exists."""
    packaged = resources.files(_PACKAGE) / _MODELS
    # MuJoCo and dm_control open the XML by file name, so only a real folder will do (a wheel is installed
    # unpacked; a zipped package would have no file names to give them).
    if isinstance(packaged, Path) and packaged.is_dir():
        return packaged
    source = Path(__file__).resolve().parent.parent / _MODELS
    if source.is_dir():
        return source
    raise FileNotFoundError(f"wrp-eval models folder not found (looked in {packaged} and {source})")


def source_experiments_dir() -> Path:
    """The repository's top-level ``experiments/`` folder (the quickstart and the paper configs) beside the package
    folder: a source checkout or an editable install has it; a wheel does not carry it (the benches that read it
    say so, or fall back to the embedded defaults)."""
    return Path(__file__).resolve().parent.parent / "experiments"


def model_file(*parts: str) -> Path:
    """A file under :func:`models_dir`, e.g. ``model_file("quadrotor", "quadrotor.xml")``; FileNotFoundError
    when it is not there."""
    path = models_dir().joinpath(*parts)
    if not path.is_file():
        raise FileNotFoundError(f"wrp-eval model file not found: {path}")
    return path


def cache_dir(*parts: str) -> Path:
    """The cache folder (or a sub-folder ``parts`` of it, e.g. ``cache_dir("ships")``), not created here.

    ``$WRP_EVAL_CACHE_DIR`` when set and non-empty (tests, shared or read-only installs), else
    ``platformdirs.user_cache_dir("wrp-eval")``."""
    env = os.environ.get(CACHE_ENV)
    root = Path(env).expanduser() if env else Path(platformdirs.user_cache_dir(APP_NAME, appauthor=False))
    return root.joinpath(*parts)
