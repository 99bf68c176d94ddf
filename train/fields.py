"""The field kinds of the run settings that the env config does not need: text, a mapping
of overrides, lists of seeds, controller names and tasks, and a model named by path or by
name. They are :class:`pairflock_env.config.fields.Kind` s like the config's own, so a run
setting is checked, named in errors and documented the same way (``name=value is invalid:
what is valid``; ``TypeError`` for a wrong type, ``ValueError`` for a wrong value).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from baselines.controllers import POLICIES
from baselines.controllers.zoo import resolve_model
from pairflock_env.config.fields import Kind, invalid
from train.mix.tasks import task_entries, task_fields

__all__ = ["ControllerNames", "ModelFile", "Overrides", "SeedList", "TaskList", "Text"]


@dataclasses.dataclass(frozen=True)
class Text(Kind):
    """A string (checked further by what uses it, e.g. a preset's or a vehicle's name)."""

    what: str
    annotation = str
    type_name = "str"

    def valid(self) -> str:
        return self.what

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> str:
        if not isinstance(value, str):
            raise invalid(name, value, f"must be {self.what}", TypeError)
        return value


@dataclasses.dataclass(frozen=True)
class Overrides(Kind):
    """A mapping of keyword values (config overrides, hyperparameters); stored as a copy."""

    what: str
    annotation = dict
    type_name = "mapping"

    def valid(self) -> str:
        return f"a mapping of {self.what}"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> dict:
        if not isinstance(value, Mapping):
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        return copy.deepcopy(dict(value))


@dataclasses.dataclass(frozen=True)
class SeedList(Kind):
    """A non-empty list of integer seeds >= 0."""

    annotation = list
    type_name = "list of int"

    def valid(self) -> str:
        return "a non-empty list of integers >= 0"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> list[int]:
        if not isinstance(value, (list, tuple)) or not all(
            isinstance(s, int) and not isinstance(s, bool) for s in value
        ):
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        if not value or min(value) < 0:
            raise invalid(name, value, f"must be {self.valid()}")
        return [int(s) for s in value]


def _analytic() -> list[str]:
    return [k for k in POLICIES if not k.endswith(":")]


@dataclasses.dataclass(frozen=True)
class ControllerNames(Kind):
    """A list of analytic controllers by registered name (:data:`baselines.POLICIES`)."""

    names: Callable[[], Sequence[str]] = _analytic
    annotation = list
    type_name = "list of str"

    def valid(self) -> str:
        return "a list of analytic controller names (baselines.POLICIES)"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> list[str]:
        if not isinstance(value, (list, tuple)):
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        known = self.names()
        for entry in value:
            if entry not in known:
                raise ValueError(
                    f"{name} entry {entry!r} is invalid: analytic controllers are "
                    f"{', '.join(known)}"
                )
        return list(value)


@dataclasses.dataclass(frozen=True)
class TaskList(Kind):
    """A non-empty list of tasks (mappings of config fields plus ``allowed`` keys of their own);
    the entries are checked by :mod:`train.mix.tasks`, which resolves them."""

    allowed: tuple[str, ...]
    annotation = list
    type_name = "list of mappings"

    def valid(self) -> str:
        return f"a non-empty list of tasks (config fields plus {', '.join(self.allowed)})"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> list[dict]:
        entries = task_entries(value, name)
        for i, entry in enumerate(entries):
            task_fields(entry, f"{name}[{i}]", self.allowed)
        return copy.deepcopy([dict(e) for e in entries])


@dataclasses.dataclass(frozen=True)
class ModelFile(Kind):
    """A saved model: a zip path or the name of a packaged policy
    (:func:`baselines.controllers.zoo.resolve_model`); stored as written."""

    annotation = str
    type_name = "path or name"

    def valid(self) -> str:
        return "a model zip or a packaged policy's name"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> str:
        if not isinstance(value, (str, Path)):
            raise invalid(name, value, "must be a path or a model name", TypeError)
        try:
            resolve_model(value)
        except FileNotFoundError as e:
            raise invalid(name, value, str(e)) from None
        return str(value)
