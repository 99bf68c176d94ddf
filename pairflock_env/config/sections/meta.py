"""Section ``meta``: where a config came from."""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import Field, Kind
from pairflock_env.config.schema import Section

__all__ = ["SECTIONS"]


class _PresetName(Kind):
    """Any string or None: the preset a config was built from (informational)."""

    annotation = str | None
    type_name = "str or None"

    def valid(self) -> str:
        return "a preset name (str) or None"

    def check(self, name: str, value: Any, ctx: Any = None) -> str | None:
        if value is None:
            return None
        if not isinstance(value, str):
            raise TypeError(f"{name}={value!r} is invalid: must be a preset name or None")
        return str(value)


META = Section(
    "meta",
    "Provenance",
    "Where a config came from.",
    (
        Field(
            "preset",
            _PresetName(),
            None,
            "",
            "Name of the preset this config was built from (informational; baselines take "
            "their default gains from it); make_config fills it in.",
        ),
    ),
)

SECTIONS = (META,)
