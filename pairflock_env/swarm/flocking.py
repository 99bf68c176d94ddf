"""The flocking protocol of eqs. 11-19 and the proximity quantities, in one pass over pairs.

For every UAV i of every swarm b (arrays shaped (B, N, dim)):

    f_i^g = sum_{j in N_i} (q_j - q_i) [a - g_r(||q_j - q_i||)]           eqs. 13-16
            g_r(rho) = b_r exp(-rho^2 / sigma^2),  g_r(d) = a
    f_i^v = b sum_{j in N_i} (p_j - p_i)                                  eq. 18
    f_i^gamma = c1 (q_gamma - q_i) + c2 (p_gamma - p_i)                   eq. 19
    a_i = f_i^g + f_i^v + h_i f_i^gamma                                   eq. 11 without f^x
    N_i = { j != i : ||q_i - q_j|| < r }                                  eq. 2

The same pass also yields what metrics and rewards need, so no second pass over the pairs
is made: each UAV's smallest distance to any UAV other than its partner, the number of UAV
pairs closer than the collision distance, the size of the largest connected component of
the interaction graph (union-find), the velocity mismatch to the leader, and a per-swarm
flag for non-finite or runaway states.

Two ways to find the pairs, same results: all pairs (O(N^2) per swarm), or a
:class:`~pairflock_env.swarm.grid.NeighborGrid` (O(N) per swarm for a flock of bounded
density). The grid path visits the pairs of each UAV i with j > i in increasing j, exactly as
the all-pairs loop does, so every floating-point sum is formed in the same order and the two
paths agree bit for bit. Swarms a grid cannot hold (non-finite coordinates) use all pairs.
The per-pair pass for observations and eq. 28 (``pair_pass``) lives in
:mod:`pairflock_env.swarm.pair_pass` and is re-exported here.

This is the only implementation of these equations; every view and vehicle model calls it.
The kernels run single-threaded under numba (compiled code is cached on disk); the small
helpers below are compiled into the kernels that call them.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.config.sections.flocking import repulsion_floor
from pairflock_env.kernels import KernelParams, jit_inline, jit_kernel
from pairflock_env.swarm.grid import (
    GridArrays,
    NeighborGrid,
    check_grid,
    dist2,
    nearest_d2,
    one_ring,
    ring_bound2,
)

__all__ = ["FLOCKING", "FlockScalars", "flocking_params", "flocking_pass"]

#: the flocking pass's parameters, as its kernels receive them (names of the config, squared
#: where the kernels compare squared distances)
FLOCKING = KernelParams(
    "Flocking",
    (
        "attraction",
        "repulsion",
        "inv_sigma2",
        "radius2",
        "consensus",
        "pin_position_gain",
        "pin_velocity_gain",
        "collision_distance2",
        "divergence_limit",
        "floor_radius2",
        "floor_gain",
    ),
)
FlockScalars = namedtuple("FlockScalars", FLOCKING.names)
FlockScalars.__doc__ = "The flocking parameters held in registers by the kernels."
_F = FLOCKING.index


def flocking_params(cfg: PairFlockConfig) -> np.ndarray:
    """The flocking pass's parameter vector (:data:`FLOCKING`) of a config (the repulsion
    floor: :func:`~pairflock_env.config.sections.flocking.repulsion_floor`)."""
    floor_radius2, floor_gain = repulsion_floor(cfg)
    return FLOCKING.pack(
        attraction=cfg.attraction,
        repulsion=cfg.repulsion,
        inv_sigma2=1.0 / cfg.repulsion_sigma2,
        radius2=cfg.radius**2,
        consensus=cfg.consensus,
        pin_position_gain=cfg.pin_position_gain,
        pin_velocity_gain=cfg.pin_velocity_gain,
        collision_distance2=cfg.collision_distance**2,
        divergence_limit=cfg.divergence_limit,
        floor_radius2=floor_radius2,
        floor_gain=floor_gain,
    )


@jit_inline
def _scalars(v):
    return FlockScalars(
        v[_F.attraction],
        v[_F.repulsion],
        v[_F.inv_sigma2],
        v[_F.radius2],
        v[_F.consensus],
        v[_F.pin_position_gain],
        v[_F.pin_velocity_gain],
        v[_F.collision_distance2],
        v[_F.divergence_limit],
        v[_F.floor_radius2],
        v[_F.floor_gain],
    )


# ---------------------------------------------------------------------------------------
# per-swarm pieces of the flocking pass
# ---------------------------------------------------------------------------------------
@jit_inline
def _count_unpaired(partner):
    n = 0
    for i in range(partner.shape[0]):
        if partner[i] < 0:
            n += 1
    return n


@jit_inline
def _velocity_mismatch(p, pl, partner, n_unpaired, b, vmis, vmax):
    """Mean and max of ||p_i - p_leader|| over the unpaired UAVs (all UAVs if none)."""
    N, D = p.shape[1], p.shape[2]
    vsum = 0.0
    vm = 0.0
    for i in range(N):
        if n_unpaired > 0 and partner[i] >= 0:
            continue
        v2 = 0.0
        for k in range(D):
            dv = p[b, i, k] - pl[b, k]
            v2 += dv * dv
        v = np.sqrt(v2)
        vsum += v
        if v > vm:
            vm = v
    vmis[b] = vsum / (n_unpaired if n_unpaired > 0 else N)
    vmax[b] = vm


@jit_inline
def _start_swarm(q, p, ql, pl, h, prm, b, acc, min_d2, parent, size):
    """Pinning term of eq. 19 into ``acc``, fresh union-find and separations; returns the
    divergence flag (a non-finite or runaway coordinate)."""
    N, D = q.shape[1], q.shape[2]
    is_bad = False
    for i in range(N):
        parent[i] = i
        size[i] = 1
        min_d2[b, i] = np.inf
        for k in range(D):
            x = q[b, i, k]
            v = p[b, i, k]
            if not (abs(x) <= prm.divergence_limit and abs(v) <= prm.divergence_limit):
                is_bad = True
            acc[b, i, k] = h[b, i] * (
                prm.pin_position_gain * (ql[b, k] - q[b, i, k])
                + prm.pin_velocity_gain * (pl[b, k] - p[b, i, k])
            )
    return is_bad


@jit_inline
def _find(parent, x):
    """Root of x in the union-find forest, halving the path on the way."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@jit_inline
