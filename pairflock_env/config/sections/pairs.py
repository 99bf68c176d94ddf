"""Sections ``pair_task`` and ``initial_state``: which UAVs are paired, at what distance, with
how much acceleration, and where every UAV starts."""

from __future__ import annotations

import math
from itertools import combinations
from typing import Any

import numpy as np

from pairflock_env.config.fields import (
    Auto,
    Box,
    Choice,
    Field,
    Kind,
    Real,
    Vector,
    invalid,
    sequence_items,
)
from pairflock_env.config.limits import (
    MAX_DISTANCE,
    MAX_GAIN,
    MAX_PLACEMENT_BYTES,
    MAX_POSITION,
    MAX_START_DENSITY,
)
from pairflock_env.config.schema import Derived, Rule, Section

__all__ = [
    "DERIVED",
    "RULES",
    "SECTIONS",
    "corner_diagonals",
    "placement_bytes",
    "start_density",
    "start_half_width",
]

#: half-width of the start box of the paper (m), kept for swarms of up to START_UAVS UAVs
START_HALF_WIDTH = 50.0
START_UAVS = 100


def start_half_width(v: Any) -> float:
    """Default ``swarm_half_width``: the paper's box up to START_UAVS UAVs; larger swarms keep
    the density of START_UAVS UAVs in it, so the side grows as n_uavs^(1/dim) (500 m for
    10,000 UAVs in 2-D)."""
    if v.n_uavs <= START_UAVS:
        return START_HALF_WIDTH
    return START_HALF_WIDTH * (v.n_uavs / START_UAVS) ** (1.0 / v.dim)


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


def corner_diagonals(dim: int) -> np.ndarray:
    """Unit-sign diagonals of the cube, (1, 1[, 1]) first; one per pair in 'corners' mode."""
    out = []
    for k in range(2 ** (dim - 1)):
        signs = [1.0] + [(-1.0 if (k >> (dim - 2 - j)) & 1 else 1.0) for j in range(dim - 1)]
        out.append(signs)
    return np.asarray(out)


def _too_many_corner_pairs(v: Any) -> str | None:
    most = 2 ** (v.dim - 1)
    if v.init == "corners" and len(v.pairs) > most:
        return (
            f'"corners" places at most {most} pairs in {v.dim}-D (one per diagonal): with '
            f'{len(v.pairs)} pairs init must be "random"'
        )
    return None


def _corners_too_close(v: Any) -> str | None:
    """With init="corners" the pair members' fixed start points must be distinct."""
    if v.init != "corners":
        return None
    corner = np.broadcast_to(np.asarray(v.pair_corner, dtype=np.float64), (v.dim,))
    diags = corner_diagonals(v.dim)[: len(v.pairs)]
    pts = np.concatenate([-diags * corner, diags * corner])
    for i, j in combinations(range(len(pts)), 2):
        d = float(np.linalg.norm(pts[i] - pts[j]))
        if d < max(v.min_init_spacing, 1e-9):
            return (
                f'puts two pair members of init="corners" {d:g} m apart, closer than '
                "min_init_spacing: pair_corner must use non-zero offsets on more axes (or use "
                'init="random")'
            )
    return None


def _ball_volume(dim: int, radius: float) -> float:
    return math.pi ** (dim / 2) / math.gamma(dim / 2 + 1) * radius**dim


def start_density(v: Any) -> float:
    """Packing fraction of the start boxes: count x volume of a ball of diameter
    min_init_spacing over the volume of the box grown by that diameter. Every UAV counts in
    the swarm box; with init="random" the paired UAVs also count in their own box."""
    s = v.min_init_spacing
    if s == 0:
        return 0.0
    ball = _ball_volume(v.dim, s / 2)
    half = np.broadcast_to(np.asarray(v.swarm_half_width, dtype=np.float64), (v.dim,))
    out = v.n_uavs * ball / float(np.prod(2 * half + s))
    if v.init == "random":
        corner = np.broadcast_to(np.asarray(v.pair_corner, dtype=np.float64), (v.dim,))
        out = max(out, 2 * len(v.pairs) * ball / float(np.prod(2 * corner + s)))
    return out


