"""The batched braking-distance CBF filter: one linear constraint per sensed UAV, then the
exact QCQP of :mod:`.qp`. The derivation is in docs/safety.md; in brief:

For agent i and a sensed UAV j let x = q_i - q_j, d = ||x||, n = x / d, w = p_i - p_j,
v = n . w (range rate), e = d - D_s, and sigma = n . (a_i - a_j) the line-of-sight part of
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
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numba import njit

from .params import SafetyParams
from .qp import STATUS_INFEASIBLE, STATUS_NOMINAL, _solve

__all__ = ["SafetyFilter", "SafetyOutput", "safety_filter"]


@njit(cache=True, nogil=True)
def _sigma_min(e, v, eps, a, T, c, lam):
    """(H, sigma_min): the barrier and the smallest line-of-sight relative acceleration
    that keeps H(next) >= (1 - lam) H and e(next) >= min(e, 0) (module docstring)."""
    beta = (c - 0.5) * a * T
    H = np.sign(e) * np.sqrt(2.0 * a * abs(e)) + v + beta
    K = v - eps + beta - (1.0 - lam) * H
    cT2 = c * T * T
    s0 = -(e + T * v) / cT2  # sigma at which the projected next distance is D_s
    R0 = -(T * s0 + K)
    Ac = a * c * T
    R = abs(R0)
    z = R * R / (T * (R + Ac + np.sqrt(Ac * (2.0 * R + Ac))))
    s_b = s0 + z if R0 >= 0.0 else s0 - z
    s_a = s0 + min(e, 0.0) / cT2
    return H, max(s_a, s_b)


@njit(cache=True, nogil=True)
def _constraints(b, i, q, p, f, coop, Ds, alpha, A_o, R2, lam, T, c, U, G, rhs, n):
    """Fill G, rhs with agent i's non-redundant constraints; return (count, min H, ok)."""
    N, D = q.shape[1], q.shape[2]
    K = 0
    hmin = np.inf
    fn = 0.0
    for k in range(D):
        fn += f[k] * f[k]
    fn = np.sqrt(fn)
    for j in range(N):
        if j == i:
            continue
        d2 = 0.0
        w2 = 0.0
        for k in range(D):
            d2 += (q[b, i, k] - q[b, j, k]) ** 2
            w2 += (p[b, i, k] - p[b, j, k]) ** 2
        if not (np.isfinite(d2) and np.isfinite(w2)):
            return 0, np.nan, False
        if d2 >= R2:
            continue
        d = np.sqrt(d2)
        for k in range(D):
            n[k] = (q[b, i, k] - q[b, j, k]) / d if d > 0.0 else 0.0
        if d == 0.0:  # coincident: any direction, opposite for the two UAVs
            n[0] = 1.0 if i < j else -1.0
        v = 0.0
        nf = 0.0
        for k in range(D):
            v += n[k] * (p[b, i, k] - p[b, j, k])
            nf += n[k] * f[k]
        a = 2.0 * alpha if coop[j] else alpha - A_o
        eps = 0.0
        if c < 1.0:  # rotation of n within the step (docs/safety.md)
            amax = 2.0 * (fn + U) if coop[j] else fn + U + A_o
            geo = min(2.0, 2.0 * T * (np.sqrt(w2) + c * T * amax) / (d + min(d, Ds)))
            eps = (1.0 - c) * T * amax * geo
        H, smin = _sigma_min(d - Ds, v, eps, a, T, c, lam)
        hmin = min(hmin, H)
        need = 0.5 * smin if coop[j] else smin + A_o
        if need - nf <= -U:
            continue  # implied by ||u|| <= U
        for k in range(D):
            G[K, k] = n[k]
        rhs[K] = need - nf
        K += 1
    return K, hmin, True


