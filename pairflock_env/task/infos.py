"""What a core step returns: the :class:`StepResult` arrays, the names of the infos, and the
two functions that assemble the infos and keep them finite for a diverged swarm.

Infos are arrays with leading axis B: per agent (B, M) (``AGENT_INFO_KEYS`` and the reward
terms ``reward_<term>``), per swarm (B,) (``SWARM_INFO_KEYS``), plus the vehicle model's own
(see its ``info()``). All values are true (never delayed or noisy). Per swarm,
``swarm_min_separation`` is the smallest distance between any two UAVs (partners included),
whether a filter is on or not; ``swarm_filter_active`` / ``swarm_filter_infeasible`` count the
UAVs whose command the safety stage changed for safety / for which no command met every
constraint (the paired UAVs under ``safety_scope="pairs"``, every UAV under ``"swarm"``).

A diverged swarm (``diverged``: its state ran beyond ``divergence_limit`` or turned
non-finite) keeps its last finite observation, and its infos that describe the state (every
key but ``LIVE_INFO_KEYS``) keep their last finite values too, so that every number a step
returns is finite; ``diverged`` is True and the episode ends.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

__all__ = [
    "AGENT_INFO_KEYS",
    "COMMAND_INFO_KEYS",
    "FLOCK_INFO_KEYS",
    "LIVE_INFO_KEYS",
    "PAIR_INFO_KEYS",
    "SAFETY_INFO_KEYS",
    "SAFETY_SWARM_INFO_KEYS",
    "SWARM_INFO_KEYS",
    "StepResult",
    "hold_last_finite",
    "make_info",
]

#: the pair quantities of every agent, (B, M), as the neighbour pass gives them
PAIR_INFO_KEYS = (
    "pair_distance",
    "pair_error",
    "sliding_surface",
    "min_separation",
    "shared_neighbors",
)
#: what the step did to each agent's command, (B, M)
COMMAND_INFO_KEYS = ("pair_accel", "action_clipped")
#: per-agent infos of the safety stage, (B, M) (every filter reports these)
SAFETY_INFO_KEYS = ("safety_active", "safety_correction", "safety_infeasible")
#: per-agent info arrays, shape (B, M)
AGENT_INFO_KEYS = (*PAIR_INFO_KEYS, *COMMAND_INFO_KEYS, *SAFETY_INFO_KEYS)
#: the neighbour pass's per-swarm quantities, (B,)
FLOCK_INFO_KEYS = (
    "collisions",
    "largest_component",
    "velocity_mismatch",
    "velocity_mismatch_max",
    "swarm_min_separation",
)
#: per-swarm counts of the safety stage, (B,): UAVs whose command it changed for safety, and
#: UAVs with no command meeting every constraint (a stage that reports only the per-agent
#: keys gets the counts over its agents)
SAFETY_SWARM_INFO_KEYS = ("swarm_filter_active", "swarm_filter_infeasible")
#: per-swarm info arrays, shape (B,)
SWARM_INFO_KEYS = ("sim_time", *FLOCK_INFO_KEYS, *SAFETY_SWARM_INFO_KEYS, "diverged")
#: infos that describe the step itself (clock, applied command, flag), not the state: always
#: current, also for a diverged swarm
LIVE_INFO_KEYS = (
    *COMMAND_INFO_KEYS,
    *SAFETY_INFO_KEYS,
    "sim_time",
    *SAFETY_SWARM_INFO_KEYS,
    "diverged",
)


@dataclasses.dataclass
class StepResult:
    """What one core step (or reset) returns; every array has leading axis B.

    The arrays are new at every step; the core keeps reading the latest ``obs`` and ``info``
    (a diverged swarm repeats its last finite values), so copy them before changing them.
    """

    obs: np.ndarray
    """(B, M, obs_size) float32, finite."""
    reward: np.ndarray
    """(B, M) float64."""
    terminated: np.ndarray
    """(B,) bool: divergence, or a collision when ``terminate_on_collision``."""
    truncated: np.ndarray
    """(B,) bool: the episode reached ``episode_steps``."""
    info: dict[str, np.ndarray]
    """Arrays named in AGENT_INFO_KEYS (B, M), SWARM_INFO_KEYS (B,) and reward terms (B, M)."""


def make_info(
    pair: Mapping[str, np.ndarray],
    flock: Mapping[str, np.ndarray],
    u: np.ndarray,
    clipped: np.ndarray,
    sim_time: np.ndarray,
    diverged: np.ndarray,
    terms: Mapping[str, np.ndarray],
    safety: Mapping[str, np.ndarray],
    pair_accel: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The core's infos of one step (fresh arrays; see the module docstring).

    Args:
        pair: the agents' pair quantities ``PAIR_INFO_KEYS`` (B, M).
        flock: the neighbour pass's outputs, ``FLOCK_INFO_KEYS`` (B,); copied.
        u: the applied pair command (B, M, dim), m/s^2; clipped: (B, M) bool.
        sim_time: (B,) s (copied); diverged: (B,) bool; terms: reward terms (B, M).
        safety: the safety stage's infos (``SAFETY_INFO_KEYS`` (B, M), optionally
            ``SAFETY_SWARM_INFO_KEYS`` (B,), and any of its own).
        pair_accel: ||u|| (B, M) when already computed (the core's agents' pass has it).
    """
    info = {k: pair[k] for k in PAIR_INFO_KEYS}
    info["pair_accel"] = (
        np.sqrt(np.einsum("bmk,bmk->bm", u, u)) if pair_accel is None else pair_accel
    )
    info["action_clipped"] = clipped
    info.update((k, v) for k, v in safety.items() if k not in SAFETY_SWARM_INFO_KEYS)
    info["sim_time"] = sim_time.copy()
    for k in FLOCK_INFO_KEYS:
        info[k] = flock[k].copy()
    counted = ("safety_active", "safety_infeasible")
    for k, per_agent in zip(SAFETY_SWARM_INFO_KEYS, counted, strict=True):
        info[k] = safety[k] if k in safety else np.count_nonzero(safety[per_agent], axis=1)
    info["diverged"] = diverged
    for k, v in terms.items():
        info[f"reward_{k}"] = v
    return info


def hold_last_finite(
    info: dict[str, np.ndarray], last: Mapping[str, np.ndarray] | None, rows: np.ndarray
) -> None:
    """In place: swarms ``rows`` (bool mask (B,)) keep every info of ``info`` but
    ``LIVE_INFO_KEYS`` at its value in ``last``, the infos of the previous step (zeros when
    there is none)."""
    for k, v in info.items():
        if k not in LIVE_INFO_KEYS:
            v[rows] = 0 if last is None else last[k][rows]
