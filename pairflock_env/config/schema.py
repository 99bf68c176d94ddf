"""Schemas: declared fields grouped in sections, the rules between them, and the frozen record
built from them.

A :class:`Schema` validates a flat mapping of values in one pass: unknown names raise
:class:`~.fields.UnknownFieldError` with a did-you-mean hint, old names map to new ones, each
field is checked by its kind in dependency order (auto defaults filled in), and every
:class:`Rule` between fields and every :class:`Derived` quantity is checked as soon as the
fields it reads are (so the first error reported is the earliest one). A failing rule names
the first of its fields that the user set (its first field when the user set none of them),
the reason and the values of the other fields involved.

:func:`declare_record` turns a schema into a frozen dataclass (equality, hashing, repr,
pickling and ``dataclasses.fields`` as for any dataclass) whose keyword-only constructor runs
that validation; :class:`Record` holds the shared methods (``replace``, ``to_dict``,
``from_dict``, deprecated attribute aliases).
"""

from __future__ import annotations

import dataclasses
import difflib
import inspect
import math
import sys
import warnings
from collections.abc import Callable, Mapping, Sequence
from types import SimpleNamespace
from typing import Any, ClassVar

import numpy as np

from pairflock_env.config.fields import Field, UnknownFieldError, fmt_num, show

__all__ = ["Derived", "Record", "Rule", "Schema", "Section", "declare_record"]


@dataclasses.dataclass(frozen=True)
class Section:
    """A named group of fields (one table in the docs)."""

    name: str
    title: str
    doc: str
    fields: tuple[Field, ...]


@dataclasses.dataclass(frozen=True)
class Rule:
    """A constraint between fields: ``test(v)`` gets the normalised values as attributes and
    returns why they break the rule (a phrase with "must"), or None."""

    fields: tuple[str, ...]
    test: Callable[[Any], str | None]
    doc: str


@dataclasses.dataclass(frozen=True)
class Derived:
    """A quantity computed from fields that must be finite and lie in [lo, hi]."""

    name: str
    fields: tuple[str, ...]
    value: Callable[[Any], float]
    lo: float
    hi: float
    unit: str
    doc: str

    def compute(self, v: Any) -> float:
        """The quantity for values ``v``; NaN when it cannot be computed (overflow, 0/0)."""
        try:
            with np.errstate(all="ignore"):  # numpy overflow gives inf, reported below
                return float(self.value(v))
        except (ArithmeticError, ValueError):
            return math.nan

    def interval(self) -> str:
        return f"[{fmt_num(self.lo)}, {fmt_num(self.hi)}]"

    def test(self, v: Any) -> str | None:
        x = self.compute(v)
        if math.isfinite(x) and self.lo <= x <= self.hi:
            return None
        unit = f" {self.unit}" if self.unit else ""
        return (
            f"it makes {self.name} = {fmt_num(x)}{unit}, which must be finite and in "
            f"{self.interval()} ({self.doc})"
        )


def external_stacklevel() -> int:
    """The ``stacklevel`` that points a warning raised by the caller at the first frame outside
    this package (the user's code)."""
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_globals.get("__name__", "").startswith("pairflock_env"):
        frame, level = frame.f_back, level + 1
    return level


def _dependency_order(fields: Mapping[str, Field]) -> tuple[str, ...]:
    """Declaration order, except that a field comes after every field it needs."""
    done: list[str] = []
    pending = list(fields.values())
    while pending:
        ready = next((f for f in pending if set(f.needs) <= set(done)), None)
        if ready is None:
            raise RuntimeError(f"unresolvable field dependencies: {[f.name for f in pending]}")
        done.append(ready.name)
        pending.remove(ready)
    return tuple(done)