def _union(parent, size, i, j):
    """Join the components of i and j, the smaller under the larger (shallow trees)."""
    x = _find(parent, i)
    y = _find(parent, j)
    if x != y:
        if size[x] > size[y]:
            x, y = y, x
        parent[x] = y
        size[y] += size[x]


@jit_inline
def _largest_component(parent, size):
    best = 0
    for i in range(parent.shape[0]):
        if parent[i] == i and size[i] > best:
            best = size[i]
    return best


@jit_inline
def _pair_force(q, p, prm, b, i, j, d2, acc):
    """Eqs. 13-18 for the neighbours i < j: symmetric, so f_ij = -f_ji. With the swarm
    layer's floor (floor_radius2 > 0) the repulsion closer than rho* is at least
    F* rho* / rho (w multiplies q_j - q_i, of length rho)."""
    w = prm.attraction - prm.repulsion * np.exp(-d2 * prm.inv_sigma2)
    if d2 < prm.floor_radius2 and d2 > 0.0:
        w = min(w, -prm.floor_gain / d2)
    for k in range(q.shape[2]):
        f = w * (q[b, j, k] - q[b, i, k]) + prm.consensus * (p[b, j, k] - p[b, i, k])
        acc[b, i, k] += f
        acc[b, j, k] -= f


