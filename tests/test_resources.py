"""Package resources: the MJCF is found in a source tree / editable install and ships inside a wheel; generated
meshes go to the user cache folder ($WRP_EVAL_CACHE_DIR when set), never into the source tree."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import platformdirs
import pytest
import setuptools

from wrp_eval import resources
from wrp_eval.ship.meshes import cached_procedural_mesh, default_cache_dir
from wrp_eval.ship.particulars import ShipParticulars, ShipType

REPO = Path(__file__).resolve().parents[1]


def test_cache_dir_honours_the_environment_variable(tmp_path, monkeypatch):
    monkeypatch.setenv(resources.CACHE_ENV, str(tmp_path / "c"))
    assert resources.cache_dir() == tmp_path / "c"
    assert resources.cache_dir("ships") == tmp_path / "c" / "ships"
    assert default_cache_dir() == tmp_path / "c" / "ships"
    monkeypatch.delenv(resources.CACHE_ENV)
    assert resources.cache_dir("ships") == Path(platformdirs.user_cache_dir("wrp-eval", appauthor=False)) / "ships"


def test_a_generated_mesh_goes_to_the_cache_not_the_source_tree(tmp_path, monkeypatch):
    monkeypatch.setenv(resources.CACHE_ENV, str(tmp_path / "cache"))
    source_models = sorted((REPO / "models").rglob("*"))
    particulars = ShipParticulars(ship_type=ShipType.FISHING, length_bp_m=31.0, breadth_m=7.0, depth_m=3.5,
                                  draft_m=2.0, superstructure_height_m=4.0)
    mesh, path = cached_procedural_mesh(particulars)
    assert path.parent == tmp_path / "cache" / "ships" and path.is_file() and len(mesh.faces)
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]   # no temporary left beside it
    assert sorted((REPO / "models").rglob("*")) == source_models


def test_models_dir_holds_the_quadrotor_mjcf():
    xml = resources.model_file("quadrotor", "quadrotor.xml")
    assert xml.parent.parent == resources.models_dir()
    assert "<mujoco" in xml.read_text()
    with pytest.raises(FileNotFoundError, match="no_such.xml"):
        resources.model_file("quadrotor", "no_such.xml")


def test_pyproject_lists_every_package_and_models_folder():
    # the package list is explicit (a mapped models/ is not discovered): a new subpackage must be added there
    tool = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert tool["package-dir"] == {"wrp_eval.models": "models"}
    expected = set(setuptools.find_packages(str(REPO), include=["wrp_eval", "wrp_eval.*"]))
    expected |= {"wrp_eval.models"} | {f"wrp_eval.models.{d.name}" for d in (REPO / "models").iterdir()
                                       if d.is_dir() and d.name != "ships"}
    assert set(tool["packages"]) == expected


@pytest.mark.slow
def test_a_built_wheel_carries_the_mjcf(tmp_path):
    src = tmp_path / "src"   # a copy: building in the checkout would write build/ and egg-info there
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(REPO / name, src / name)
    for name in ("wrp_eval", "models"):
        shutil.copytree(REPO / name, src / name, ignore=shutil.ignore_patterns("__pycache__", "ships"))
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                           "-w", str(tmp_path / "dist"), str(src)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    (wheel,) = (tmp_path / "dist").glob("wrp_eval-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert "wrp_eval/models/quadrotor/quadrotor.xml" in names
    assert "wrp_eval/resources.py" in names and not any("/ships/" in n for n in names)
