"""Schemas: declared fields grouped in sections, the rules between them, and the frozen record
built from them.

A :class:`Schema` validates a flat mapping of values in one pass: unknown names raise
:class:`~.fields.UnknownFieldError` with a did-you-mean hint, each field is checked by its
kind in dependency order (auto defaults filled in), and every :class:`Rule` between fields and
every :class:`Derived` quantity is checked as soon as the fields it reads are (so the first
error reported is the earliest one). A failing rule names the first of its fields that the
user set (its first field when the user set none of them), the reason and the values of the
other fields involved.

:func:`declare_record` turns a schema into a frozen :class:`Record` class (equality, hashing,
repr and pickling by the declared fields) whose keyword-only constructor runs that
validation. One machinery serves every declared parameter set of the project: the env config,
the learning interface's, the safety filter's and the training run's parameters.
"""

from __future__ import annotations

import dataclasses
import difflib
import inspect
import math
from collections.abc import Callable, Mapping, Sequence
from types import SimpleNamespace
from typing import Any, ClassVar

import numpy as np

from pairflock_env.compat import upgrade_stored
from pairflock_env.config.fields import Field, UnknownFieldError, fmt_num, show

__all__ = [
    "Derived",
    "Record",
    "Rule",
    "Schema",
    "Section",
    "declare_record",
    "refresh_signature",
]


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

    A schema grows by :meth:`add` (a plug-in's section, see ``docs/extending.md``); records
    built before that keep the fields they had.
    """

    def __init__(
        self,
        label: str,
        sections: Sequence[Section],
        rules: Sequence[Rule] = (),
        derived: Sequence[Derived] = (),
    ) -> None:
        self.label = label
        self.sections: tuple[Section, ...] = ()
        self.rules: tuple[Rule, ...] = ()
        self.derived: tuple[Derived, ...] = ()
        self.fields: dict[str, Field] = {}
        self.section_of: dict[str, str] = {}
        self.add(sections, rules, derived)

    def add(
        self,
        sections: Sequence[Section] = (),
        rules: Sequence[Rule] = (),
        derived: Sequence[Derived] = (),
    ) -> None:
        """Declare more sections, rules and derived quantities (checked like the first ones;
        ``RuntimeError`` for a field declared twice or a rule over undeclared fields, and the
        schema is left as it was)."""
        fields, section_of = dict(self.fields), dict(self.section_of)
        for sec in sections:
            if any(s.name == sec.name for s in self.sections):
                raise RuntimeError(f"section {sec.name!r} is declared twice")
            for f in sec.fields:
                if f.name in fields:
                    raise RuntimeError(f"field {f.name!r} is declared twice")
                fields[f.name] = f
                section_of[f.name] = sec.name
        all_rules = (*self.rules, *rules)
        all_derived = (*self.derived, *derived)
        for r in (*rules, *derived):
            missing = set(r.fields) - set(fields)
            if missing:
                raise RuntimeError(f"rule {r.doc!r} names undeclared fields {sorted(missing)}")
        order = _dependency_order(fields)
        # each rule is checked as soon as the last of its fields is (earliest error first)
        position = {name: i for i, name in enumerate(order)}
        ready: dict[str, list[Rule | Derived]] = {}
        for r in (*all_rules, *all_derived):
            last = max(r.fields, key=position.__getitem__)
            ready.setdefault(last, []).append(r)
        self.sections = (*self.sections, *sections)
        self.fields, self.section_of = fields, section_of
        self.rules, self.derived = all_rules, all_derived
        self.order, self._ready = order, ready

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

    def resolve(self, values: Mapping[Any, Any]) -> dict[str, Any]:
        """``values`` as a dict, after checking that every name is a field
        (:class:`~.fields.UnknownFieldError` with a did-you-mean hint otherwise)."""
        for key in values:
            if key not in self.fields:
                raise self.unknown(key)
        return dict(values)

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


def _restore(cls: type[Record], values: Mapping[str, Any]) -> Record:
    """Unpickle: rebuild and validate (a pickle is data, and data is checked)."""
    return cls._create(values, tuple(values))


class Record:
    """A frozen, validated record of the fields of a :class:`Schema` (a config, or the
    parameters of a learning interface, a safety filter or a training run).

    The constructor takes keywords only and validates them; attributes read the values;
    :meth:`replace` makes a changed copy, :meth:`to_dict` / :meth:`from_dict` store and load
    one. Equality, hashing and ``repr`` go by the declared fields; assigning to an attribute
    raises ``dataclasses.FrozenInstanceError``; unpickling validates again.
    """

    schema: ClassVar[Schema]
    #: the kind of stored mapping :meth:`from_dict` reads (see :mod:`pairflock_env.compat`)
    stored_as: ClassVar[str | None] = None

    def __init__(self, **values: Any) -> None:
        resolved = self.schema.resolve(values)
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
        """Rebuild a record from :meth:`to_dict` output, e.g. one stored with a trained model
        (the keys of older releases are read through
        :func:`pairflock_env.compat.upgrade_stored`); unknown names raise ``TypeError``."""
        if not isinstance(data, Mapping):
            raise TypeError(f"data={show(data)} is invalid: must be a mapping of field values")
        if cls.stored_as is not None:
            data = upgrade_stored(cls.stored_as, data)
        values = cls.schema.resolve(data)
        return cls._create(values, tuple(values))

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python dict (JSON/YAML friendly: tuples become lists) of every field."""
        return {name: _plain(getattr(self, name)) for name in self._names()}

    def replace(self, **overrides: Any) -> Any:
        """A copy with some fields changed (validated like the constructor). Fields that were
        derived (``auto``) are derived again, and a vector given as one number follows a
        change of ``dim`` (or ``d_m`` of ``pairs``)."""
        changed = self.schema.resolve(overrides)
        values = self._given()
        values.update(changed)
        return self._create(values, tuple(changed))

    def _names(self) -> tuple[str, ...]:
        """The fields this record holds (a plug-in may declare more after it was built)."""
        return tuple(n for n in self.schema.fields if n in self.__dict__)

    def _given(self) -> dict[str, Any]:
        """The values as a user could have given them (derived ones left out)."""
        auto = self.__dict__.get("_auto_fields", frozenset())
        fields = self.schema.fields
        return {
            n: fields[n].kind.collapse(getattr(self, n)) for n in self._names() if n not in auto
        }

    def _key(self) -> tuple[Any, ...]:
        return tuple((n, getattr(self, n)) for n in self._names())

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        body = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._names())
        return f"{type(self).__name__}({body})"

    def __setattr__(self, name: str, value: Any) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot delete field {name!r}")

    def __reduce__(self) -> tuple[Any, ...]:
        return (_restore, (type(self), self._given()))


def declare_record(
    name: str, schema: Schema, base: type[Record], module: str, doc: str
) -> type[Record]:
    """A :class:`Record` subclass named ``name`` over ``schema``, with the methods of ``base``
    and a keyword-only constructor that validates. ``module`` is where users import it from
    (so that pickles find it)."""
    cls = type(name, (base,), {"__doc__": doc, "schema": schema, "__module__": module})
    refresh_signature(cls)
    return cls


def refresh_signature(cls: type[Record]) -> None:
    """Give ``cls`` the keyword-only signature of its schema's fields (``help()``,
    ``inspect.signature``); called again when the schema grows."""
    cls.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
        [
            inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY, default=f.default)
            for f in cls.schema.fields.values()
        ]
    )