@jit_inline
def _separation(min_d2, b, i, j, partner_i, d2):
    """Nearest non-partner distances of i and j, updated with their pair."""
    if j != partner_i:
        if d2 < min_d2[b, i]:
            min_d2[b, i] = d2
        if d2 < min_d2[b, j]:
            min_d2[b, j] = d2


@jit_kernel
def _pass_all_pairs(q, p, partner, prm, b, acc, min_d2, parent, size):
    """Every pair i < j of swarm b; returns the number of collisions."""
    N = q.shape[1]
    nc = 0
    for i in range(N):
        pi = partner[i]
        for j in range(i + 1, N):
            d2 = dist2(q, b, i, j)
            _separation(min_d2, b, i, j, pi, d2)
            if d2 < prm.collision_distance2:
                nc += 1
            if d2 < prm.radius2:
                _pair_force(q, p, prm, b, i, j, d2, acc)
                _union(parent, size, i, j)
    return nc


@jit_inline
def _sort_by_index(nb_j, nb_d2, n):
    """Insertion sort of the first n neighbours by index (the lists are short)."""
    for t in range(1, n):
        j, d2 = nb_j[t], nb_d2[t]
        s = t
        while s > 0 and nb_j[s - 1] > j:
            nb_j[s] = nb_j[s - 1]
            nb_d2[s] = nb_d2[s - 1]
            s -= 1
        nb_j[s] = j
        nb_d2[s] = d2


@jit_kernel
def _pass_grid(q, p, partner, prm, b, g, acc, min_d2, parent, size, nb_j, nb_d2):
    """:func:`_pass_all_pairs` over the grid's one-ring pairs, same order and results."""
    N = q.shape[1]
    nc = 0
    for i in range(N):
        pi = partner[i]
        n_bk = one_ring(q, b, i, g, g.buckets)
        n = 0
        for t in range(n_bk):
            bk = g.buckets[t]
            end = g.start[b, bk + 1]
            s0 = end  # bucket lists increase: the UAVs after i are a tail
            while s0 > g.start[b, bk] and g.order[b, s0 - 1] > i:
                s0 -= 1
            for s in range(s0, end):
                j = g.order[b, s]
                d2 = dist2(q, b, i, j)
                _separation(min_d2, b, i, j, pi, d2)
                if d2 < prm.collision_distance2:
                    nc += 1
                if d2 < prm.radius2:
                    _union(parent, size, i, j)
                    nb_j[n] = j
                    nb_d2[n] = d2
                    n += 1
        _sort_by_index(nb_j, nb_d2, n)
        for t in range(n):
            _pair_force(q, p, prm, b, i, nb_j[t], nb_d2[t], acc)
    # the one-ring proves separations shorter than a cell; the others need a wider search
    bound = ring_bound2(g, 1)
    for i in range(N):
        if not min_d2[b, i] < bound:
            min_d2[b, i] = nearest_d2(q, b, i, partner[i], g, min_d2[b, i], 1)
    return nc


@jit_kernel
def _flock_swarms(q, p, ql, pl, h, partner, prm, out, work, g):
    """Every swarm: grid pass where ``g`` holds the swarm, all pairs otherwise."""
    acc, min_d2, n_coll, lcc, bad, vmis, vmax = out
    parent, size, nb_j, nb_d2 = work
    n_unpaired = _count_unpaired(partner)
    for b in range(q.shape[0]):
        _velocity_mismatch(p, pl, partner, n_unpaired, b, vmis, vmax)
        bad[b] = _start_swarm(q, p, ql, pl, h, prm, b, acc, min_d2, parent, size)
        if g is not None and g.ok[b]:
            n_coll[b] = _pass_grid(q, p, partner, prm, b, g, acc, min_d2, parent, size, nb_j, nb_d2)
        else:
            n_coll[b] = _pass_all_pairs(q, p, partner, prm, b, acc, min_d2, parent, size)
        lcc[b] = _largest_component(parent, size)