@njit(cache=True, nogil=True)
def _filter_kernel(q, p, f, un, agents, coop, pr, u, active, corr, infeas, hmin):
    B, M, D = un.shape
    N = q.shape[1]
    Ds, alpha, A_o, R2, lam, T, c, U = pr[0], pr[1], pr[2], pr[3], pr[4], pr[5], pr[6], pr[7]
    G = np.zeros((max(N, 1), 3))
    rhs = np.zeros(max(N, 1))
    W = np.zeros((3, 4, 4))
    idx = np.zeros(4, np.int64)
    cand = np.zeros(3)
    best = np.zeros(3)
    uin = np.zeros(3)
    uo = np.zeros(3)
    nv = np.zeros(3)
    for b in range(B):
        for m in range(M):
            K, h, ok = _constraints(
                b, agents[m], q, p, f[b, m], coop, Ds, alpha, A_o, R2, lam, T, c, U, G, rhs, nv
            )
            hmin[b, m] = h
            for k in range(D):
                uin[k] = un[b, m, k]
            if ok:
                status, _ = _solve(uin, G, rhs, K, U, D, W, idx, cand, best, uo)
            else:  # non-finite state (a diverged swarm): pass the command through
                status = STATUS_INFEASIBLE
                uo[:D] = uin[:D]
            dc = 0.0
            for k in range(D):
                u[b, m, k] = uo[k]
                dc += (uo[k] - uin[k]) ** 2
            corr[b, m] = np.sqrt(dc)
            active[b, m] = status != STATUS_NOMINAL
            infeas[b, m] = status == STATUS_INFEASIBLE


@dataclasses.dataclass
class SafetyOutput:
    """Preallocated outputs of the filter for B swarms x M agents."""

    u: np.ndarray
    """(B, M, dim) filtered pair command, m/s^2; ||u|| <= accel_limit."""
    active: np.ndarray
    """(B, M) bool: the filter changed the command (a constraint or the bound was binding)."""
    correction: np.ndarray
    """(B, M) ||u - u_nom||, m/s^2."""
    infeasible: np.ndarray
    """(B, M) bool: no command within the bound satisfies every constraint (the output then
    maximises the smallest constraint margin), or the state was not finite."""
    barrier: np.ndarray
    """(B, M) smallest barrier value H over the sensed UAVs, m/s (inf: none sensed)."""

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

    Every UAV listed in ``agents`` runs this filter, so against each other (partners
    included) they split the constraint in halves; the other UAVs are assumed to accelerate
    towards an agent at most ``other_accel``. Agent i uses only the relative positions and
    velocities of UAVs closer than ``sensing_radius``, its own flocking command and its
    own bound.
    """

    def __init__(self, params: SafetyParams, agents, n_uavs: int) -> None:
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
        self.cooperative = np.zeros(self.n_uavs, np.bool_)
        self.cooperative[self.agents] = True
        P = params
        self._pr = np.array(
            [
                P.safety_distance,
                P.brake_accel,
                P.other_accel,
                P.sensing_radius**2,
                P.decay,
                P.dt,
                P.position_gain,
                P.accel_limit,
            ]
        )

    def allocate(self, num_envs: int, dim: int) -> SafetyOutput:
        """Output arrays for ``num_envs`` swarms in ``dim`` dimensions."""
        return SafetyOutput.empty(int(num_envs), self.agents.size, int(dim))

    def apply(self, q, p, flock_accel, u_nom, out: SafetyOutput | None = None) -> SafetyOutput:
        """Filter the nominal pair commands of every agent of every swarm.

        Args:
            q, p: positions (m) and velocities (m/s) of all UAVs, (B, N, dim) float64.
            flock_accel: (B, M, dim) each agent's own flocking command f_i, m/s^2.
            u_nom: (B, M, dim) nominal pair commands, m/s^2.
            out: arrays to fill (from :meth:`allocate`); new ones when None.
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
        if not np.isfinite(un).all() or not np.isfinite(f).all():
            raise ValueError("u_nom and flock_accel must be finite")
        if out is None:
            out = self.allocate(B, D)
        elif out.u.shape != shape:
            raise ValueError(f"out.u has shape {out.u.shape}, expected {shape}")
        o = out
        _filter_kernel(q, p, f, un, self.agents, self.cooperative, self._pr, *o.arrays())
        return out

    @staticmethod
    def _array(name, x, shape):
        a = np.asarray(x)
        if a.dtype.kind not in "fiu":
            raise TypeError(f"{name} has dtype {a.dtype}; expected a real dtype")
        if a.ndim != 3 or (shape is not None and a.shape != shape):
            raise ValueError(f"{name} has shape {a.shape}, expected {shape or '(B, N, dim)'}")
        return np.ascontiguousarray(a, dtype=np.float64)


def safety_filter(params: SafetyParams, q, p, agents, flock_accel, u_nom) -> SafetyOutput:
    """One-call form of :meth:`SafetyFilter.apply` (builds the filter each call)."""
    return SafetyFilter(params, agents, np.shape(q)[1]).apply(q, p, flock_accel, u_nom)
