"""Section ``reward``: the per-agent penalty terms, collisions and divergence."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pairflock_env.config.fields import Field, Flag, OrNone, Real
from pairflock_env.config.limits import MAX_DISTANCE, MAX_STEP_PENALTY, MAX_WEIGHT
from pairflock_env.config.schema import Derived, Rule, Section

__all__ = ["DERIVED", "RULES", "SECTIONS", "collision_ellipsoid", "largest_step_penalty"]

_WEIGHT = Real(0.0, MAX_WEIGHT)


def largest_step_penalty(v: Any) -> float:
    """The largest penalty of one agent-step: each weight times the bound of its term. While
    a swarm is not diverged every coordinate is within divergence_limit L, so the pair error
    is at most 2 sqrt(dim) L + max(d_m); effort is at most dim (clipped actions); the
    separation and collision terms are at most 1."""
    err = 2 * math.sqrt(v.dim) * v.divergence_limit + max(v.d_m)
    return (
        v.reward_error_weight * err
        + v.reward_effort_weight * v.dim
        + v.reward_separation_weight
        + v.reward_collision_weight
    )


def _start_extent(v: Any) -> float:
    """Largest |coordinate| a UAV can start at."""
    center = np.abs(np.asarray(v.swarm_center, dtype=np.float64))
    half = np.broadcast_to(np.asarray(v.swarm_half_width, dtype=np.float64), (v.dim,))
    corner = np.broadcast_to(np.asarray(v.pair_corner, dtype=np.float64), (v.dim,))
    return float(np.max(center + np.maximum(half, corner)))


def _starts_diverged(v: Any) -> str | None:
    extent = _start_extent(v)
    if extent >= v.divergence_limit:
        return (
            f"must exceed the largest start coordinate |swarm_center| + max(swarm_half_width, "
            f"pair_corner) = {extent:g} m, or every swarm is flagged diverged at reset"
        )
    return None


def collision_ellipsoid(v: Any) -> tuple[float, float] | None:
    """The collision ellipsoid's squared horizontal radius and its squash (collision_distance /
    collision_height)^2, or None for the sphere of radius ``collision_distance``: a pair with
    offset (dx, dy, dz) collides when dx^2 + dy^2 + squash dz^2 < collision_distance^2."""
    if v.collision_height is None:
        return None
    return v.collision_distance**2, (v.collision_distance / v.collision_height) ** 2


def _height_covers_distance(v: Any) -> str | None:
    if v.collision_height is not None and not v.collision_height >= v.collision_distance:
        return (
            f"must be None or >= collision_distance ({v.collision_distance:g} m): the ellipsoid "
            "is taller than wide"
        )
    return None


def _height_needs_3d(v: Any) -> str | None:
    if v.collision_height is not None and v.dim != 3:
        return f"must be None with dim={v.dim} (the ellipsoid's vertical axis needs dim=3)"
    return None


REWARD = Section(
    "reward",
    "Reward, collisions and divergence",
    "r_i = -w_err |e_i| - w_u (||u_i|| / pair_accel_limit)^2 - w_sep max(0, D - s_i) / D "
    "- w_col [s_i < collision_distance], s_i the distance to the nearest non-partner UAV and "
    "D = reward_separation_distance (pairflock_env.task.rewards).",
    (
        Field("reward_error_weight", _WEIGHT, 1.0, "1/m", "Weight w_err of |pair error|."),
        Field(
            "reward_effort_weight",
            _WEIGHT,
            0.01,
            "1",
            "Weight w_u of (||u|| / pair_accel_limit)^2.",
        ),
        Field(
            "reward_separation_weight",
            _WEIGHT,
            1.0,
            "1",
            "Weight w_sep of max(0, D - min_separation) / D, D = reward_separation_distance.",
        ),
        Field(
            "reward_collision_weight",
            _WEIGHT,
            10.0,
            "1",
            "Penalty w_col per step while min_separation < collision_distance.",
        ),
        Field(
            "reward_separation_distance",
            Real(1e-3, MAX_DISTANCE),
            1.0,
            "m",
            "Separation D below which the separation penalty starts.",
        ),
        Field(
            "collision_distance",
            Real(0.0, MAX_DISTANCE),
            0.5,
            "m",
            "Two UAVs closer than this count as a collision (the horizontal radius of the "
            "collision ellipsoid when collision_height is set).",
        ),
        Field(
            "collision_height",
            OrNone(Real(0.0, MAX_DISTANCE, lo_open=True), "a sphere of radius collision_distance"),
            None,
            "m",
            "Vertical radius of the collision ellipsoid, as Crazyswarm measures downwash: two "
            "UAVs count as a collision when (dx^2 + dy^2) / collision_distance^2 + dz^2 / "
            "collision_height^2 < 1 (inter-centre offsets, z up). At least collision_distance; "
            "needs dim=3. It changes the flocking pass's collision count (info collisions, "
            "metric max_collisions); the reward's collision term and terminate_on_collision "
            "keep the sphere (docs/crazyflie.md).",
        ),
        Field(
            "terminate_on_collision",
            Flag(),
            False,
            "",
            "End the episode (terminated) when a paired UAV collides.",
        ),
        Field(
            "divergence_limit",
            Real(1e-3, 1e9),
            1e6,
            "m, m/s",
            "A swarm whose |position| or |velocity| exceeds this, or turns non-finite, is "
            "flagged diverged and its episode ends.",
        ),
    ),
)

SECTIONS = (REWARD,)

RULES = (
    Rule(
        ("collision_height", "collision_distance"),
        _height_covers_distance,
        "collision_height (when set) >= collision_distance",
    ),
    Rule(("collision_height", "dim"), _height_needs_3d, "collision_height (when set) needs dim=3"),
    Rule(
        ("divergence_limit", "swarm_center", "swarm_half_width", "pair_corner", "dim"),
        _starts_diverged,
        "divergence_limit > the largest start coordinate",
    ),
)

DERIVED = (
    Derived(
        "largest per-step penalty",
        (
            "reward_error_weight",
            "reward_effort_weight",
            "reward_separation_weight",
            "reward_collision_weight",
            "divergence_limit",
            "d_m",
            "dim",
        ),
        largest_step_penalty,
        0.0,
        MAX_STEP_PENALTY,
        "",
        "w_err (2 sqrt(dim) divergence_limit + max d_m) + w_u dim + w_sep + w_col",
    ),
    Derived(
        "collision_distance^2",
        ("collision_distance",),
        lambda v: v.collision_distance**2,
        0.0,
        MAX_DISTANCE**2,
        "m^2",
        "squared collision distance of the flocking pass",
    ),
)
