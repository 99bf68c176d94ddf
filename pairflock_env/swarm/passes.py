"""The neighbour pass of one state: every consumer of neighbours served from one search.

:class:`NeighborPass` owns the search the config asks for (``neighbor_search``: all pairs,
or a :class:`~pairflock_env.swarm.grid.NeighborGrid` rebuilt from the positions before each
pass) and the output buffers of the two passes that read it:

* :func:`~pairflock_env.swarm.flocking.flocking_pass`: the flocking command (eqs. 11-19), each
  UAV's nearest non-partner distance, collisions and the largest connected component;
* :func:`~pairflock_env.swarm.pair_pass.pair_pass`: the shared-neighbour count of eq. 28 and
  each agent's K nearest UAVs (the observation's neighbour slots).

Both paths give the same results (the grid visits the same pairs in the same summation
order); the grid is O(N) per swarm for a flock of bounded density instead of O(N^2). The
grid stays available after the pass (:attr:`NeighborPass.grid`) for any later stage that
needs the neighbours of the same state.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.swarm.flocking import flocking_params, flocking_runner
from pairflock_env.swarm.grid import NeighborGrid
from pairflock_env.swarm.pair_pass import pair_runner

__all__ = ["NeighborPass", "make_grid"]


def make_grid(cfg: PairFlockConfig, num_swarms: int) -> NeighborGrid | None:
    """The grid every pass of ``cfg`` can use (cells of ``max(radius, collision_distance,
    collision_height)``), or ``None`` when ``neighbor_search`` resolves to all pairs."""
    if not cfg.uses_grid:
        return None
    cell = max(cfg.radius, cfg.collision_distance, cfg.collision_height or 0.0)
    return NeighborGrid(num_swarms, cfg.n_uavs, cfg.dim, cell_size=cell)


class NeighborPass:
    """The passes of B swarms of one config, with their buffers and (optionally) a grid.

    Args:
        cfg: the configuration (pairs, radius, obs_neighbors, neighbor_search ...).
        num_swarms: number of swarms B.

    It holds the one definition of the agents' indexing that the core shares:
    ``agent_uavs`` (M,) A0, B0, A1, B1, ...; ``partner_uavs`` (M,); ``agent_pair`` (M,) the
    pair index of each agent; ``agent_dm`` (M,) its pair's d_m; ``partner_of`` (N,) the
    partner UAV of each UAV, or -1.
    """

    def __init__(self, cfg: PairFlockConfig, num_swarms: int) -> None:
        pairs = np.asarray(cfg.pairs, dtype=np.int64)  # (P, 2)
        self.cfg = cfg
        self.params = flocking_params(cfg)
        self.agent_uavs = pairs.reshape(-1).copy()
        self.partner_uavs = pairs[:, ::-1].reshape(-1).copy()
        self.agent_pair = np.repeat(np.arange(len(pairs)), 2)
        self.agent_dm = cfg.d_m_array[self.agent_pair]
        self.partner_of = np.full(cfg.n_uavs, -1, np.int64)
        self.partner_of[self.agent_uavs] = self.partner_uavs
        self.grid = g = make_grid(cfg, num_swarms)
        shape = (num_swarms, cfg.n_uavs, cfg.dim)
        self._flock = flocking_runner(self.params, shape, g)
        self._pairs = pair_runner(
            shape, self.agent_uavs, self.partner_uavs, cfg.radius, cfg.obs_neighbors, g
        )
        self.flock_out: dict[str, np.ndarray] | None = None
        self.pair_out: dict[str, np.ndarray] | None = None

    def run(
        self,
        q: np.ndarray,
        p: np.ndarray,
        leader_q: np.ndarray,
        leader_p: np.ndarray,
        pinned: np.ndarray,
    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """Run the neighbour pass over the state q, p (B, N, dim) with the leader at
        ``leader_q``, ``leader_p``.

        Returns the flocking outputs (:func:`~pairflock_env.swarm.flocking.flocking_pass`)
        and the pair pass's (:func:`~pairflock_env.swarm.pair_pass.pair_pass`: eq. 28's
        shared count per pair and each agent's K nearest), also kept as :attr:`flock_out`
        and :attr:`pair_out`; the agents' pass (:mod:`pairflock_env.task.agent_pass`) turns
        them into what a step reports, and adds ``swarm_min_separation`` (B,) to the flocking
        outputs: the smallest distance between any two UAVs, partners included (m).
        """
        if self.grid is not None:
            self.grid.build(q)
        self.flock_out = fl = self._flock(q, p, leader_q, leader_p, pinned, self.partner_of)
        self.pair_out = pp = self._pairs(q, p)
        return fl, pp
