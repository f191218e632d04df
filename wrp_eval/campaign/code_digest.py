"""The digest of the code that decides a trial's result, so that a stored campaign is not extended by other code.

A campaign folder is resumed when its fingerprint matches (runner.py). The config alone does not decide a
trial: a change of the simulator or the oracle changes every flight under the same config, and trials flown by
two versions must not mix in one store (session 17 found stores silently extended across a physics change).
The digest covers the source of the evaluator's module and of every ``wrp_eval`` module it imports, at any
depth, found by reading the import statements (function-level imports included: conservative), the MJCF models
and the versions of the libraries that decide the numbers (MuJoCo, numpy, scipy, open3d, numba). Any edit of
those files, even one that keeps the numbers, makes a new digest: the stored trials stay readable (a complete
store is used as it is), and a new folder is needed to fly more.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import sys
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from wrp_eval.campaign.evaluators import RENAMED_EVALUATORS
from wrp_eval.errors import InputError
from wrp_eval.resources import models_dir

_PACKAGE = "wrp_eval"


def _source_file(module: str) -> Path | None:
    """The source file of ``module`` (a package's ``__init__.py``), found on disk below its top-level package
    (nothing but that package's ``__init__`` is imported); for ``__main__`` (an evaluator defined in the running
    script) the script's file. None when there is none."""
    if module == "__main__":
        loaded = getattr(sys.modules.get(module), "__file__", None)
        return Path(loaded) if loaded and loaded.endswith(".py") else None
    top, _, rest = module.partition(".")
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        return None
    if spec is None or spec.origin is None or not spec.origin.endswith(".py"):
        return None
    if not rest:
        return Path(spec.origin)
    if spec.submodule_search_locations is None:
        return None
    base = Path(spec.origin).parent.joinpath(*rest.split("."))
    for file in (base.with_suffix(".py"), base / "__init__.py"):
        if file.is_file():
            return file
    return None


def _imported(tree: ast.Module, module: str, is_package: bool) -> set[str]:
    """Module names a source file imports (``from a import b`` counts ``a`` and ``a.b``: b may be a module)."""
    names: set[str] = set()
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1] + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
    return names


def _parents(module: str) -> list[str]:
    """``a.b.c`` -> [a, a.b]: the packages whose ``__init__`` runs on import."""
    parts = module.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def module_closure(root: str) -> dict[str, Path]:
    """``root`` and every module of ``wrp_eval`` (or of ``root``'s own top-level package) it imports at any depth:
    name -> source file."""
    scope = {_PACKAGE, root.split(".")[0]}
    found: dict[str, Path] = {}
    pending = [root]
    while pending:
        name = pending.pop()
        if name in found or name.split(".")[0] not in scope:
            continue
        file = _source_file(name)
        if file is None:
            continue
        found[name] = file
        tree = ast.parse(file.read_bytes(), filename=str(file))
        pending.extend(_imported(tree, name, file.name == "__init__.py"))
        pending.extend(_parents(name))
    return found


# the libraries whose numbers a trial's result depends on (physics, random streams, ray casting, kernels)
LIBRARIES = ("mujoco", "numpy", "scipy", "open3d", "numba")


@lru_cache(maxsize=8)
def trial_code_digest(evaluator: str) -> str:
    """sha256 (16 hex digits) of the sources a trial of ``evaluator`` ("module:factory", a renamed one read as
    today's) runs, of the MJCF models folder and of the versions of :data:`LIBRARIES`. An evaluator module
    without Python source is an :class:`InputError` (nothing to digest)."""
    module = RENAMED_EVALUATORS.get(evaluator, evaluator).partition(":")[0]
    closure = module_closure(module)
    if module not in closure:
        raise InputError("campaign evaluator", f"{module!r} has no Python source to digest")
    h = hashlib.sha256()
    for name, file in sorted(closure.items()):
        h.update(name.encode() + b"\0" + file.read_bytes() + b"\0")
    models = models_dir()
    for file in sorted(p for p in models.rglob("*") if p.is_file() and not p.name.startswith(".")):
        h.update(str(file.relative_to(models)).encode() + b"\0" + file.read_bytes() + b"\0")
    for name in LIBRARIES:
        try:
            h.update(f"{name}=={version(name)}".encode() + b"\0")
        except PackageNotFoundError:
            h.update(f"{name} absent".encode() + b"\0")
    return h.hexdigest()[:16]
