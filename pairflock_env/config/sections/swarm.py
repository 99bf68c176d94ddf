"""Sections ``meta``, ``swarm`` and ``timing``: who flies, in how many dimensions, how fast
the clock ticks and how long an episode lasts."""

from __future__ import annotations

import math
from typing import Any

from pairflock_env.config.fields import Auto, Choice, Field, Int, Kind, OrNone, Real
from pairflock_env.config.limits import MAX_EPISODE_STEPS, MAX_SUBSTEPS, MAX_TIME, MAX_UAVS
from pairflock_env.config.schema import Derived, Rule, Section

__all__ = [
    "DERIVED",
    "GRID_MIN_UAVS",
    "RULES",
    "SECTIONS",
    "episode_steps",
    "physics_dt",
    "quad_min_substeps",
    "uses_grid",
]

#: smallest swarm for which neighbor_search="auto" picks the grid. Measured (core step,
#: UAV-steps/s, grid / all pairs, one thread, CPU time): over rollouts of 20 steps from the
#: start and the lattice states (``python benchmarks/bench_core.py --cpu-time --quick
#: --sections threshold``) the grid is 0.68-1.25x at N = 100, 1.09-1.63x at 150, 1.20-1.96x
#: at 200 and 1.64-2.18x at 250 (B = 1 and 64); free-running from reset, where the swarm
#: contracts and packs denser, it was 0.75-0.95x at 150, 0.93-1.18x at 200 and 1.36-1.69x
#: at 300. From 250 UAVs the grid wins in every case measured.
GRID_MIN_UAVS = 250


def uses_grid(v: Any) -> bool:
    """Whether the neighbour search of config ``v`` is the grid (``neighbor_search``, with
    "auto" resolved by ``n_uavs``)."""
    if v.neighbor_search == "auto":
        return v.n_uavs >= GRID_MIN_UAVS
    return v.neighbor_search == "grid"


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


def episode_steps(v: Any) -> int:
    """Control steps per episode: ``max_cycles``, or ``round(horizon / dt)`` (at least 1)."""
    if v.max_cycles is not None:
        return int(v.max_cycles)
    return max(1, round(v.horizon / v.dt))


def physics_dt(v: Any) -> float:
    """Physics step dt / substeps (s)."""
    return v.dt / v.substeps


def attitude_rate(v: Any) -> float:
    """Fastest rate of the quadrotor attitude loop (rad/s): the explicit integration needs a
    physics step of at most 0.1 / rate."""
    return max(v.quad_attitude_freq, v.quad_yaw_freq) * max(1.0, 2 * v.quad_attitude_damping)


def quad_min_substeps(v: Any) -> int:
    """Fewest substeps that resolve the quadrotor attitude loop at ``dt`` (capped at the
    substeps limit; the rule then says what to change)."""
    need = math.ceil(v.dt / (0.1 / attitude_rate(v)) - 1e-9)
    return max(1, min(need, MAX_SUBSTEPS))


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

SWARM = Section(
    "swarm",
    "Swarm and vehicle",
    "How many UAVs fly, which vehicle model, in how many dimensions.",
    (
        Field("n_uavs", Int(2, MAX_UAVS), 50, "UAVs", "Number of UAVs N in each swarm."),
        Field(
            "neighbor_search",
            Choice(("auto", "all_pairs", "grid")),
            "auto",
            "",
            'How each step finds neighbours: "all_pairs" (every pair, O(N^2) per swarm), '
            '"grid" (a uniform cell list with cells of max(radius, collision_distance), O(N) '
            'for a flock of bounded density) or "auto" (all pairs up to '
            f"{GRID_MIN_UAVS - 1} UAVs, the grid from {GRID_MIN_UAVS}: the faster one, "
            "measured). Both give the same trajectories.",
        ),
        Field(
            "dynamics",
            Choice(("particle", "quadrotor")),
            "particle",
            "",
            'Vehicle model: "particle" (double integrator, eq. 1) or "quadrotor" (6-DOF rigid '
            "body behind a geometric attitude controller, section quadrotor; needs dim=3).",
        ),
        Field(
            "dim",
            Int(2, 3),
            2,
            "",
            "Spatial dimension (the quadrotor needs 3).",
            auto=Auto(
                lambda v: 3 if v.dynamics == "quadrotor" else 2,
                ("dynamics",),
                '2, or 3 with dynamics="quadrotor"',
            ),
        ),
    ),
)

TIMING = Section(
    "timing",
    "Timing",
    "Control period, physics substeps and episode length.",
    (
        Field(
            "dt",
            Real(1e-6, 1.0),
            0.01,
            "s",
            "Control period: the protocol and the pair action are held over it (zero-order hold).",
        ),
        Field(
            "substeps",
            Int(1, MAX_SUBSTEPS),
            1,
            "steps",
            "Physics substeps per control period (physics step = dt / substeps).",
            auto=Auto(
                lambda v: quad_min_substeps(v) if v.dynamics == "quadrotor" else 1,
                (
                    "dynamics",
                    "dt",
                    "quad_attitude_freq",
                    "quad_yaw_freq",
                    "quad_attitude_damping",
                ),
                '1; with dynamics="quadrotor" the fewest that resolve the attitude loop',
            ),
        ),
        Field(
            "integrator",
            Choice(("semi_implicit", "exact")),
            "semi_implicit",
            "",
            'Particle integrator: "semi_implicit" (symplectic Euler, the paper\'s) or "exact" '
            "(exact solution of the double integrator under a held acceleration).",
        ),
        Field(
            "horizon",
            Real(0.0, MAX_TIME, lo_open=True),
            50.0,
            "s",
            "Episode length (truncation); ignored when max_cycles is set.",
        ),
        Field(
            "max_cycles",
            OrNone(Int(1, MAX_EPISODE_STEPS), "use horizon"),
            None,
            "steps",
            "Episode length in control steps; overrides horizon when given.",
        ),
    ),
)

SECTIONS = (META, SWARM, TIMING)

RULES = (
    Rule(
        ("dim", "dynamics"),
        lambda v: (
            'must be 3 with dynamics="quadrotor"'
            if v.dynamics == "quadrotor" and v.dim != 3
            else None
        ),
        'dim = 3 with dynamics="quadrotor"',
    ),
)

DERIVED = (
    Derived(
        "episode_steps",
        ("horizon", "dt", "max_cycles"),
        episode_steps,
        1,
        MAX_EPISODE_STEPS,
        "steps",
        "max_cycles or round(horizon / dt)",
    ),
    Derived(
        "episode end time",
        ("horizon", "dt", "max_cycles"),
        lambda v: episode_steps(v) * v.dt,
        0.0,
        MAX_TIME,
        "s",
        "episode_steps x dt, the sim time at truncation",
    ),
    Derived(
        "physics_dt",
        ("substeps", "dt"),
        physics_dt,
        1e-10,
        1.0,
        "s",
        "dt / substeps",
    ),
)
