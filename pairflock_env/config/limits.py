"""The documented limits of a configuration: sizes, magnitudes and the budgets they add up to.

Every bound a field declares is one of these constants (or a physical bound written next to
the field), so that ``docs/config.md`` can quote them and a change is made in one place. The
limits are wide enough for every experiment the project runs (the large-swarm work needs
10,000 UAVs) and tight enough that no accepted configuration overflows float64 in a step, runs
for an unbounded time inside a numba loop, or allocates more than the stated memory.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["LIMITS", "Limit"]


class Limit(NamedTuple):
    """One documented limit: its name, value, unit and why it is there."""

    name: str
    value: float
    unit: str
    why: str


MAX_UAVS = 100_000
MAX_SUBSTEPS = 10_000
MAX_EPISODE_STEPS = 1_000_000_000
MAX_TIME = 1e9
MAX_PARTNER_DELAY = 100_000
MAX_OBS_NEIGHBORS = 1_000
MAX_TURNS = 1_000
MAX_POSITION = 1e7
MAX_DISTANCE = 1e5
MAX_SPEED = 1e4
MAX_GAIN = 1e6
MAX_REACTION_TIME = 10.0
MAX_WEIGHT = 1e6
MAX_STEP_PENALTY = 1e15
MAX_DELAY_BYTES = 256 * 2**20
MAX_SWARM_BYTES = 2**30
MAX_PLACEMENT_BYTES = 8 * 2**30
#: largest packing fraction of the start boxes (see ``initial state`` in docs/config.md)
MAX_START_DENSITY = {2: 0.3, 3: 0.15}

LIMITS: tuple[Limit, ...] = (
    Limit("MAX_UAVS", MAX_UAVS, "UAVs", "largest swarm (n_uavs); the large-swarm work needs 10^4"),
    Limit(
        "MAX_SUBSTEPS",
        MAX_SUBSTEPS,
        "steps",
        "physics steps per control step: bounds the time of one step() (the quadrotor loop "
        "cannot be interrupted)",
    ),
    Limit(
        "MAX_EPISODE_STEPS",
        MAX_EPISODE_STEPS,
        "steps",
        "control steps per episode (max_cycles or round(horizon / dt))",
    ),
    Limit("MAX_TIME", MAX_TIME, "s", "episode length and leader times: sim time stays exact"),
    Limit(
        "MAX_PARTNER_DELAY",
        MAX_PARTNER_DELAY,
        "steps",
        "partner delay (the delay buffer is also bounded in bytes)",
    ),
    Limit("MAX_OBS_NEIGHBORS", MAX_OBS_NEIGHBORS, "UAVs", "neighbours in each observation"),
    Limit("MAX_TURNS", MAX_TURNS, "turns", "leader turns (each costs work in every step)"),
    Limit("MAX_POSITION", MAX_POSITION, "m", "largest coordinate of a start point or box"),
    Limit("MAX_DISTANCE", MAX_DISTANCE, "m", "largest spacing, radius, d_m or distance threshold"),
    Limit("MAX_SPEED", MAX_SPEED, "m/s", "largest leader velocity component"),
    Limit(
        "MAX_GAIN",
        MAX_GAIN,
        "SI",
        "largest flocking, pinning and surface gain: with |q|, |p| <= divergence_limit no sum "
        "of the flocking pass overflows",
    ),
    Limit("MAX_WEIGHT", MAX_WEIGHT, "1", "largest reward weight"),
    Limit(
        "MAX_REACTION_TIME",
        MAX_REACTION_TIME,
        "s",
        "largest reaction time of the safety filter, set or derived from the vehicle's lag",
    ),
    Limit(
        "MAX_STEP_PENALTY",
        MAX_STEP_PENALTY,
        "1",
        "largest per-step penalty the reward weights allow (sum of weight x bound of its term): "
        "the return of the longest episode stays far below the float32 maximum",
    ),
    Limit(
        "MAX_DELAY_BYTES",
        MAX_DELAY_BYTES,
        "bytes",
        "partner-delay ring buffer per swarm, 3 (partner_delay + 1) n_agents dim x 8 bytes",
    ),
    Limit(
        "MAX_SWARM_BYTES",
        MAX_SWARM_BYTES,
        "bytes",
        "state, observation and neighbour arrays per swarm (formula in the derived table)",
    ),
    Limit(
        "MAX_PLACEMENT_BYTES",
        MAX_PLACEMENT_BYTES,
        "bytes",
        "temporaries of the random start placement (a neighbour grid, linear in N: far below "
        "this bound for every n_uavs allowed)",
    ),
    Limit(
        "MAX_START_DENSITY",
        MAX_START_DENSITY[2],
        "1",
        "2-D packing fraction of the start boxes (3-D: 0.15): random placement succeeded at "
        "these densities in every trial; denser starts are refused at construction",
    ),
)
