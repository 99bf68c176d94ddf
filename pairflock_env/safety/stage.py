"""The safety stage of the core's step: the configured filter applied to the decoded pair
command, and its per-agent infos.

:class:`SafetyStage` is what :class:`~pairflock_env.core.PairFlockCore` holds: with
``safety_filter="none"`` it returns the command unchanged (the same array) and reports zeros;
with ``"cbf"`` it runs one :class:`~.barrier.SafetyFilter` over all B x M agents with
preallocated outputs. Both vehicle models get the same stage: it changes the pair term of
the desired acceleration, which the particle integrates and the quadrotor's attitude loop
tracks.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.safety.cbf.barrier import SafetyFilter, SafetyOutput
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.swarm.grid import NeighborGrid

__all__ = ["SAFETY_INFO_KEYS", "SafetyStage"]

#: per-agent infos of the stage, (B, M): bool, m/s^2, bool
SAFETY_INFO_KEYS = ("safety_active", "safety_correction", "safety_infeasible")


class SafetyStage:
    """Stage 2b of a core step (between decoding and the desired acceleration).

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
        self.enabled = config.safety_filter == "cbf"
        B, M = int(num_swarms), int(np.size(agent_uavs))
        self.agent_uavs = np.asarray(agent_uavs, dtype=np.int64)
        self.filter: SafetyFilter | None = None
        self.output: SafetyOutput | None = None
        if self.enabled:
            params = SafetyParams.from_config(config)
            self.filter = SafetyFilter(params, self.agent_uavs, config.n_uavs, partner_uavs)
            self.output = self.filter.allocate(B, config.dim)
        self._shape = (B, M)

    def apply(
        self,
        q: np.ndarray,
        p: np.ndarray,
        flock_acc: np.ndarray,
        u: np.ndarray,
        grid: NeighborGrid | None = None,
    ):
        """The pair command to apply (B, M, dim): ``u`` itself when the filter is off, else
        a new array with each agent's filtered command.

        Args:
            q: positions of all UAVs (B, N, dim), m.
            p: velocities of all UAVs (B, N, dim), m/s.
            flock_acc: the flocking command of every UAV in the current state (B, N, dim);
                each agent uses its own row only.
            u: the decoded pair command (B, M, dim), m/s^2.
            grid: the core's neighbour grid of this state, if it has one (the filter then
                looks up each agent's candidates in it; the result is the same).
        """
        if not self.enabled:
            return u
        out = self.filter.apply(q, p, flock_acc[:, self.agent_uavs], u, self.output, grid)
        return out.u.copy()

    def info(self, reset: bool = False) -> dict[str, np.ndarray] | None:
        """The per-agent infos of the last step (fresh arrays, ``SAFETY_INFO_KEYS``): whether
        the filter changed the command for safety, the size of the change (m/s^2) and
        whether no command within the bound met every constraint. None when the filter is
        off or at a reset (nothing was filtered): :func:`~pairflock_env.task.infos.make_info`
        then reports zeros / False."""
        if not self.enabled or reset:
            return None
        o = self.output
        return {
            "safety_active": o.active.copy(),
            "safety_correction": o.correction.copy(),
            "safety_infeasible": o.infeasible.copy(),
        }
