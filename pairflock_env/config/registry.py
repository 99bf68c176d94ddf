"""The env's plug-in seams: one registry per kind of part, each entry carrying what the rest of
the house asks about it.

=====================  ==========================  =============================================
registry               config field                entry (what it carries)
=====================  ==========================  =============================================
:data:`VEHICLES`       ``dynamics``                :class:`~pairflock_env.dynamics.Vehicle`
:data:`FILTERS`        ``safety_filter``           :class:`~pairflock_env.safety.Filter`
:data:`LEADERS`        ``leader``                  :class:`~pairflock_env.swarm.leader.Leader`
:data:`OBSERVATIONS`   ``obs_extra``               :class:`~pairflock_env.task.observations.
                                                   ObservationField`
=====================  ==========================  =============================================

Every entry is a :class:`Plugin`: a name (the value of its config field), a one-line doc, and
optionally a config :class:`~.schema.Section` of its own parameters with rules and derived
quantities. Registering an entry declares its section in the config schema, so its fields
become keywords of every view, are validated like the built-in ones and appear in the
generated ``docs/config.md``; the built-in parts register through the same call
(``docs/extending.md`` shows one of each added from outside the package).
"""

from __future__ import annotations

import dataclasses
import difflib
import importlib
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from importlib.metadata import entry_points
from typing import Any

from pairflock_env.config.fields import Kind, invalid, sequence_items
from pairflock_env.config.schema import Derived, Rule, Section

__all__ = [
    "FILTERS",
    "LEADERS",
    "OBSERVATIONS",
    "VEHICLES",
    "Plugin",
    "Registered",
    "RegisteredNames",
    "Registry",
    "load_plugins",
]

#: environment variable naming plug-in modules to import with the package (comma-separated);
#: fresh processes (benchmark workers) inherit it, so a plug-in reaches them too
PLUGINS_VARIABLE = "PAIRFLOCK_PLUGINS"
#: entry-point group of installed plug-in packages
ENTRY_POINT_GROUP = "pairflock_env.plugins"


@dataclasses.dataclass(frozen=True, kw_only=True)
class Plugin:
    """What every registry entry has: its name, what it is, and its own config parameters."""

    name: str
    doc: str
    #: the config section of its own parameters (None: it has none); declared on registration
    section: Section | None = None
    rules: tuple[Rule, ...] = ()
    derived: tuple[Derived, ...] = ()


class Registry(Mapping[str, Any]):
    """Named entries of one seam, in registration order.

    Args:
        seam: what an entry is, for messages ("vehicle model").
        field: the config field whose values are the entries' names.
    """

    def __init__(self, seam: str, field: str) -> None:
        self.seam = seam
        self.field = field
        self._entries: dict[str, Plugin] = {}
        #: called with each new entry before it is added (the config schema declares its
        #: section there: see pairflock_env.config.model)
        self.declare: Callable[[Plugin], None] | None = None

    def register(self, entry: Plugin) -> Plugin:
        """Add ``entry`` (returned, so this works as a decorator of a factory's result).

        ``TypeError`` unless it is a :class:`Plugin`; ``ValueError`` for a name that is not a
        plain identifier or is taken; a section whose fields clash with the config's raises
        and leaves both the registry and the config as they were."""
        if not isinstance(entry, Plugin):
            raise TypeError(f"entry={entry!r} is invalid: must be a {self.seam} entry (a Plugin)")
        name = entry.name
        if not isinstance(name, str) or not name.isidentifier():
            raise invalid("name", name, "must be a plain identifier (letters, digits, _)")
        if name in self._entries:
            raise ValueError(f"{self.seam} {name!r} is registered already")
        self._entries[name] = entry
        try:
            if self.declare is not None:
                self.declare(entry)
        except Exception:
            del self._entries[name]
            raise
        return entry

    def section_fields(self) -> tuple[str, ...]:
        """The config fields declared by the entries' own sections."""
        return tuple(
            f.name
            for e in self._entries.values()
            if e.section is not None
            for f in e.section.fields
        )

    def __getitem__(self, name: str) -> Any:
        try:
            return self._entries[name]
        except (KeyError, TypeError):
            raise KeyError(self.unknown(name)) from None

    def unknown(self, name: Any) -> str:
        hint = difflib.get_close_matches(str(name), list(self._entries), n=1)
        extra = f"; did you mean {hint[0]!r}?" if hint else ""
        return f"no {self.seam} named {name!r}{extra} (registered: {', '.join(self._entries)})"

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.seam!r}: {', '.join(self._entries)})"


