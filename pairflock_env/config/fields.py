"""Declared fields: what a configuration field is, and how a value given for it is checked.

A :class:`Field` names a value and gives its :class:`Kind` (type and valid range), default,
unit and meaning. A kind normalises what users write (a scalar broadcast to a vector, numpy
scalars to Python numbers, lists to tuples) and raises ``TypeError`` for a wrong type and
``ValueError`` for a value out of range, each message naming the field, the value and what is
valid. Kinds that depend on other fields (a vector's length is ``dim``) list them in
``needs``; the schema checks fields in an order that respects these dependencies.
"""

from __future__ import annotations

import dataclasses
import math
import reprlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "Auto",
    "Box",
    "Choice",
    "Field",
    "Flag",
    "Int",
    "Kind",
    "OrNone",
    "Real",
    "UnknownFieldError",
    "Vector",
    "fmt_num",
    "invalid",
    "sequence_items",
    "show",
]


class UnknownFieldError(TypeError, ValueError):
    """An unknown keyword. A ``TypeError``, as Python raises for an unexpected keyword argument
    (wrappers such as TorchRL's ``GymEnv`` rely on that), and also a ``ValueError`` so that
    code written against releases that raised ``ValueError`` keeps working."""


_REPR = reprlib.Repr()
_REPR.maxstring = 60
_REPR.maxother = 60
_REPR.maxlist = _REPR.maxtuple = 8
_REPR.maxlong = 30


def show(value: Any) -> str:
    """A short repr for messages: long sequences, big arrays and huge numbers are abbreviated."""
    if isinstance(value, np.ndarray) and value.size > 8:
        return f"array(shape={value.shape}, dtype={value.dtype})"
    return _REPR.repr(value)


def invalid(name: str, value: Any, valid: str, exc: type[Exception] = ValueError) -> Exception:
    """The project's error for a bad value: ``name=value is invalid: <what is valid>``."""
    return exc(f"{name}={show(value)} is invalid: {valid}")


def fmt_num(x: Any) -> str:
    """A number as the docs and messages write it: 1e6, 2.98e-6, 0.632, 100_000."""
    if isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_)):
        return f"{int(x):_}" if abs(int(x)) >= 10_000 else str(int(x))
    if isinstance(x, (float, np.floating)):
        x = float(x)
        if not math.isfinite(x):
            return str(x)
        plain = f"{x:.6g}"
        mant, exp = f"{x:.5e}".split("e")
        mant = mant.rstrip("0").rstrip(".")
        short = f"{mant}e{int(exp)}"
        # the exponent form when it is clearly shorter (1e5, 1e-6), else the plain one
        return short if "e" in plain or len(short) + 2 <= len(plain) else plain
    return repr(x)


def sequence_items(value: Any) -> list[Any] | None:
    """The elements of a sequence or an array with at least one axis; None for anything else
    (numbers, strings, 0-d arrays, sets, mappings), which callers treat as one scalar."""
    if isinstance(value, (str, bytes)):
        return None
    if isinstance(value, np.ndarray):
        return None if value.ndim == 0 else list(value)
    if isinstance(value, Sequence):
        return list(value)
    return None


class Kind:
    """How the value of one field is checked and normalised (subclasses hold the range)."""

    #: Python annotation of the normalised value (for the generated dataclass)
    annotation: Any = Any
    #: the type as the docs table writes it
    type_name = "value"

    @property
    def needs(self) -> tuple[str, ...]:
        """Fields whose (normalised) values :meth:`check` reads from its context."""
        return ()

    def check(self, name: str, value: Any, ctx: Mapping[str, Any]) -> Any:
        """The normalised value, or ``TypeError``/``ValueError`` naming ``name``."""
        raise NotImplementedError

    def valid(self) -> str:
        """What is valid, in words (for messages and the docs table)."""
        raise NotImplementedError

    def collapse(self, value: Any) -> Any:
        """The value as a user could have written it, so that ``replace`` re-broadcasts a
        scalar when the field it depends on (``dim``, ``pairs``) changes."""
        return value


@dataclasses.dataclass(frozen=True)
class Int(Kind):
    """An integer in [lo, hi] (bools and floats are refused)."""

    lo: int
    hi: int
    annotation = int
    type_name = "int"

    def valid(self) -> str:
        return f"an integer in [{fmt_num(self.lo)}, {fmt_num(self.hi)}]"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> int:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        v = int(value)
        if not self.lo <= v <= self.hi:
            raise invalid(name, value, f"must be {self.valid()}")
        return v


def _to_float(value: Any) -> float:
    if isinstance(value, float):  # also np.float64
        return float(value)
    try:
        if isinstance(value, np.floating):  # np.longdouble beyond float64 casts to inf
            with np.errstate(over="ignore"):
                return float(value)
        return float(value)
    except OverflowError:  # a Python int beyond the float range
        return math.inf


