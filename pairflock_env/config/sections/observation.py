"""Section ``observation``: what each agent observes, and the memory its arrays cost."""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import Field, Int
from pairflock_env.config.limits import MAX_OBS_NEIGHBORS, MAX_SWARM_BYTES
from pairflock_env.config.registry import OBSERVATIONS, RegisteredNames
from pairflock_env.config.schema import Derived, Section

__all__ = ["DERIVED", "SECTIONS", "obs_size", "swarm_bytes"]


def base_obs_size(dim: int, k: int) -> int:
    """Length of the built-in part of one agent's observation
    (pairflock_env.task.observations.ObsLayout)."""
    return 6 * dim + 2 + k * (2 * dim + 1)


def obs_size(v: Any) -> int:
    """Length of one agent's observation: the built-in fields and ``obs_extra``."""
    extra = sum(OBSERVATIONS[name].size(v.dim, v.obs_neighbors) for name in v.obs_extra)
    return base_obs_size(v.dim, v.obs_neighbors) + extra


def swarm_bytes(v: Any) -> int:
    """Bytes of the per-swarm arrays that grow with the config: state and flocking command
    (N x dim, float64), the float32 observation (agents x obs_size) and the neighbour
    offsets, velocities and mask (agents x K x (2 dim + 1), float64)."""
    n, d, m, k = v.n_uavs, v.dim, 2 * len(v.pairs), v.obs_neighbors
    return 8 * 3 * n * d + 4 * m * obs_size(v) + 8 * m * k * (2 * d + 1)


OBSERVATION = Section(
    "observation",
    "Observation",
    "What each paired UAV (agent) observes (docs: observation layout).",
    (
        Field(
            "obs_neighbors",
            Int(0, MAX_OBS_NEIGHBORS),
            6,
            "UAVs",
            "Number K of nearest non-partner UAVs in each agent's observation.",
        ),
        Field(
            "obs_extra",
            RegisteredNames(OBSERVATIONS),
            (),
            "",
            "Registered observation fields appended after the built-in ones, in this order "
            "(pairflock_env.task.observations.OBSERVATIONS; none are built in).",
        ),
    ),
)

SECTIONS = (OBSERVATION,)

DERIVED = (
    Derived(
        "swarm arrays",
        ("n_uavs", "obs_neighbors", "obs_extra", "pairs", "dim"),
        swarm_bytes,
        0,
        MAX_SWARM_BYTES,
        "bytes per swarm",
        "24 N dim + 4 M obs_size + 8 M K (2 dim + 1), M = 2 len(pairs), K = obs_neighbors",
    ),
)
