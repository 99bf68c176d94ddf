"""The pair pass: shared neighbours of each pair (eq. 28) and each agent's K nearest UAVs.

Like the flocking pass it runs over all pairs or over a
:class:`~pairflock_env.swarm.grid.NeighborGrid`, with identical results: the shared count is
an integer over the same distance tests, and the K nearest are the K smallest
(squared distance, index) pairs whatever order the candidates are found in.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import BoundKernel, jit_inline, jit_kernel
from pairflock_env.swarm.grid import (
    GridArrays,
    NeighborGrid,
    check_grid,
    dist2,
    k_nearest_all_pairs,
    k_nearest_grid,
    one_ring,
)

__all__ = ["pair_pass"]


@jit_inline
def _is_shared(q, b, ia, ib, j, r2):
    """1 if UAV j (neither ia nor ib) is a neighbour of both ia and ib, else 0."""
    if j in (ia, ib):
        return 0
    return 1 if dist2(q, b, ia, j) < r2 and dist2(q, b, ib, j) < r2 else 0


@jit_inline
def _shared_count(q, b, ia, ib, r2, g):
    """|N_A & N_B| of eq. 28 (Assumption 4), plus 2 when A and B are neighbours: the mutual
    link contributes -2a y - 2b y' to y''."""
    cnt = 0
    if g is not None and g.ok[b]:
        n_bk = one_ring(q, b, ia, g, g.buckets)
        for t in range(n_bk):
            bk = g.buckets[t]
            for s in range(g.start[b, bk], g.start[b, bk + 1]):
                cnt += _is_shared(q, b, ia, ib, g.order[b, s], r2)
    else:
        for j in range(q.shape[1]):
            cnt += _is_shared(q, b, ia, ib, j, r2)
    if dist2(q, b, ia, ib) < r2:
        cnt += 2
    return cnt


@jit_inline
def _write_neighbors(q, p, b, m, i, best_j, K, nbr_pos, nbr_vel, nbr_mask):
    """Offsets of agent m's (UAV i's) K nearest, zero-padded where fewer exist."""
    D = q.shape[2]
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


@jit_kernel
def _pair_swarms(q, p, agents, partners, r2, out, work, g):
    shared, nbr_pos, nbr_vel, nbr_mask = out
    best_d2, best_j = work
    K = nbr_pos.shape[2]
    for b in range(q.shape[0]):
        for m in range(0, agents.shape[0], 2):  # agents come in (A, B)
            shared[b, m // 2] = _shared_count(q, b, agents[m], agents[m + 1], r2, g)
        for m in range(agents.shape[0]):
            i = agents[m]
            if g is not None and g.ok[b]:
                k_nearest_grid(q, b, i, partners[m], g, best_d2, best_j, K)
            else:
                k_nearest_all_pairs(q, b, i, partners[m], best_d2, best_j, K)
            _write_neighbors(q, p, b, m, i, best_j, K, nbr_pos, nbr_vel, nbr_mask)


@jit_kernel
def _pair_kernel(q, p, agents, partners, r2, shared, nbr_pos, nbr_vel, nbr_mask, best_d2, best_j):
    out = (shared, nbr_pos, nbr_vel, nbr_mask)
    _pair_swarms(q, p, agents, partners, r2, out, (best_d2, best_j), None)


@jit_kernel
def _pair_grid_kernel(
    q, p, agents, partners, r2, shared, nbr_pos, nbr_vel, nbr_mask, best_d2, best_j, *grid
):
    out = (shared, nbr_pos, nbr_vel, nbr_mask)
    _pair_swarms(q, p, agents, partners, r2, out, (best_d2, best_j), GridArrays(*grid))


def pair_pass(
    q: np.ndarray,
    p: np.ndarray,
    agents: np.ndarray,
    partners: np.ndarray,
    radius: float,
    n_neighbors: int,
    out: dict[str, np.ndarray] | None = None,
    grid: NeighborGrid | None = None,
) -> dict[str, np.ndarray]:
    """Per-pair shared neighbour counts and each agent's K nearest other UAVs.

    Args:
        agents: UAV index of each agent, (M,) with pairs laid out as A0, B0, A1, B1, ...
        partners: partner UAV index of each agent, (M,).
        grid: ``None`` for all pairs, or a :class:`~pairflock_env.swarm.grid.NeighborGrid`
            with ``cell_size >= radius`` built from ``q``'s current values (same results).

    Returns:
        dict with ``shared`` (B, P) float (N of eq. 28: |N_A & N_B|, plus 2 when A and B are
        neighbours of each other), ``nbr_pos`` / ``nbr_vel`` (B, M, K, dim) offsets of the K
        nearest non-partner UAVs (nearest first, ties to the lower index, zero-padded) and
        ``nbr_mask`` (B, M, K).
    """
    run = pair_runner(q.shape, agents, partners, radius, n_neighbors, grid, out)
    return run(q, p)


def pair_runner(
    shape: tuple[int, int, int],
    agents: np.ndarray,
    partners: np.ndarray,
    radius: float,
    n_neighbors: int,
    grid: NeighborGrid | None = None,
    out: dict[str, np.ndarray] | None = None,
):
    """:func:`pair_pass` for repeated calls on arrays of ``shape`` (B, N, dim) with the same
    agents: checked and allocated once. Returns ``run(q, p) -> out`` (the same dict)."""
    B, _N, D = shape
    M = agents.shape[0]
    K = n_neighbors
    check_grid(grid, tuple(shape), radius**2, "radius")
    if out is None or out["nbr_pos"].shape != (B, M, K, D):
        out = {
            "shared": np.empty((B, M // 2)),
            "nbr_pos": np.empty((B, M, K, D)),
            "nbr_vel": np.empty((B, M, K, D)),
            "nbr_mask": np.empty((B, M, K)),
            "_best_d2": np.empty(max(K, 1)),
            "_best_j": np.empty(max(K, 1), np.int64),
        }
    keys = ("shared", "nbr_pos", "nbr_vel", "nbr_mask", "_best_d2", "_best_j")
    tail = (agents, partners, radius**2, *(out[k] for k in keys))
    if grid is None:
        return BoundKernel(_pair_kernel, tail, out)
    return BoundKernel(_pair_grid_kernel, (*tail, *grid.arrays), out)