# The entry points take arrays one by one: the dispatcher types plain arrays fastest, which
# matters for small swarms, where a pass takes a few microseconds.
@jit_kernel
def _flocking_kernel(
    q, p, ql, pl, h, partner, prm, acc, min_d2, ncol, lcc, bad, vmis, vmax, parent, size, nbj, nbd
):
    out = (acc, min_d2, ncol, lcc, bad, vmis, vmax)
    _flock_swarms(q, p, ql, pl, h, partner, _scalars(prm), out, (parent, size, nbj, nbd), None)


@jit_kernel
def _flocking_grid_kernel(
    q,
    p,
    ql,
    pl,
    h,
    partner,
    prm,
    acc,
    min_d2,
    ncol,
    lcc,
    bad,
    vmis,
    vmax,
    parent,
    size,
    nbj,
    nbd,
    *grid,
):
    out = (acc, min_d2, ncol, lcc, bad, vmis, vmax)
    work = (parent, size, nbj, nbd)
    _flock_swarms(q, p, ql, pl, h, partner, _scalars(prm), out, work, GridArrays(*grid))


def flocking_pass(
    params: np.ndarray,
    q: np.ndarray,
    p: np.ndarray,
    leader_q: np.ndarray,
    leader_p: np.ndarray,
    pinned: np.ndarray,
    partner: np.ndarray,
    out: dict[str, np.ndarray] | None = None,
    grid: NeighborGrid | None = None,
) -> dict[str, np.ndarray]:
    """Flocking acceleration and proximity quantities of every UAV.

    Args:
        params: the parameter vector of :func:`flocking_params`.
        q, p: positions and velocities, (B, N, dim) float64.
        leader_q, leader_p: virtual leader, (B, dim).
        pinned: h_i of eq. 6 as 0/1 floats, (B, N).
        partner: partner index of each UAV or -1, (N,) int64.
        out: preallocated outputs to reuse (as returned by a previous call).
        grid: ``None`` for all pairs, or a :class:`~pairflock_env.swarm.grid.NeighborGrid`
            with ``cell_size >= max(radius, collision_distance)``, built from ``q``'s current
            values. Both give identical results.

    Returns:
        dict with ``acc`` (B, N, dim) m/s^2, ``min_d2`` (B, N) squared distance to the nearest
        non-partner UAV, ``collisions`` (B,) int, ``largest_component`` (B,) int,
        ``diverged`` (B,) bool, ``velocity_mismatch`` / ``velocity_mismatch_max`` (B,) mean
        and max of ||p_i - p_leader|| over the unpaired UAVs (all UAVs when every UAV is
        paired). Per-swarm sums run sequentially, so results do not depend on B.
    """
    B, N, D = q.shape
    check_grid(
        grid,
        q.shape,
        max(params[_F.radius2], params[_F.collision_distance2]),
        "max(radius, collision_distance)",
    )
    if out is None or out["acc"].shape != q.shape:
        out = {
            "acc": np.empty((B, N, D)),
            "min_d2": np.empty((B, N)),
            "collisions": np.empty(B, np.int64),
            "largest_component": np.empty(B, np.int64),
            "diverged": np.empty(B, np.bool_),
            "velocity_mismatch": np.empty(B),
            "velocity_mismatch_max": np.empty(B),
            "_parent": np.empty(N, np.int64),
            "_size": np.empty(N, np.int64),
            "_nb_j": np.empty(N, np.int64),
            "_nb_d2": np.empty(N),
        }
    args = (
        q,
        p,
        leader_q,
        leader_p,
        pinned,
        partner,
        params,
        out["acc"],
        out["min_d2"],
        out["collisions"],
        out["largest_component"],
        out["diverged"],
        out["velocity_mismatch"],
        out["velocity_mismatch_max"],
        out["_parent"],
        out["_size"],
        out["_nb_j"],
        out["_nb_d2"],
    )
    if grid is None:
        _flocking_kernel(*args)
    else:
        _flocking_grid_kernel(*args, *grid.arrays)
    return out
