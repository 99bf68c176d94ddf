"""The flocking protocol of eqs. 11-19 and the proximity quantities, in one O(N^2) sweep.

For every UAV i of every swarm b (arrays shaped (B, N, dim)):

    f_i^g = sum_{j in N_i} (q_j - q_i) [a - g_r(||q_j - q_i||)]           eqs. 13-16
            g_r(rho) = b_r exp(-rho^2 / sigma^2),  g_r(d) = a
    f_i^v = b sum_{j in N_i} (p_j - p_i)                                  eq. 18
    f_i^gamma = c1 (q_gamma - q_i) + c2 (p_gamma - p_i)                   eq. 19
    a_i = f_i^g + f_i^v + h_i f_i^gamma                                   eq. 11 without f^x
    N_i = { j != i : ||q_i - q_j|| < r }                                  eq. 2

The same sweep also yields what metrics and rewards need, so no second pass over the pairs
is made: each UAV's smallest distance to any UAV other than its partner, the number of UAV
pairs closer than the collision distance, the size of the largest connected component of
the interaction graph (union-find), the velocity mismatch to the leader, and a per-swarm
flag for non-finite or runaway states.

This is the only implementation of these equations; every view and vehicle model calls it.
The kernels run single-threaded under numba (one JIT-compiled function per dtype signature;
compiled code is cached on disk).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .config import PairFlockConfig

__all__ = ["FlockingParams", "flocking_pass", "pair_pass"]


class FlockingParams:
    """Scalar parameters of the flocking sweep, unpacked once from a config."""

    __slots__ = ("a", "b_r", "c1", "c2", "coll2", "consensus", "inv_sigma2", "limit", "r2")

    def __init__(self, cfg: PairFlockConfig) -> None:
        self.a = cfg.attraction
        self.b_r = cfg.repulsion
        self.inv_sigma2 = 1.0 / cfg.repulsion_sigma2
        self.r2 = cfg.radius**2
        self.consensus = cfg.consensus
        self.c1 = cfg.pin_position_gain
        self.c2 = cfg.pin_velocity_gain
        self.coll2 = cfg.collision_distance**2
        self.limit = cfg.divergence_limit


@njit(cache=True, nogil=True)
def _flocking_kernel(
    q,
    p,
    ql,
    pl,
    h,
    partner,
    a,
    b_r,
    inv_s2,
    r2,
    cons,
    c1,
    c2,
    coll2,
    limit,
    acc,
    min_d2,
    n_coll,
    lcc,
    bad,
    vmis,
    vmax,
    parent,
    size,
):
    B, N, D = q.shape
    n_unpaired = 0
    for i in range(N):
        if partner[i] < 0:
            n_unpaired += 1
    for b in range(B):
        # velocity mismatch to the leader over the unpaired UAVs (all UAVs if none)
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
        # divergence check and pinning term (eq. 19)
        is_bad = False
        for i in range(N):
            parent[i] = i
            size[i] = 0
            min_d2[b, i] = np.inf
            for k in range(D):
                x = q[b, i, k]
                v = p[b, i, k]
                if not (abs(x) <= limit and abs(v) <= limit):
                    is_bad = True
                acc[b, i, k] = h[b, i] * (
                    c1 * (ql[b, k] - q[b, i, k]) + c2 * (pl[b, k] - p[b, i, k])
                )
        bad[b] = is_bad
        nc = 0
        for i in range(N):
            pi = partner[i]
            for j in range(i + 1, N):
                d2 = 0.0
                for k in range(D):
                    dx = q[b, j, k] - q[b, i, k]
                    d2 += dx * dx
                if j != pi:
                    if d2 < min_d2[b, i]:
                        min_d2[b, i] = d2
                    if d2 < min_d2[b, j]:
                        min_d2[b, j] = d2
                if d2 < coll2:
                    nc += 1
                if d2 < r2:
                    # eqs. 13-18: symmetric, so f_ij = -f_ji
                    w = a - b_r * np.exp(-d2 * inv_s2)
                    for k in range(D):
                        f = w * (q[b, j, k] - q[b, i, k]) + cons * (p[b, j, k] - p[b, i, k])
                        acc[b, i, k] += f
                        acc[b, j, k] -= f
                    # union-find with path halving
                    x = i
                    while parent[x] != x:
                        parent[x] = parent[parent[x]]
                        x = parent[x]
                    y = j
                    while parent[y] != y:
                        parent[y] = parent[parent[y]]
                        y = parent[y]
                    if x != y:
                        parent[x] = y
        n_coll[b] = nc
        best = 0
        for i in range(N):
            x = i
            while parent[x] != x:
                x = parent[x]
            size[x] += 1
            if size[x] > best:
                best = size[x]
        lcc[b] = best


def flocking_pass(
    params: FlockingParams,
    q: np.ndarray,
    p: np.ndarray,
    leader_q: np.ndarray,
    leader_p: np.ndarray,
    pinned: np.ndarray,
    partner: np.ndarray,
    out: dict[str, np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """Flocking acceleration and proximity quantities of every UAV.

    Args:
        q, p: positions and velocities, (B, N, dim) float64.
        leader_q, leader_p: virtual leader, (B, dim).
        pinned: h_i of eq. 6 as 0/1 floats, (B, N).
        partner: partner index of each UAV or -1, (N,) int64.
        out: preallocated outputs to reuse (as returned by a previous call).

    Returns:
        dict with ``acc`` (B, N, dim) m/s^2, ``min_d2`` (B, N) squared distance to the nearest
        non-partner UAV, ``collisions`` (B,) int, ``largest_component`` (B,) int,
        ``diverged`` (B,) bool, ``velocity_mismatch`` / ``velocity_mismatch_max`` (B,) mean
        and max of ||p_i - p_leader|| over the unpaired UAVs (all UAVs when every UAV is
        paired). Per-swarm sums run sequentially, so results do not depend on B.
    """
    B, N, D = q.shape
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
        }
    pr = params
    _flocking_kernel(
        q,
        p,
        leader_q,
        leader_p,
        pinned,
        partner,
        pr.a,
        pr.b_r,
        pr.inv_sigma2,
        pr.r2,
        pr.consensus,
        pr.c1,
        pr.c2,
        pr.coll2,
        pr.limit,
        out["acc"],
        out["min_d2"],
        out["collisions"],
        out["largest_component"],
        out["diverged"],
        out["velocity_mismatch"],
        out["velocity_mismatch_max"],
        out["_parent"],
        out["_size"],
    )
    return out


@njit(cache=True, nogil=True)
def _pair_kernel(q, p, agents, partners, r2, shared, nbr_pos, nbr_vel, nbr_mask, best_d2, best_j):
    B, N, D = q.shape
    M = agents.shape[0]
    K = nbr_pos.shape[2]
    for b in range(B):
        # shared neighbour count of each pair (eq. 28, Assumption 4); agents come in (A, B)
        for m in range(0, M, 2):
            ia = agents[m]
            ib = agents[m + 1]
            cnt = 0
            for j in range(N):
                if j in (ia, ib):
                    continue
                da = 0.0
                db = 0.0
                for k in range(D):
                    x = q[b, j, k] - q[b, ia, k]
                    da += x * x
                    x = q[b, j, k] - q[b, ib, k]
                    db += x * x
                if da < r2 and db < r2:
                    cnt += 1
            dab = 0.0
            for k in range(D):
                x = q[b, ib, k] - q[b, ia, k]
                dab += x * x
            if dab < r2:
                cnt += 2  # the mutual link contributes -2a y - 2b y' to y''
            shared[b, m // 2] = cnt
        # K nearest non-partner UAVs of each agent, sorted by distance
        for m in range(M):
            i = agents[m]
            pi = partners[m]
            for s in range(K):
                best_d2[s] = np.inf
                best_j[s] = -1
            for j in range(N):
                if j in (i, pi):
                    continue
                d2 = 0.0
                for k in range(D):
                    x = q[b, j, k] - q[b, i, k]
                    d2 += x * x
                if K > 0 and d2 < best_d2[K - 1]:
                    s = K - 1
                    while s > 0 and best_d2[s - 1] > d2:
                        best_d2[s] = best_d2[s - 1]
                        best_j[s] = best_j[s - 1]
                        s -= 1
                    best_d2[s] = d2
                    best_j[s] = j
            for s in range(K):
                j = best_j[s]
                if j >= 0:
                    nbr_mask[b, m, s] = 1.0
                    for k in range(D):
                        nbr_pos[b, m, s, k] = q[b, j, k] - q[b, i, k]
                        nbr_vel[b, m, s, k] = p[b, j, k] - p[b, i, k]
                else:
                    nbr_mask[b, m, s] = 0.0
                    for k in range(D):
                        nbr_pos[b, m, s, k] = 0.0
                        nbr_vel[b, m, s, k] = 0.0


def pair_pass(
    q: np.ndarray,
    p: np.ndarray,
    agents: np.ndarray,
    partners: np.ndarray,
    radius: float,
    n_neighbors: int,
    out: dict[str, np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """Per-pair shared neighbour counts and each agent's K nearest other UAVs.

    Args:
        agents: UAV index of each agent, (M,) with pairs laid out as A0, B0, A1, B1, ...
        partners: partner UAV index of each agent, (M,).

    Returns:
        dict with ``shared`` (B, P) float (N of eq. 28: |N_A & N_B|, plus 2 when A and B are
        neighbours of each other), ``nbr_pos`` / ``nbr_vel`` (B, M, K, dim) offsets of the K
        nearest non-partner UAVs (nearest first, zero-padded) and ``nbr_mask`` (B, M, K).
    """
    B, _N, D = q.shape
    M = agents.shape[0]
    K = n_neighbors
    if out is None or out["nbr_pos"].shape != (B, M, K, D):
        out = {
            "shared": np.empty((B, M // 2)),
            "nbr_pos": np.empty((B, M, K, D)),
            "nbr_vel": np.empty((B, M, K, D)),
            "nbr_mask": np.empty((B, M, K)),
            "_best_d2": np.empty(max(K, 1)),
            "_best_j": np.empty(max(K, 1), np.int64),
        }
    _pair_kernel(
        q,
        p,
        agents,
        partners,
        radius**2,
        out["shared"],
        out["nbr_pos"],
        out["nbr_vel"],
        out["nbr_mask"],
        out["_best_d2"],
        out["_best_j"],
    )
    return out
