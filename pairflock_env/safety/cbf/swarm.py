"""The swarm layer (``safety_scope="swarm"``, docs/swarm-safety.md): every UAV, paired or
not, replaces its whole command by the nearest one that keeps ``safety_distance`` from every
UAV it senses.

It is the pair filter generalised (:mod:`.barrier`, docs/safety.md): the same braking-
distance barrier, the same row writer, the same exact solver, run by every UAV. Since every
UAV filters, ``safety_other_accel`` is not used: each pairwise condition
n . (a_i - a_j) >= sigma_min is split between the two UAVs in proportion to their brake
accelerations, except that a paired UAV which out-brakes an unpaired UAV's whole bound takes
their row alone (:mod:`.swarm_kernels`). An unpaired UAV's whole command lies in the ball
||a|| <= ``swarm_accel_limit``; a paired UAV keeps its pair budget, ||a - f|| <=
``pair_accel_limit`` around its flocking command f.

>>> import numpy as np
>>> from pairflock_env.safety import SafetyParams, SwarmFilter
>>> filt = SwarmFilter(SafetyParams(accel_limit=50.0), [0, 1], 4, accel_limit=20.0,
...                    brake_accel=16.0, swarm_radius=8.0)  # UAVs 0, 1 are a pair
>>> q = np.array([[[0.0, 50.0], [5.0, 50.0], [0.0, 0.0], [3.0, 0.0]]])  # 2 and 3: 3 m apart
>>> p = np.array([[[0.0, 0.0], [0.0, 0.0], [5.5, 0.0], [-5.5, 0.0]]])  # ... closing at 11 m/s
>>> a = np.zeros((1, 4, 2))  # nobody is told to brake
>>> out = filt.apply(q, p, a, a)
>>> out.active[0].tolist(), out.a[0, 2:, 0].round(2).tolist()  # 2 and 3 brake, half each
([False, False, True, True], [-4.55, 4.55])
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from pairflock_env.safety.cbf.barrier import SafetyFilter, grid_arrays
from pairflock_env.safety.cbf.kernels import WS_ADD, WS_MAX
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.safety.cbf.search import FIT_ROWS, RADIUS_LEVELS
from pairflock_env.safety.cbf.swarm_kernels import SWARM, VEC_ROWS, swarm_kernel
from pairflock_env.swarm.grid import NeighborGrid

__all__ = ["SwarmFilter", "SwarmOutput"]

#: room for this many outlier contacts per UAV (beyond it a swarm's step goes without the
#: outlier split: the same commands, slower)
OUTLIER_CONTACTS = 8


@dataclasses.dataclass
class SwarmOutput:
    """Preallocated outputs of the swarm layer for B swarms of N UAVs with M agents."""

    a: np.ndarray
    """(B, N, dim) every UAV's filtered whole command, m/s^2."""
    u: np.ndarray
    """(B, M, dim) each agent's pair command a - f (||u|| <= pair_accel_limit)."""
    active: np.ndarray
    """(B, N) bool: the nominal command violated a barrier row (or none was feasible)."""
    correction: np.ndarray
    """(B, N) ||a - a_nom||, m/s^2 (also > 0 where only the ball cut the nominal)."""
    infeasible: np.ndarray
    """(B, N) bool: no command within the ball met every row (the max-margin command is
    applied), or the state was not finite."""
    barrier: np.ndarray
    """(B, N) smallest barrier value H over the rows evaluated, m/s (inf: none)."""

    def arrays(self) -> tuple[np.ndarray, ...]:
        """The kernel's output order."""
        return self.a, self.u, self.active, self.correction, self.infeasible, self.barrier

    @classmethod
    def empty(cls, B: int, N: int, M: int, dim: int) -> SwarmOutput:
        z = np.zeros
        return cls(z((B, N, dim)), z((B, M, dim)), z((B, N), bool), z((B, N)), z((B, N), bool),
                   z((B, N)))  # fmt: skip


def _positive(name: str, value: float) -> float:
    v = float(value)
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{name}={value!r} is invalid: must be a finite number > 0")
    return v