@dataclasses.dataclass(frozen=True)
class Registered(Kind):
    """The name of one entry of ``registry`` (checked against what is registered now);
    ``none_means`` is what ``None`` stands for, if anything. With ``after_sections`` the field
    is checked after every field of the entries' own sections, so that rules and defaults
    that read this field may ask the chosen entry about its parameters."""

    registry: Registry
    none_means: str | None = None
    after_sections: bool = False
    annotation = str
    type_name = "str"

    @property
    def needs(self) -> tuple[str, ...]:
        return self.registry.section_fields() if self.after_sections else ()

    def valid(self) -> str:
        names = ", ".join(map(repr, self.registry))
        none = f" (None: {self.none_means!r})" if self.none_means else ""
        return f"one of {names}{none}"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> str:
        if value is None and self.none_means is not None:
            return self.none_means
        if not isinstance(value, str):
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        if value not in self.registry:
            raise invalid(name, value, f"must be {self.valid()}")
        return str(value)


@dataclasses.dataclass(frozen=True)
class RegisteredNames(Kind):
    """A tuple of distinct names of entries of ``registry`` (a single name is one entry)."""

    registry: Registry
    annotation = tuple
    type_name = "tuple of str"

    def valid(self) -> str:
        return f"a sequence of distinct names out of {', '.join(map(repr, self.registry))}"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> tuple:
        items: Sequence[Any] | None = [value] if isinstance(value, str) else sequence_items(value)
        if items is None:
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        one = Registered(self.registry)
        out = tuple(one.check(f"{name}[{i}]", x) for i, x in enumerate(items))
        if len(set(out)) != len(out):
            raise invalid(name, value, "must name each entry at most once")
        return out


#: vehicle models (``dynamics``): pairflock_env.dynamics registers particle and quadrotor
VEHICLES = Registry("vehicle model", "dynamics")
#: safety filters (``safety_filter``): pairflock_env.safety registers none and cbf
FILTERS = Registry("safety filter", "safety_filter")
#: leader trajectories (``leader``): pairflock_env.swarm.leader registers the built-in ones
LEADERS = Registry("leader trajectory", "leader")
#: extra observation fields (``obs_extra``), appended after the built-in layout
OBSERVATIONS = Registry("observation field", "obs_extra")


_loaded: set[str] = set()


def load_plugins() -> tuple[str, ...]:
    """Import the plug-in modules of installed packages (entry points of the group
    ``pairflock_env.plugins``) and those named in ``$PAIRFLOCK_PLUGINS``, once each; a
    plug-in module registers its entries when imported. Returns the modules loaded now.
    ``pairflock_env`` calls it on import, so every process, a benchmark's worker included,
    sees the same registries."""
    names = [ep.value.split(":")[0] for ep in entry_points(group=ENTRY_POINT_GROUP)]
    names += [m.strip() for m in os.environ.get(PLUGINS_VARIABLE, "").split(",") if m.strip()]
    new = []
    for name in names:
        if name in _loaded:
            continue
        try:
            importlib.import_module(name)
        except ImportError as e:
            raise ImportError(
                f"plug-in module {name!r} (from ${PLUGINS_VARIABLE} or the entry points "
                f"{ENTRY_POINT_GROUP!r}) failed to import: {e}"
            ) from e
        _loaded.add(name)
        new.append(name)
    return tuple(new)
