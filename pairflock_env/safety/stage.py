"""The safety stage of the core's step: the configured filter applied to the decoded pair
command, and its per-agent infos.

A stage is what a :class:`~pairflock_env.safety.Filter` entry builds for a core:
``stage(config, agent_uavs, num_swarms, partner_uavs)`` with :meth:`apply` (the command to
use, from what each UAV senses) and :meth:`info` (at least ``SAFETY_INFO_KEYS``, (B, M)).
:class:`NoFilterStage` (``safety_filter="none"``) returns the command unchanged (the same
array) and reports zeros; :class:`CBFStage` (``"cbf"``) runs one
:class:`~pairflock_env.safety.cbf.barrier.SafetyFilter` over all B x M agents with
preallocated outputs. Every vehicle model gets the same stage: it changes the pair term of
the desired acceleration, which the particle integrates and the quadrotor's attitude loop
tracks.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.safety.cbf.barrier import SafetyFilter, SafetyOutput
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.swarm.grid import NeighborGrid
from pairflock_env.task.infos import SAFETY_INFO_KEYS

__all__ = ["SAFETY_INFO_KEYS", "CBFStage", "NoFilterStage"]


class NoFilterStage:
    """``safety_filter="none"``: the decoded command as it is, and zero infos."""

    def __init__(
        self, config: Any, agent_uavs: np.ndarray, num_swarms: int, partner_uavs: Any = None
    ) -> None:
        self._shape = (int(num_swarms), int(np.size(agent_uavs)))

    def apply(self, q, p, flock_acc, u, grid=None) -> np.ndarray:
        return u

    def info(self, reset: bool = False) -> dict[str, np.ndarray]:
        shape = self._shape
        return {
            "safety_active": np.zeros(shape, bool),
            "safety_correction": np.zeros(shape),
            "safety_infeasible": np.zeros(shape, bool),
        }


class CBFStage(NoFilterStage):
    """``safety_filter="cbf"``: stage 2b of a core step (between decoding and the desired
    acceleration), the braking-distance CBF filter on every paired UAV.

    Args:
        config: the env config (section ``safety``; ``pair_accel_limit``, ``dt``, ...).
        agent_uavs: (M,) UAV index of each agent.
        num_swarms: B.
        partner_uavs: (M,) UAV index of each agent's partner (constrained at any distance);
            None: only the UAVs within the sensing radius.
    """

    def __init__(
        self,
        config: Any,
        agent_uavs: np.ndarray,
        num_swarms: int,
        partner_uavs: np.ndarray | None = None,
    ) -> None:
        super().__init__(config, agent_uavs, num_swarms)
        self.agent_uavs = np.asarray(agent_uavs, dtype=np.int64)
        params = SafetyParams.from_config(config)
        self.filter = SafetyFilter(params, self.agent_uavs, config.n_uavs, partner_uavs)
        self.output: SafetyOutput = self.filter.allocate(int(num_swarms), config.dim)

    def apply(
        self,
        q: np.ndarray,
        p: np.ndarray,
        flock_acc: np.ndarray,
        u: np.ndarray,
        grid: NeighborGrid | None = None,
    ) -> np.ndarray:
        """A new array (B, M, dim) with each agent's filtered command.

        Args:
            q: positions of all UAVs (B, N, dim), m.
            p: velocities of all UAVs (B, N, dim), m/s.
            flock_acc: the flocking command of every UAV in the current state (B, N, dim);
                each agent uses its own row only.
            u: the decoded pair command (B, M, dim), m/s^2.
            grid: the core's neighbour grid of this state, if it has one (the filter then
                looks up each agent's candidates in it; the result is the same).
        """
        out = self.filter.apply(q, p, flock_acc[:, self.agent_uavs], u, self.output, grid)
        return out.u.copy()

    def info(self, reset: bool = False) -> dict[str, np.ndarray]:
        """The per-agent infos of the last step (fresh arrays): whether the filter changed
        the command for safety, the size of the change (m/s^2) and whether no command within
        the bound met every constraint; zeros at a reset (nothing was filtered)."""
        if reset:
            return super().info()
        o = self.output
        return {
            "safety_active": o.active.copy(),
            "safety_correction": o.correction.copy(),
            "safety_infeasible": o.infeasible.copy(),
        }
