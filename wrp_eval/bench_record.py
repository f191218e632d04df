"""The benchmark record every stage's ``bench.py`` returns, and the machine description stored beside them.

A record is ``{name, value, unit, anchor, anchor_value, note}`` (anchor: where the comparison figure comes from,
e.g. "paper Table 7"). Kept apart from :mod:`wrp_eval.bench` (the registry of groups, above every stage) so
that the stages' benchmarks import it without importing upwards.
"""

from __future__ import annotations

import importlib
import os
import platform
from dataclasses import dataclass
from typing import Any

import numpy


@dataclass(frozen=True)
class BenchRecord:
    name: str
    value: float
    unit: str
    anchor: str | None = None
    anchor_value: float | None = None
    note: str = ""


def environment() -> dict[str, Any]:
    """Machine and library versions, stored with every bench file."""
    versions = {"python": platform.python_version(), "numpy": numpy.__version__}
    for mod in ("scipy", "mujoco", "open3d", "torch", "trimesh", "rerun"):
        try:
            versions[mod] = importlib.import_module(mod).__version__
        except Exception:  # a missing optional library is simply not reported
            pass
    return {"machine": platform.machine(), "processor": platform.processor(), "cpus": os.cpu_count(),
            "system": platform.platform(), "versions": versions}