def _separation(x: npt.ArrayLike, shape: tuple[int, int]) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise TypeError(f"separation has dtype {a.dtype}; expected a real dtype")
    if a.shape != shape:
        raise ValueError(f"separation has shape {a.shape}, expected {shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _scratch(N: int, M: int) -> tuple[tuple, tuple]:
    """The kernel's scratch for N UAVs with M agents: ``work`` (but the x order, which
    depends on B) and ``solver`` (:func:`~pairflock_env.safety.cbf.swarm_kernels.swarm_kernel`)."""
    K = WS_MAX + WS_ADD
    i64 = np.int64
    levels = RADIUS_LEVELS + 1
    outliers = (np.zeros(levels), np.zeros(levels, i64), np.zeros(N + 1, i64), np.zeros(N, i64),
                np.zeros(OUTLIER_CONTACTS * N + 64, i64))  # fmt: skip
    work = (np.zeros(N + 1, i64), np.zeros(N + 1, i64), np.zeros(N, i64),
            np.zeros(max(N * M, 1), i64), np.zeros((N, 3)), np.zeros(N), np.zeros((VEC_ROWS, 3)),
            np.zeros((FIT_ROWS, 3)), np.zeros(N), np.zeros(levels), np.zeros(N, i64),
            np.zeros(N // 64 + 2, np.uint64), outliers)  # fmt: skip
    solver = (np.zeros((4, 4, 4)), np.zeros(5, i64), np.zeros((K, 3)), np.zeros(K),
              np.zeros(K, i64), np.zeros(N))  # fmt: skip
    return work, solver


class SwarmFilter:
    """The swarm layer over B swarms of N UAVs.

    Args:
        params: the pair filter's :class:`~pairflock_env.safety.SafetyParams` (barrier
            distance, dt, integrator, decay, reaction time; ``accel_limit`` and
            ``brake_accel`` are the paired UAVs' ball and brake; ``sensing_radius`` the
            radius of every row that involves a paired UAV).
        agents: (M,) UAV index of each paired UAV (agent); the others are unpaired.
        n_uavs: N.
        partners: optional (M,) partner of each agent (-1: none), constrained at any
            distance.
        accel_limit: U_s, the ball of an unpaired UAV's whole command (m/s^2).
        brake_accel: alpha_s, an unpaired UAV's brake (m/s^2), in (0, accel_limit].
        swarm_radius: two unpaired UAVs constrain each other closer than this (m).

    Attributes:
        pair_alone: whether the paired UAVs take their rows against unpaired UAVs alone
            (``brake_accel - accel_limit >= `` the unpaired brake; else those rows are
            shared by brake capacity).
    """

    def __init__(
        self,
        params: SafetyParams,
        agents: npt.ArrayLike,
        n_uavs: int,
        partners: npt.ArrayLike | None = None,
        *,
        accel_limit: float,
        brake_accel: float,
        swarm_radius: float,
    ) -> None:
        pair = SafetyFilter(params, agents, n_uavs, partners)  # checks params, agents, partners
        U, a = _positive("accel_limit", accel_limit), _positive("brake_accel", brake_accel)
        if a > U:
            raise ValueError(f"brake_accel={brake_accel!r} is invalid: must be <= {U:g}")
        P = params
        r = _positive("swarm_radius", swarm_radius)
        if not r > P.barrier_distance:
            raise ValueError(
                f"swarm_radius={swarm_radius!r} is invalid: must exceed safety_distance + "
                f"margin = {P.barrier_distance:g}"
            )
        self.params, self.n_uavs, self.agents = P, pair.n_uavs, pair.agents
        N, M = self.n_uavs, self.agents.size
        paired = pair.cooperative
        mate = np.full(N, -1, np.int64)
        mate[self.agents] = pair.partners
        slot = np.full(N, -1, np.int64)
        slot[self.agents] = np.arange(M)
        #: a paired UAV takes its rows against unpaired UAVs alone when it out-brakes their
        #: whole bound by at least their own brake (module docstring of .swarm_kernels)
        self.pair_alone = bool(M) and P.brake_accel - U >= a
        coop_p = paired if self.pair_alone else np.ones(N, np.bool_)
        self._ints = (paired, mate, self.agents, np.ones(N, np.bool_), coop_p, slot)
        alpha = np.where(paired, P.brake_accel, a)
        bound = np.where(paired, P.accel_limit, U)
        self._reals = (alpha, bound, np.zeros(N))
        #: the kernel's parameters (:data:`~pairflock_env.safety.cbf.swarm_kernels.SWARM`)
        self._pr = SWARM.pack(
            barrier_distance=P.barrier_distance,
            dt=P.dt,
            position_gain=P.position_gain,
            decay=P.decay,
            reaction_time=P.reaction_time,
            pair_radius2=P.sensing_radius**2,
            swarm_radius2=r * r,
            other_accel=U,
            pair_alone=float(self.pair_alone),
            skip_far=1.0,
        )
        self._work, self._solver = _scratch(N, M)
        #: (B, N) each swarm's UAVs in increasing x as the last step left them (searches
        #: without a grid walk it; kept across steps, so sorting it again is near O(N))
        self._xorder = np.zeros((0, N), np.int64)
        self._reach = np.zeros(1)
        #: the radius (m) of the longest grid search of the last :meth:`apply` (0: none)
        self.search_reach = 0.0

    def allocate(self, num_swarms: int, dim: int) -> SwarmOutput:
        """Output arrays for ``num_swarms`` swarms in ``dim`` dimensions."""
        return SwarmOutput.empty(int(num_swarms), self.n_uavs, self.agents.size, int(dim))

    def apply(
        self,
        q: npt.ArrayLike,
        p: npt.ArrayLike,
        a_nom: npt.ArrayLike,
        flock_accel: npt.ArrayLike,
        out: SwarmOutput | None = None,
        grid: NeighborGrid | Sequence[NeighborGrid] | None = None,
        separation: npt.ArrayLike | None = None,
    ) -> SwarmOutput:
        """Filter the nominal whole command of every UAV of every swarm.

        Args:
            q, p: positions and velocities of all UAVs (B, N, dim), m and m/s.
            a_nom: (B, N, dim) nominal commands (flocking + pair term), m/s^2, finite.
            flock_accel: (B, N, dim) flocking commands (a paired UAV's ball is around its
                own).
            out: arrays to fill (from :meth:`allocate`); new ones when None.
            grid: optional :class:`~pairflock_env.swarm.grid.NeighborGrid` built from these
                ``q`` (any cell size), or a ladder of up to three such grids, finest first:
                each search then uses the finest grid whose cells are at least a third of
                its radius, with the same result bit for bit as scanning all N.
            separation: optional (B, N) squared distance from each UAV to its nearest
                other UAV, its partner left out, in these ``q`` (the flocking pass's
                ``min_d2``): searches shorter than it are skipped, with the same result. It
                must be exact (or smaller); a larger value would hide a UAV.
        """
        check = SafetyFilter._array
        q, p = check("q", q, None), check("p", p, None)
        B, N, D = q.shape
        if self.n_uavs != N or p.shape != q.shape or not 1 <= D <= 3:
            raise ValueError(
                f"q and p have shapes {q.shape}, {p.shape}; expected (B, {self.n_uavs}, dim)"
            )
        a_nom = check("a_nom", a_nom, q.shape)
        f = check("flock_accel", flock_accel, q.shape)
        if not np.isfinite(a_nom).all():
            raise ValueError("a_nom contains NaN or inf; the nominal commands must be finite")
        if out is None:
            out = self.allocate(B, D)
        elif out.a.shape != q.shape:
            raise ValueError(f"out.a has shape {out.a.shape}, expected {q.shape}")
        ladder = [] if grid is None else [grid] if isinstance(grid, NeighborGrid) else list(grid)
        if not 1 <= len(ladder) <= 3 and grid is not None:
            raise ValueError(f"grid has {len(ladder)} grids; expected a NeighborGrid or 1-3")
        gs = [grid_arrays(g, q) for g in ladder] or [grid_arrays(None, q)]
        if any(b.h < a.h for a, b in itertools.pairwise(gs)):
            raise ValueError("grid is invalid: a ladder of grids must go from fine to coarse")
        gs += [gs[-1]] * (3 - len(gs))
        if self._xorder.shape[0] != B:
            self._xorder = np.tile(np.arange(N, dtype=np.int64), (B, 1))
            self._unknown = np.zeros((B, N))
        sep = self._unknown if separation is None else _separation(separation, (B, N))
        self._reach[0] = 0.0
        swarm_kernel(q, p, a_nom, f, self._ints, self._reals, self._pr, grid is not None,
                     (*gs, self._reach), sep, out.arrays(), (*self._work, self._xorder),
                     self._solver)  # fmt: skip
        self.search_reach = float(np.sqrt(self._reach[0]))
        return out
