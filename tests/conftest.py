"""Suite-wide hooks."""

from __future__ import annotations

import pytest


def pytest_collection_modifyitems(session: pytest.Session, config: pytest.Config, items: list[pytest.Item]) -> None:
    """Files holding a test marked ``slow`` run first, each file's own order kept: ``make test`` hands whole files to
    its two pytest-xdist workers in this order (``--dist loadfile``), so a long file no longer starts last while the
    other worker has nothing left to do."""
    slow_files = {item.path for item in items if item.get_closest_marker("slow") is not None}
    items.sort(key=lambda item: item.path not in slow_files)
