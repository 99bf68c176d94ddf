"""The safety stage of the core's step: the configured filter applied to the decoded pair
command (or, under ``safety_scope="swarm"``, to every UAV's whole command), and its infos.

A stage is what a :class:`~pairflock_env.safety.Filter` entry builds for a core:
``stage(config, agent_uavs, num_swarms, partner_uavs)`` with :meth:`apply` (the command to
use, from what each UAV senses) and :meth:`info` (at least ``SAFETY_INFO_KEYS``, (B, M)).
:class:`NoFilterStage` (``safety_filter="none"``) returns the command unchanged (the same
array) and reports zeros; :class:`CBFStage` (``"cbf"``) runs one
:class:`~pairflock_env.safety.cbf.barrier.SafetyFilter` over all B x M agents with
preallocated outputs; :class:`SwarmStage` (``"cbf"`` with ``safety_scope="swarm"``) runs
the :class:`~pairflock_env.safety.cbf.swarm.SwarmFilter` over all B x N UAVs and holds their
filtered whole commands in :attr:`SwarmStage.whole_command`, which the core then applies.
Every vehicle model gets the same stage: it changes the desired acceleration, which the
particle integrates and the quadrotor's attitude loop tracks.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.config.sections.safety import (
    swarm_accel_limit,
    swarm_brake_accel,
    swarm_sensing_radius,
)
from pairflock_env.safety.cbf.barrier import SafetyFilter, SafetyOutput
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.safety.cbf.search import LADDER_REACH
from pairflock_env.safety.cbf.swarm import SwarmFilter, SwarmOutput
from pairflock_env.swarm.grid import NeighborGrid
from pairflock_env.task.infos import SAFETY_INFO_KEYS, SAFETY_SWARM_INFO_KEYS

__all__ = [
    "SAFETY_INFO_KEYS",
    "SAFETY_SWARM_INFO_KEYS",
    "CBFStage",
    "NoFilterStage",
    "SwarmStage",
    "cbf_stage",
]

#: the swarm layer's own grid has cells of this many barrier distances: its searches reach
#: about one barrier distance plus the braking distance at the flock's relative speeds
#: (10,000 UAVs of the large preset after 15 s, 1.3-1.8 m apart: the layer takes 2.3 ms
#: with cells of 2.0, 2.6 ms with 3.0, 3.5 ms with 1.0 and 2.9 ms with 1.5; one thread)
SWARM_CELL = 2.0
#: the ratio of cell sizes in the layer's ladder of grids: while the flock contracts from a
#: spread start, searches reach tens of metres (10,000 UAVs of the large preset 3 s after a
#: reset: 19 m median) and would visit thousands of the fine grid's cells each
LADDER = 4.0


class NoFilterStage:
    """``safety_filter="none"``: the decoded command as it is, and zero infos."""

    #: the filtered whole command of every UAV (B, N, dim) of the last :meth:`apply`, for a
    #: stage that filters every UAV's command (the core applies it as the desired
    #: acceleration); None: the core adds the pair command to the flocking command itself
    whole_command: np.ndarray | None = None

    def __init__(
        self, config: Any, agent_uavs: np.ndarray, num_swarms: int, partner_uavs: Any = None
    ) -> None:
        self._shape = (int(num_swarms), int(np.size(agent_uavs)))

    def apply(self, q, p, flock_acc, u, grid=None) -> np.ndarray:
        return u

    def sense(self, flock_out: dict[str, np.ndarray]) -> None:
        """Called by the core after every neighbour pass with the flocking outputs of the
        state the next :meth:`apply` filters (``min_d2``: each UAV's squared distance to
        its nearest non-partner UAV, ...); a stage may keep what it needs. Optional for a
        plug-in stage; this one keeps nothing."""

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


class SwarmStage(NoFilterStage):
    """``safety_filter="cbf"`` with ``safety_scope="swarm"``: every UAV filters its whole
    command (flocking + pair term) with the :class:`~pairflock_env.safety.cbf.swarm.
    SwarmFilter`; the agents' rows give the per-agent infos, the counts over all UAVs
    ``swarm_filter_active`` and ``swarm_filter_infeasible``. Arguments as :class:`CBFStage`.
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
        self.filter = SwarmFilter(
            params,
            self.agent_uavs,
            config.n_uavs,
            partner_uavs,
            accel_limit=swarm_accel_limit(config),
            brake_accel=swarm_brake_accel(config),
            swarm_radius=swarm_sensing_radius(config),
        )
        B, N, D = int(num_swarms), config.n_uavs, config.dim
        self.output: SwarmOutput = self.filter.allocate(B, D)
        #: the layer's own grids (cells of SWARM_CELL barrier distances, and LADDER times and
        #: LADDER^2 times that, for the long searches of a fast flock), when the core's
        #: neighbour search is the grid; empty: every search scans all N (same result)
        self.grids: tuple[NeighborGrid, ...] = ()
        #: the last neighbour pass's min_d2 (B, N) (:meth:`sense`), or None
        self._separation: np.ndarray | None = None
        if config.uses_grid:
            h = SWARM_CELL * params.barrier_distance
            self.grids = tuple(NeighborGrid(B, N, D, cell_size=h * LADDER**k) for k in range(3))
        #: how many grids of the ladder the next apply builds: those the last one's longest
        #: search needed (a settled flock needs the finest only; a search beyond the built
        #: ones takes the coarsest built, slower, with the same result)
        self._levels = len(self.grids)

    def apply(self, q, p, flock_acc, u, grid=None) -> np.ndarray:
        """Filter every UAV's whole command a = f (+ u on the agents); returns the agents'
        pair commands a - f (B, M, dim) and sets :attr:`whole_command`. ``grid`` (the
        core's) is not used: the layer searches its own ladder of finer grids."""
        a = flock_acc.copy()
        a[:, self.agent_uavs] += u
        ladder = self.grids[: self._levels]
        for g in ladder:
            g.build(q)
        sep = self._separation
        out = self.filter.apply(q, p, a, flock_acc, self.output, ladder or None, sep)
        if ladder:
            reach = self.filter.search_reach  # a search uses a grid whose cells are >= reach/3
            self._levels = 1 + sum(reach > LADDER_REACH * g.cell_size for g in self.grids[:-1])
        self.whole_command = out.a
        return out.u.copy()

    def sense(self, flock_out: dict[str, np.ndarray]) -> None:
        """Keep the pass's nearest-neighbour distances: a UAV whose search radius is below
        its own needs no search (the same commands; most UAVs of a settled flock)."""
        self._separation = flock_out["min_d2"]

    def info(self, reset: bool = False) -> dict[str, np.ndarray]:
        """The agents' rows of the layer's outputs (as :meth:`CBFStage.info`) and the per-swarm
        counts ``SAFETY_SWARM_INFO_KEYS`` over all UAVs (fresh arrays; zeros at a reset)."""
        o, ag = self.output, self.agent_uavs
        if reset:
            B = o.active.shape[0]
            return {**super().info(), **{k: np.zeros(B, np.int64) for k in SAFETY_SWARM_INFO_KEYS}}
        return {
            "safety_active": o.active[:, ag],
            "safety_correction": o.correction[:, ag],
            "safety_infeasible": o.infeasible[:, ag],
            "swarm_filter_active": np.count_nonzero(o.active, axis=1),
            "swarm_filter_infeasible": np.count_nonzero(o.infeasible, axis=1),
        }


def cbf_stage(
    config: Any, agent_uavs: np.ndarray, num_swarms: int, partner_uavs: np.ndarray | None = None
) -> NoFilterStage:
    """The stage of ``safety_filter="cbf"``: :class:`SwarmStage` under
    ``safety_scope="swarm"``, else :class:`CBFStage`."""
    cls = SwarmStage if config.safety_scope == "swarm" else CBFStage
    return cls(config, agent_uavs, num_swarms, partner_uavs)
