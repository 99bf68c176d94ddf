"""Section ``swarm``: how many UAVs fly, which vehicle model, in how many dimensions, and how
neighbours are found."""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import Auto, Choice, Field, Int
from pairflock_env.config.limits import MAX_UAVS
from pairflock_env.config.registry import VEHICLES, Registered
from pairflock_env.config.schema import Rule, Section

__all__ = ["GRID_MIN_UAVS", "RULES", "SECTIONS", "uses_grid"]

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


def _vehicle_dims(v: Any) -> str | None:
    dims = VEHICLES[v.dynamics].dims
    if v.dim in dims:
        return None
    return f"must be {' or '.join(map(str, dims))} with dynamics={v.dynamics!r}"


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
            '"grid" (a uniform cell list with cells of max(radius, collision_distance, '
            "collision_height), O(N) "
            'for a flock of bounded density) or "auto" (all pairs up to '
            f"{GRID_MIN_UAVS - 1} UAVs, the grid from {GRID_MIN_UAVS}: the faster one, "
            "measured). Both give the same trajectories.",
        ),
        Field(
            "dynamics",
            Registered(VEHICLES, after_sections=True),
            "particle",
            "",
            'Vehicle model (pairflock_env.dynamics.VEHICLES): "particle" (double integrator, '
            'eq. 1) or "quadrotor" (6-DOF rigid body behind a geometric attitude controller, '
            "section quadrotor; needs dim=3), or a registered plug-in.",
        ),
        Field(
            "dim",
            Int(2, 3),
            2,
            "",
            "Spatial dimension (the quadrotor needs 3).",
            auto=Auto(
                lambda v: VEHICLES[v.dynamics].dims[0],
                ("dynamics",),
                'the vehicle model\'s first dimension: 2, or 3 with dynamics="quadrotor"',
            ),
        ),
    ),
)

SECTIONS = (SWARM,)

RULES = (Rule(("dim", "dynamics"), _vehicle_dims, "dim is one the vehicle model flies in"),)
