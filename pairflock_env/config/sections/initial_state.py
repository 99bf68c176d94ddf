"""Section ``initial_state``: where every UAV starts, and the checks that make a random
placement succeed."""

from __future__ import annotations

import math
from itertools import combinations
from typing import Any

import numpy as np

from pairflock_env.config.fields import Auto, Box, Choice, Field, Real, Vector
from pairflock_env.config.limits import (
    MAX_DISTANCE,
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

SECTIONS = (INITIAL_STATE,)

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
)