@dataclasses.dataclass(frozen=True)
class Real(Kind):
    """A finite real number in [lo, hi] (or an open end), stored as a Python float."""

    lo: float
    hi: float
    lo_open: bool = False
    hi_open: bool = False
    annotation = float
    type_name = "float"

    def interval(self) -> str:
        a = "(" if self.lo_open else "["
        b = ")" if self.hi_open else "]"
        return f"{a}{fmt_num(float(self.lo))}, {fmt_num(float(self.hi))}{b}"

    def valid(self) -> str:
        return f"a finite number in {self.interval()}"

    def contains(self, v: float) -> bool:
        above = v > self.lo if self.lo_open else v >= self.lo
        below = v < self.hi if self.hi_open else v <= self.hi
        return math.isfinite(v) and above and below

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> float:
        if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (int, float, np.integer, np.floating)
        ):
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        v = _to_float(value)
        if not self.contains(v):
            raise invalid(name, value, f"must be {self.valid()}")
        return v


@dataclasses.dataclass(frozen=True)
class Choice(Kind):
    """One of a few strings."""

    options: tuple[str, ...]
    annotation = str
    type_name = "str"

    def valid(self) -> str:
        return "one of " + ", ".join(map(repr, self.options))

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> str:
        if not isinstance(value, str):
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        if value not in self.options:
            raise invalid(name, value, f"must be {self.valid()}")
        return str(value)


@dataclasses.dataclass(frozen=True)
class Flag(Kind):
    """True or False (numpy bools accepted, stored as Python bools)."""

    annotation = bool
    type_name = "bool"

    def valid(self) -> str:
        return "True or False"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> bool:
        if not isinstance(value, (bool, np.bool_)):
            raise invalid(name, value, "must be a bool (True or False)", TypeError)
        return bool(value)


@dataclasses.dataclass(frozen=True)
class OrNone(Kind):
    """None (with the stated meaning) or a value of ``kind``."""

    kind: Kind
    meaning: str

    @property
    def annotation(self) -> Any:  # type: ignore[override]
        return self.kind.annotation | None

    @property
    def type_name(self) -> str:  # type: ignore[override]
        return f"{self.kind.type_name} or None"

    @property
    def needs(self) -> tuple[str, ...]:
        return self.kind.needs

    def valid(self) -> str:
        return f"None ({self.meaning}) or {self.kind.valid()}"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any]) -> Any:
        if value is None:
            return None
        try:
            return self.kind.check(name, value, ctx)
        except (TypeError, ValueError) as e:
            raise type(e)(f"{e} (or None: {self.meaning})") from None


@dataclasses.dataclass(frozen=True)
class Vector(Kind):
    """A tuple of ``length`` numbers (``"dim"``: the config's dim); one number is broadcast."""

    elem: Real
    length: int | str = "dim"
    annotation = tuple
    type_name = "float or tuple"

    @property
    def needs(self) -> tuple[str, ...]:
        return ("dim",) if self.length == "dim" else ()

    def valid(self) -> str:
        n = self.length if self.length == "dim" else str(self.length)
        return f"one number (every axis) or {n} numbers, each in {self.elem.interval()}"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any]) -> tuple[float, ...]:
        n = int(ctx["dim"]) if self.length == "dim" else int(self.length)
        items = sequence_items(value)
        if items is None:
            return (self.elem.check(name, value),) * n
        if len(items) != n:
            dims = f" (dim={n})" if self.length == "dim" else ""
            raise invalid(name, value, f"must be a number or a sequence of {n} numbers{dims}")
        return tuple(self.elem.check(f"{name}[{i}]", x) for i, x in enumerate(items))

    def collapse(self, value: Any) -> Any:
        if isinstance(value, tuple) and value and all(x == value[0] for x in value):
            return value[0]
        return value


@dataclasses.dataclass(frozen=True)
class Box(Kind):
    """Half-widths of a box: one number > 0 (kept as a number) or ``dim`` numbers >= 0, not
    all 0."""

    hi: float
    annotation = Any
    type_name = "float or tuple"

    @property
    def needs(self) -> tuple[str, ...]:
        return ("dim",)

    def valid(self) -> str:
        return (
            f"one number in (0, {fmt_num(self.hi)}] (every axis) or dim numbers in "
            f"[0, {fmt_num(self.hi)}], not all 0"
        )

    def check(self, name: str, value: Any, ctx: Mapping[str, Any]) -> float | tuple[float, ...]:
        items = sequence_items(value)
        if items is None:
            return Real(0.0, self.hi, lo_open=True).check(name, value)
        comps = Vector(Real(0.0, self.hi)).check(name, value, ctx)
        if max(comps) <= 0:
            raise invalid(name, value, "components must be >= 0 and not all 0")
        return comps


@dataclasses.dataclass(frozen=True)
class Auto:
    """A default computed from other fields when the user does not set the field."""

    rule: Callable[[Any], Any]
    needs: tuple[str, ...]
    doc: str


@dataclasses.dataclass(frozen=True)
class Field:
    """One declared field: name, kind (type and valid range), default, unit and meaning.

    ``auto`` replaces the default by a value derived from other fields unless the user sets
    this one.
    """

    name: str
    kind: Kind
    default: Any
    unit: str
    doc: str
    auto: Auto | None = None

    @property
    def needs(self) -> tuple[str, ...]:
        return (*self.kind.needs, *(self.auto.needs if self.auto else ()))