class Schema:
    """Sections of declared fields, plus the rules and derived quantities over them.

    Args:
        label: what a field is called in messages ("configuration field").
        sections: the sections, in the order of the docs and of ``to_dict``.
        rules, derived: each is checked right after the last of its ``fields`` (so a rule's
            test may read exactly the fields it lists).
    """

    def __init__(
        self,
        label: str,
        sections: Sequence[Section],
        rules: Sequence[Rule] = (),
        derived: Sequence[Derived] = (),
    ) -> None:
        self.label = label
        self.sections = tuple(sections)
        self.fields: dict[str, Field] = {}
        self.section_of: dict[str, str] = {}
        for sec in self.sections:
            for f in sec.fields:
                if f.name in self.fields:
                    raise RuntimeError(f"field {f.name!r} is declared twice")
                self.fields[f.name] = f
                self.section_of[f.name] = sec.name
        self.aliases = {a: f.name for f in self.fields.values() for a in f.aliases}
        self.rules = tuple(rules)
        self.derived = tuple(derived)
        for r in (*self.rules, *self.derived):
            missing = set(r.fields) - set(self.fields)
            if missing:
                raise RuntimeError(f"rule {r.doc!r} names undeclared fields {sorted(missing)}")
        self.order = _dependency_order(self.fields)
        # each rule is checked as soon as the last of its fields is (earliest error first)
        position = {name: i for i, name in enumerate(self.order)}
        self._ready: dict[str, list[Rule | Derived]] = {}
        for r in (*self.rules, *self.derived):
            last = max(r.fields, key=position.__getitem__)
            self._ready.setdefault(last, []).append(r)

    def section(self, name: str) -> Section:
        for sec in self.sections:
            if sec.name == name:
                return sec
        raise KeyError(
            f"section {name!r} does not exist; sections: "
            + ", ".join(s.name for s in self.sections)
        )

    # ------------------------------------------------------------------ names
    def unknown(self, key: Any) -> UnknownFieldError:
        names = list(self.fields)
        hint = difflib.get_close_matches(str(key), names, n=3)
        extra = f" Did you mean {', '.join(map(repr, hint))}?" if hint else ""
        return UnknownFieldError(
            # Python's own wording first: wrappers (TorchRL's GymEnv) look for it to retry
            # without an optional keyword such as frameskip
            f"got an unexpected keyword argument {key!r}: unknown {self.label} {key!r}.{extra} "
            f"Valid {self.label}s: {', '.join(names)}."
        )

    def resolve(self, values: Mapping[Any, Any], *, warn: bool) -> dict[str, Any]:
        """``values`` with old names mapped to current ones (a ``DeprecationWarning`` each when
        ``warn``); ``UnknownFieldError`` for a name that is neither."""
        out: dict[str, Any] = {}
        for key, v in values.items():
            name = self.aliases.get(key, key) if isinstance(key, str) else key
            if name not in self.fields:
                raise self.unknown(key)
            if name != key:
                if name in values:
                    raise TypeError(
                        f"{key} and {name} name the same {self.label}; give only {name}"
                    )
                if warn:
                    warnings.warn(
                        f"{self.label} {key!r} is deprecated; use {name!r} (same meaning)",
                        DeprecationWarning,
                        stacklevel=external_stacklevel(),
                    )
            why = self.fields[name].deprecated
            if warn and why and v is not None:
                # a FutureWarning: its meaning changed, and Python shows it to the users of
                # the command lines too (a DeprecationWarning from library code it hides)
                warnings.warn(
                    f"{self.label} {name!r} is deprecated: {why}",
                    FutureWarning,
                    stacklevel=external_stacklevel(),
                )
            out[name] = v
        return out

    # ------------------------------------------------------------------ values
    def build(
        self, values: Mapping[str, Any], user_set: Sequence[str] = ()
    ) -> tuple[dict[str, Any], frozenset[str]]:
        """Validated, normalised values of every field and the names whose value was derived
        (``auto``) rather than given. ``values`` holds current names only (see
        :meth:`resolve`); ``user_set`` says which of them the user set (for blame)."""
        ctx: dict[str, Any] = {}
        ns = SimpleNamespace()  # the same values as attributes, for auto and rule functions
        auto: set[str] = set()
        for name in self.order:
            f = self.fields[name]
            if name in values:
                raw = values[name]
            elif f.auto is not None:
                raw = f.auto.rule(ns)
                auto.add(name)
            else:
                raw = f.default
            ctx[name] = f.kind.check(name, raw, ctx)
            setattr(ns, name, ctx[name])
            for rule in self._ready.get(name, ()):
                try:
                    why = rule.test(ns)
                except ArithmeticError as e:  # a rule that overflows is broken, not passed
                    why = f"must keep the rule {rule.doc!r} computable ({e})"
                if why is not None:
                    raise self._rule_error(rule.fields, why, ctx, user_set)
        return {name: ctx[name] for name in self.fields}, frozenset(auto)

    @staticmethod
    def _rule_error(
        fields: Sequence[str], why: str, values: Mapping[str, Any], user_set: Sequence[str]
    ) -> ValueError:
        given = set(user_set)
        blame = next((n for n in fields if n in given), fields[0])
        others = "; ".join(f"{n}={show(values[n])}" for n in fields if n != blame)
        tail = f" [with {others}]" if others else ""
        return ValueError(f"{blame}={show(values[blame])} is invalid: {why}{tail}")


