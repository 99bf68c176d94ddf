"""Section ``pair_task``: which UAVs are paired, at what distance, with how much acceleration
(Sec. IV)."""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.config.fields import Field, Kind, Real, invalid, sequence_items
from pairflock_env.config.limits import MAX_DISTANCE, MAX_GAIN
from pairflock_env.config.schema import Derived, Section

__all__ = ["DERIVED", "SECTIONS", "Pairs", "PerPair"]


class Pairs(Kind):
    """A non-empty sequence of disjoint (A, B) pairs of UAV indices (stored as tuples)."""

    annotation = tuple
    type_name = "tuple of pairs"

    @property
    def needs(self) -> tuple[str, ...]:
        return ("n_uavs",)

    def valid(self) -> str:
        return "a non-empty sequence of disjoint (A, B) pairs of UAV indices in [0, n_uavs)"

    def check(self, name: str, value: Any, ctx: Any) -> tuple[tuple[int, int], ...]:
        n = ctx["n_uavs"]
        pairs = sequence_items(value)
        if pairs is None:
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        if not pairs:
            raise invalid(name, value, "must be a non-empty sequence of (A, B) index pairs")
        norm: list[tuple[int, int]] = []
        seen: set[int] = set()
        for pr in pairs:
            items = sequence_items(pr)
            if items is None or len(items) != 2:
                raise invalid(name, value, "each pair must be two integer UAV indices (A, B)")
            if any(
                isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer))
                for x in items
            ):
                raise invalid(name, value, "each pair must be two integer UAV indices (A, B)")
            a, b = int(items[0]), int(items[1])
            if not (0 <= a < n and 0 <= b < n):
                raise invalid(name, value, f"indices must be in [0, {n - 1}] (n_uavs={n})")
            if a == b or a in seen or b in seen:
                raise invalid(name, value, "pairs must be disjoint: no UAV may appear twice")
            seen.update((a, b))
            norm.append((a, b))
        return tuple(norm)


class PerPair(Kind):
    """One number for every pair, or one per pair (stored as a tuple of len(pairs))."""

    annotation = tuple
    type_name = "float or tuple"

    def __init__(self, elem: Real) -> None:
        self.elem = elem

    @property
    def needs(self) -> tuple[str, ...]:
        return ("pairs",)

    def valid(self) -> str:
        return f"one number or one per pair, each in {self.elem.interval()}"

    def check(self, name: str, value: Any, ctx: Any) -> tuple[float, ...]:
        p = len(ctx["pairs"])
        items = sequence_items(value)
        if items is None:
            return (self.elem.check(name, value),) * p
        if len(items) != p:
            raise invalid(name, value, f"must be one number or {p} numbers (one per pair)")
        return tuple(self.elem.check(f"{name}[{i}]", x) for i, x in enumerate(items))

    def collapse(self, value: Any) -> Any:
        if isinstance(value, tuple) and value and all(x == value[0] for x in value):
            return value[0]
        return value


PAIR_TASK = Section(
    "pair_task",
    "Pair task (Sec. IV)",
    "The pairs, their desired distance and the bound on the pair action.",
    (
        Field(
            "pairs",
            Pairs(),
            ((0, 1),),
            "indices",
            "Disjoint pairs (A, B) of UAV indices; y = q_B - q_A (eq. 21).",
        ),
        Field(
            "d_m",
            PerPair(Real(1e-3, MAX_DISTANCE)),
            5.0,
            "m",
            "Desired pair distance d_m: one value for every pair or one per pair.",
        ),
        Field(
            "surface_slope",
            Real(1e-6, MAX_GAIN),
            4.0,
            "1/s",
            "Slope c of the sliding surface s = c e + e' (eq. 26) used in infos and metrics; "
            "the sliding-mode baseline uses the same value unless told otherwise.",
        ),
        Field(
            "pair_accel_limit",
            Real(1e-6, MAX_GAIN),
            1000.0,
            "m/s^2",
            "Bound on each component of a pair action (action 1.0 = this acceleration).",
        ),
    ),
)

SECTIONS = (PAIR_TASK,)

DERIVED = (
    Derived(
        "pair_accel_limit^2",
        ("pair_accel_limit",),
        lambda v: v.pair_accel_limit**2,
        1e-12,
        MAX_GAIN**2,
        "m^2/s^4",
        "normalises the effort term of the reward",
    ),
)
