"""Sections ``observation`` and ``robustness``: what each agent observes, and the imperfections
the paper's proofs assume away (noise, delay, disturbance); plus the memory they cost."""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import Field, Int, Real
from pairflock_env.config.limits import (
    MAX_DELAY_BYTES,
    MAX_GAIN,
    MAX_OBS_NEIGHBORS,
    MAX_PARTNER_DELAY,
    MAX_SWARM_BYTES,
)
from pairflock_env.config.schema import Derived, Section

__all__ = ["DERIVED", "SECTIONS", "delay_buffer_bytes", "obs_size", "swarm_bytes"]


def obs_size(dim: int, k: int) -> int:
    """Length of one agent's observation (pairflock_env.task.observations.ObsLayout)."""
    return 6 * dim + 2 + k * (2 * dim + 1)


def delay_buffer_bytes(v: Any) -> int:
    """Bytes of the partner-delay ring buffer of one swarm: (q, p, flocking command) of every
    agent over partner_delay + 1 steps."""
    if v.partner_delay == 0:
        return 0
    return 3 * (v.partner_delay + 1) * 2 * len(v.pairs) * v.dim * 8


def swarm_bytes(v: Any) -> int:
    """Bytes of the per-swarm arrays that grow with the config: state and flocking command
    (N x dim, float64), the float32 observation (agents x obs_size) and the neighbour
    offsets, velocities and mask (agents x K x (2 dim + 1), float64)."""
    n, d, m, k = v.n_uavs, v.dim, 2 * len(v.pairs), v.obs_neighbors
    return 8 * 3 * n * d + 4 * m * obs_size(d, k) + 8 * m * k * (2 * d + 1)


_NOISE = Real(0.0, MAX_GAIN)

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
    ),
)

ROBUSTNESS = Section(
    "robustness",
    "Robustness",
    "Noise, delay and disturbances (all off in the paper).",
    (
        Field(
            "obs_noise_position",
            _NOISE,
            0.0,
            "m",
            "Std of white Gaussian noise on the observed partner offset y, per axis and step.",
        ),
        Field(
            "obs_noise_velocity",
            _NOISE,
            0.0,
            "m/s",
            "Std of white Gaussian noise on the observed relative velocity y'.",
        ),
        Field(
            "partner_delay",
            Int(0, MAX_PARTNER_DELAY),
            0,
            "steps",
            "Communication delay of the partner's state (position, velocity, flocking "
            "command) as each agent sees it.",
        ),
        Field(
            "disturbance_std",
            _NOISE,
            0.0,
            "m/s^2",
            "Std of a random acceleration added to every UAV's command, per axis, drawn each "
            "control period and held over it.",
        ),
    ),
)

SECTIONS = (OBSERVATION, ROBUSTNESS)

DERIVED = (
    Derived(
        "partner-delay buffer",
        ("partner_delay", "pairs", "dim"),
        delay_buffer_bytes,
        0,
        MAX_DELAY_BYTES,
        "bytes per swarm",
        "3 (partner_delay + 1) x 2 len(pairs) x dim x 8",
    ),
    Derived(
        "swarm arrays",
        ("n_uavs", "obs_neighbors", "pairs", "dim"),
        swarm_bytes,
        0,
        MAX_SWARM_BYTES,
        "bytes per swarm",
        "24 N dim + 4 M obs_size + 8 M K (2 dim + 1), M = 2 len(pairs), K = obs_neighbors",
    ),
)
