"""Config plumbing shared by every stage: the strict base model and the YAML loader.

A bad file becomes one :class:`InputError` line naming the file, the key and the problem.
The experiment config itself is composed in :mod:`wrp_eval.config`.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from functools import cache
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from wrp_eval.errors import InputError


class StrictModel(BaseModel):
    """Base of every config section: unknown keys are an error, values are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)


M = TypeVar("M", bound=BaseModel)

log = logging.getLogger(__name__)
_READING_STORED = ContextVar("reading_stored", default=False)


@contextmanager
def reading_stored() -> Iterator[None]:
    """Validate documents the program stored itself (a campaign's config): old key names pass silently, the
    deprecation line is for configs a user writes."""
    token = _READING_STORED.set(True)
    try:
        yield
    finally:
        _READING_STORED.reset(token)


@cache
def _warn_renamed(section: str, old: str, new: str) -> None:
    log.warning("config: %s.%s is a deprecated key, read as %s.%s (rename it)", section, old, section, new)


def renamed_keys(data: Any, renames: dict[str, str], section: str) -> Any:
    """A section written with an old key name (``renames``: old -> new) is read as the new one, with one
    deprecation line per key and process (configs and stored campaigns keep working); both names at once is an
    error. For a model's ``model_validator(mode="before")``."""
    if not isinstance(data, dict) or not (renames.keys() & data.keys()):
        return data
    data = dict(data)
    for old, new in renames.items():
        if old in data:
            if new in data:
                raise ValueError(f"give {new!r} only ({old!r} is its deprecated name)")
            if not _READING_STORED.get():
                _warn_renamed(section, old, new)
            data[new] = data.pop(old)
    return data


def format_validation_error(source: str | Path, err: ValidationError) -> InputError:
    """One line naming the file, the first offending key and the problem (plus how many more)."""
    problems = err.errors()
    first = problems[0]
    key = ".".join(str(p) for p in first["loc"]) or "<top level>"
    message = first["msg"]
    if first["type"] == "extra_forbidden":
        message = "unknown key"
    more = f" (and {len(problems) - 1} more problem(s))" if len(problems) > 1 else ""
    return InputError(source, f"key '{key}': {message}{more}")


def parse_model(model: type[M], data: Any, source: str | Path) -> M:
    """Validate ``data`` into ``model``; any problem becomes an :class:`InputError` naming ``source``."""
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise InputError(source, f"expected a mapping at the top level, got {type(data).__name__}")
    try:
        return model.model_validate(data)
    except ValidationError as err:
        raise format_validation_error(source, err) from None
    except ValueError as err:  # a model_validator raised outside pydantic's wrapping
        raise InputError(source, str(err)) from None


def read_yaml(path: str | Path) -> Any:
    """``yaml.safe_load`` of a file; unreadable or malformed YAML is an :class:`InputError`."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(path, "no such file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(path, f"cannot read: {err}") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err)
        raise InputError(path, f"invalid YAML{where}: {problem}") from None


def load_model(model: type[M], path: str | Path) -> M:
    """Read a YAML file and validate it into ``model``."""
    return parse_model(model, read_yaml(path), path)
