"""The batched braking-distance CBF filter: one linear constraint per sensed UAV, then the
exact QCQP of :mod:`.qp`. The derivation is in docs/safety.md; in brief:

For agent i and a sensed UAV j let x = q_i - q_j, d = ||x||, n = x / d, w = p_i - p_j,
v = n . w (range rate), e = d - D_s (here D_s is the barrier distance
safety_distance + margin), and sigma = n . (a_i - a_j) the line-of-sight part of
the relative acceleration held over the control period T. The barrier

    H(e, v) = sgn(e) sqrt(2 alpha_ij |e|) + v + beta,    beta = (c - 1/2) alpha_ij T,

is >= 0 (with e >= 0) exactly when braking at alpha_ij from the next step on stops the
sampled 1-D motion before D_s (c: :attr:`SafetyParams.position_gain`). Projecting the next
state onto the current n gives, for any held accelerations, d+ >= e + D_s + T v + c T^2 sigma
and (semi-implicit Euler, one substep, where x+ = x + T w+ and the distance is convex along
that segment) v+ >= v + T sigma; other integrators subtract a bound eps on the rotation
error. Both lower bounds increase with sigma and H increases with both arguments, so the
discrete condition H+ >= (1 - lambda) H together with e+ >= min(e, 0) holds as soon as
sigma >= sigma_min, a closed-form root (:func:`_sigma_min`). That is one halfspace in u_i:

    n . (f_i + u_i) >= sigma_min + A_o        (unpaired j:  n . a_j <= A_o assumed)
    n . (f_i + u_i) >= sigma_min / 2          (filtered j:  j enforces the other half)

With a reaction time tau (``SafetyParams.reaction_time``) the barrier is taken at the gap
left after coasting tau at the current range rate, E = e + tau v, in place of e (and the
distance itself still obeys e+ >= min(e, 0)).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import numpy.typing as npt

from pairflock_env.safety.cbf.kernels import BARRIER, _filter_kernel
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.swarm.grid import NeighborGrid

__all__ = ["SafetyFilter", "SafetyOutput", "grid_arrays", "safety_filter"]


@dataclasses.dataclass
class SafetyOutput:
    """Preallocated outputs of the filter for B swarms x M agents."""

    u: np.ndarray
    """(B, M, dim) filtered pair command, m/s^2; ||u|| <= accel_limit."""
    active: np.ndarray
    """(B, M) bool: the nominal command violated a barrier constraint (or the problem was
    infeasible), so the filter changed it for safety."""
    correction: np.ndarray
    """(B, M) ||u - u_nom||, m/s^2; also > 0 when only the bound ||u|| <= accel_limit cut a
    nominal command (e.g. a corner of the env's per-axis action box) and active is False."""
    infeasible: np.ndarray
    """(B, M) bool: no command within the bound satisfies every constraint (the output then
    maximises the smallest constraint margin), or the agent's state or flocking command was
    not finite (a diverged swarm: the nominal is passed through)."""
    barrier: np.ndarray
    """(B, M) smallest barrier value H over the sensed UAVs the filter evaluates, m/s (inf:
    none, NaN: a non-finite state). UAVs within the sensing radius that it proves too far
    to bind (unpaired or paired) are skipped without computing H; theirs is > 0
    (docs/safety.md, "Skipping far UAVs")."""

    def arrays(self) -> tuple[np.ndarray, ...]:
        """(u, active, correction, infeasible, barrier), the kernel's output order."""
        return self.u, self.active, self.correction, self.infeasible, self.barrier

    @classmethod
    def empty(cls, B: int, M: int, dim: int) -> SafetyOutput:
        return cls(
            np.zeros((B, M, dim)),
            np.zeros((B, M), bool),
            np.zeros((B, M)),
            np.zeros((B, M), bool),
            np.zeros((B, M)),
        )


class SafetyFilter:
    """The decentralised CBF safety filter for the paired UAVs of a swarm.

    Args:
        params: a :class:`SafetyParams`.
        agents: (M,) UAV index of each filtered (paired) UAV.
        n_uavs: N, the number of UAVs per swarm.
        partners: optional (M,) UAV index of each agent's partner (-1: none), constrained at
            any distance: the pair controller senses its partner over the pair's link
            whatever their distance, so the partner need not enter the sensing radius on the
            safe side. None: no partners (every UAV only within the radius).

    Every UAV listed in ``agents`` runs this filter, so against each other (partners
    included) they split the constraint in halves; the other UAVs are assumed to accelerate
    towards an agent at most ``other_accel``. Agent i uses only the relative positions and
    velocities of its partner and of the UAVs closer than ``sensing_radius``, its own
    flocking command and its own bound.
    """

    def __init__(
        self,
        params: SafetyParams,
        agents: npt.ArrayLike,
        n_uavs: int,
        partners: npt.ArrayLike | None = None,
    ) -> None:
        if not isinstance(params, SafetyParams):
            raise TypeError(f"params={params!r} is invalid: must be a SafetyParams")
        if isinstance(n_uavs, bool) or not isinstance(n_uavs, (int, np.integer)) or n_uavs < 1:
            raise ValueError(f"n_uavs={n_uavs!r} is invalid: must be an integer >= 1")
        ag = np.asarray(agents)
        if ag.ndim != 1 or ag.dtype.kind not in "iu":
            raise TypeError(f"agents must be a 1-D integer array, got {ag.dtype} {ag.shape}")
        if ag.size and (ag.min() < 0 or ag.max() >= n_uavs or np.unique(ag).size != ag.size):
            raise ValueError(f"agents={ag.tolist()} is invalid: distinct indices in [0, {n_uavs})")
        self.params = params
        self.n_uavs = int(n_uavs)
        self.agents = ag.astype(np.int64)
        self.partners = self._partners(partners, self.agents, self.n_uavs)
        self.cooperative = np.zeros(self.n_uavs, np.bool_)
        self.cooperative[self.agents] = True
        P = params
        #: the kernel's parameters (:data:`~pairflock_env.safety.cbf.kernels.BARRIER`)
        self._pr = BARRIER.pack(
            barrier_distance=P.barrier_distance,
            brake_accel=P.brake_accel,
            other_accel=P.other_accel,
            sensing_radius2=P.sensing_radius**2,
            decay=P.decay,
            dt=P.dt,
            position_gain=P.position_gain,
            accel_limit=P.accel_limit,
            reaction_time=P.reaction_time,
            skip_far=1.0,
        )

    def allocate(self, num_swarms: int, dim: int) -> SafetyOutput:
        """Output arrays for ``num_swarms`` swarms in ``dim`` dimensions."""
        return SafetyOutput.empty(int(num_swarms), self.agents.size, int(dim))

    def apply(
        self,
        q: npt.ArrayLike,
        p: npt.ArrayLike,
        flock_accel: npt.ArrayLike,
        u_nom: npt.ArrayLike,
        out: SafetyOutput | None = None,
        grid: NeighborGrid | None = None,
    ) -> SafetyOutput:
        """Filter the nominal pair commands of every agent of every swarm.

        Args:
            q: positions of all UAVs (B, N, dim), m.
            p: velocities of all UAVs (B, N, dim), m/s.
            flock_accel: (B, M, dim) each agent's own flocking command f_i, m/s^2.
            u_nom: (B, M, dim) nominal pair commands, m/s^2 (finite).
            out: arrays to fill (from :meth:`allocate`); new ones when None.
            grid: optional :class:`~pairflock_env.swarm.grid.NeighborGrid` built from these
                positions ``q``: each agent then looks only at the UAVs the grid finds within
                its ranges (and its partner), O(M k) per swarm instead of O(M N), with the
                same result bit for bit. Swarms the grid does not hold, or whose state is
                not finite, are scanned in full.
        Returns:
            ``out``, filled.
        """
        q, p = self._array("q", q, None), self._array("p", p, None)
        B, N, D = q.shape
        if self.n_uavs != N or p.shape != q.shape or not 1 <= D <= 3:
            raise ValueError(
                f"q and p have shapes {q.shape}, {p.shape}; expected (B, {self.n_uavs}, dim)"
            )
        shape = (B, self.agents.size, D)
        f = self._array("flock_accel", flock_accel, shape)
        un = self._array("u_nom", u_nom, shape)
        if not np.isfinite(un).all():
            raise ValueError("u_nom contains NaN or inf; the nominal commands must be finite")
        if out is None:
            out = self.allocate(B, D)
        elif out.u.shape != shape:
            raise ValueError(f"out.u has shape {out.u.shape}, expected {shape}")
        g = grid_arrays(grid, q)
        o = out
        ag, mates = self.agents, self.partners
        use = grid is not None
        _filter_kernel(q, p, f, un, ag, mates, self.cooperative, self._pr, use, g, *o.arrays())
        return out

    @staticmethod
    def _partners(partners, agents: np.ndarray, n_uavs: int) -> np.ndarray:
        if partners is None:
            return np.full(agents.size, -1, np.int64)
        mates = np.asarray(partners)
        if mates.shape != agents.shape or mates.dtype.kind not in "iu":
            raise TypeError(
                f"partners must be a 1-D integer array like agents {agents.shape}, got "
                f"{mates.dtype} {mates.shape}"
            )
        bad = (mates < -1) | (mates >= n_uavs) | (mates == agents)
        if bad.any():
            raise ValueError(
                f"partners={mates.tolist()} is invalid: each must be -1 (none) or a UAV index "
                f"in [0, {n_uavs}) other than the agent's own"
            )
        return mates.astype(np.int64)

    @staticmethod
    def _array(name, x, shape):
        a = np.asarray(x)
        if a.dtype.kind not in "fiu":
            raise TypeError(f"{name} has dtype {a.dtype}; expected a real dtype")
        if a.ndim != 3 or (shape is not None and a.shape != shape):
            raise ValueError(f"{name} has shape {a.shape}, expected {shape or '(B, N, dim)'}")
        return np.ascontiguousarray(a, dtype=np.float64)


def grid_arrays(grid: NeighborGrid | None, q: np.ndarray):
    """The arrays of ``grid`` for a filter kernel (a 1-UAV placeholder when it is None);
    ``ValueError`` unless the grid was built from these positions ``q``."""
    if grid is None:
        return _no_grid()
    if not isinstance(grid, NeighborGrid):
        raise TypeError(f"grid={grid!r} is invalid: must be a NeighborGrid or None")
    built = grid.positions
    if built is None or built.shape != q.shape or not (built is q or np.array_equal(built, q)):
        raise ValueError(
            "grid is invalid: it must be built from the positions q passed here "
            "(NeighborGrid.build(q))"
        )
    return grid.arrays


@functools.cache
def _no_grid():
    """Arrays of a 1-UAV grid: what the kernel gets (and ignores) when there is no grid."""
    return NeighborGrid(1, 1, 2, cell_size=1.0).build(np.zeros((1, 1, 2))).arrays


def safety_filter(
    params: SafetyParams, q, p, agents, flock_accel, u_nom, partners=None
) -> SafetyOutput:
    """One-call form of :meth:`SafetyFilter.apply` (builds the filter each call)."""
    filt = SafetyFilter(params, agents, np.shape(q)[1], partners)
    return filt.apply(q, p, flock_accel, u_nom)