def _plain(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_plain(x) for x in value]
    return value


class Record:
    """Methods shared by the frozen records :func:`declare_record` builds from a schema."""

    schema: ClassVar[Schema]

    def __init__(self, **values: Any) -> None:
        resolved = self.schema.resolve(values, warn=True)
        self._fill(resolved, tuple(resolved))

    def _fill(self, values: Mapping[str, Any], user_set: Sequence[str]) -> None:
        norm, auto = self.schema.build(values, user_set)
        for name, v in norm.items():
            object.__setattr__(self, name, v)
        # names filled in by an auto rule, re-derived by replace(); not part of equality
        object.__setattr__(self, "_auto_fields", auto)

    @classmethod
    def _create(cls, values: Mapping[str, Any], user_set: Sequence[str]) -> Any:
        obj = cls.__new__(cls)
        obj._fill(values, user_set)
        return obj

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Any:
        """Rebuild a record from :meth:`to_dict` output, e.g. one stored with a trained model.
        Old field names are accepted silently; unknown names raise ``TypeError``."""
        if not isinstance(data, Mapping):
            raise TypeError(f"data={show(data)} is invalid: must be a mapping of field values")
        values = cls.schema.resolve(data, warn=False)
        return cls._create(values, tuple(values))

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python dict (JSON/YAML friendly: tuples become lists) of every field."""
        return {name: _plain(getattr(self, name)) for name in self.schema.fields}

    def replace(self, **overrides: Any) -> Any:
        """A copy with some fields changed (validated like the constructor). Fields that were
        derived (``auto``) are derived again, and a vector given as one number follows a
        change of ``dim`` (or ``d_m`` of ``pairs``)."""
        changed = self.schema.resolve(overrides, warn=True)
        auto = getattr(self, "_auto_fields", frozenset())
        values = {
            name: f.kind.collapse(getattr(self, name))
            for name, f in self.schema.fields.items()
            if name not in auto
        }
        values.update(changed)
        return self._create(values, tuple(changed))

    def __getattr__(self, name: str) -> Any:
        # only called when normal lookup fails: deprecated names of fields
        aliases = type(self).schema.aliases
        if name in aliases:
            warnings.warn(
                f"{type(self).__name__}.{name} is deprecated; use .{aliases[name]} (same value)",
                DeprecationWarning,
                stacklevel=external_stacklevel(),
            )
            return getattr(self, aliases[name])
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def __setstate__(self, state: Mapping[str, Any]) -> None:
        # pickles made before a field was renamed hold the old name
        state = dict(state)
        for old, new in type(self).schema.aliases.items():
            if old in state:
                state.setdefault(new, state.pop(old))
        self.__dict__.update(state)


def declare_record(
    name: str, schema: Schema, base: type[Record], module: str, doc: str
) -> type[Record]:
    """A frozen dataclass named ``name`` with one field per declaration of ``schema``, the
    methods of ``base`` (a :class:`Record` subclass) and a keyword-only constructor that
    validates. ``module`` is where users import it from (so that pickles find it)."""
    spec = [
        (
            f.name,
            f.kind.annotation,
            dataclasses.field(default=f.default, metadata={"declaration": f}),
        )
        for f in schema.fields.values()
    ]
    cls = dataclasses.make_dataclass(
        name,
        spec,
        bases=(base,),
        namespace={"__doc__": doc, "schema": schema},
        frozen=True,
        init=False,
    )
    cls.__module__ = module
    cls.__signature__ = inspect.Signature(
        [
            inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY, default=f.default)
            for f in schema.fields.values()
        ]
    )
    return cls