def placement_bytes(v: Any) -> int:
    """Peak bytes of the random start placement's temporaries: the neighbour grid that finds
    conflicts (per UAV: its bucket, its slot, about 8 bucket starts and bucket-list entries,
    int64) plus one redraw of dim float64 per UAV; 0 when min_init_spacing is 0 (no
    placement loop). Linear in N."""
    if v.min_init_spacing == 0:
        return 0
    return 8 * v.n_uavs * (v.dim + 12) + 1024


def _crowded(v: Any) -> str | None:
    phi = start_density(v)
    most = MAX_START_DENSITY[v.dim]
    if phi > most:
        return (
            f"packs the start boxes to {phi:.3g} (ball volume fraction), which must be <= "
            f"{most} in {v.dim}-D for random placement: lower min_init_spacing or n_uavs, or "
            'enlarge swarm_half_width (pair_corner for init="random")'
        )
    return None


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

INITIAL_STATE = Section(
    "initial_state",
    "Initial state",
    "Where the UAVs start (at rest).",
    (
        Field(
            "init",
            Choice(("corners", "random")),
            "corners",
            "",
            '"corners": pair members in opposite corners (the paper\'s extreme case); '
            '"random": pair members anywhere in the corner box.',
        ),
        Field(
            "swarm_half_width",
            Box(MAX_POSITION),
            START_HALF_WIDTH,
            "m",
            "Unpaired UAVs start uniform in [-w, w]^dim around swarm_center; one number for "
            "every axis or one per axis.",
            auto=Auto(
                start_half_width,
                ("n_uavs", "dim"),
                f"{START_HALF_WIDTH:g} up to {START_UAVS} UAVs; beyond, the box grows at "
                f"constant density: {START_HALF_WIDTH:g} (n_uavs / {START_UAVS})^(1/dim)",
            ),
        ),
        Field(
            "pair_corner",
            Box(MAX_POSITION),
            90.0,
            "m",
            'Pair members start at swarm_center -/+ this offset on every axis (init="corners"); '
            "one number for every axis or one per axis.",
        ),
        Field(
            "swarm_center",
            Vector(Real(-MAX_POSITION, MAX_POSITION)),
            0.0,
            "m",
            "Centre of the start box; a number for every axis or a sequence of dim.",
        ),
        Field(
            "min_init_spacing",
            Real(0.0, MAX_DISTANCE),
            2.0,
            "m",
            "No two UAVs start closer than this.",
        ),
    ),
)

SECTIONS = (PAIR_TASK, INITIAL_STATE)

_PLACEMENT = ("min_init_spacing", "n_uavs", "swarm_half_width", "pair_corner", "init", "pairs")

RULES = (
    Rule(
        ("init", "pairs", "dim"),
        _too_many_corner_pairs,
        'init="corners" holds at most 2^(dim-1) pairs (one per diagonal)',
    ),
    Rule(
        ("pair_corner", "pairs", "init", "min_init_spacing", "dim"),
        _corners_too_close,
        'init="corners": the fixed pair start points are at least min_init_spacing apart',
    ),
    Rule(
        (*_PLACEMENT, "dim"),
        _crowded,
        "packing fraction of the start boxes <= 0.3 (2-D) or 0.15 (3-D): random placement "
        "with min_init_spacing then succeeds",
    ),
)

DERIVED = (
    Derived(
        "start placement memory",
        ("n_uavs", "min_init_spacing", "dim"),
        placement_bytes,
        0,
        MAX_PLACEMENT_BYTES,
        "bytes",
        "8 N (dim + 12) + 1024 while min_init_spacing > 0",
    ),
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
