"""The pair pass: shared neighbours of each pair (eq. 28) and each agent's K nearest UAVs.

Like the flocking pass it runs over all pairs or over a
:class:`~pairflock_env.swarm.grid.NeighborGrid`, with identical results: the shared count is
an integer over the same distance tests, and the K nearest are the K smallest
(squared distance, index) pairs whatever order the candidates are found in. Over all pairs,
each agent's squared distances to every UAV are computed once into a row (a loop that
vectorises) and both the shared count and the K nearest are read from it; kernels are
compiled per dimension.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import BoundKernel, jit_inline, jit_kernel
from pairflock_env.swarm.grid import (
    GridArrays,
    NeighborGrid,
    check_grid,
    dist2,
    insert_nearest,
    k_nearest_grid,
    one_ring,
    reset_nearest,
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
    link contributes -2a y - 2b y' to y''. On the grid: A's one-ring."""
    cnt = 0
    n_bk = one_ring(q, b, ia, g, g.buckets)
    for t in range(n_bk):
        bk = g.buckets[t]
        for s in range(g.start[b, bk], g.start[b, bk + 1]):
            cnt += _is_shared(q, b, ia, ib, g.order[b, s], r2)
    if dist2(q, b, ia, ib) < r2:
        cnt += 2
    return cnt


@jit_inline
def _dist_row(q, b, i, row, three):
    """row[j]: the squared distance of UAVs i and j of swarm b, for every j (the numbers of
    :func:`~pairflock_env.swarm.grid.dist2`, axes summed in order; this loop vectorises)."""
    x0, x1 = q[b, i, 0], q[b, i, 1]
    x2 = q[b, i, 2] if three else 0.0
    for j in range(q.shape[1]):
        a, e = q[b, j, 0] - x0, q[b, j, 1] - x1
        d2 = a * a + e * e
        if three:
            z = q[b, j, 2] - x2
            d2 += z * z
        row[j] = d2


@jit_inline
def _shared_in_rows(ra, rb, ia, ib, r2):
    """:func:`_shared_count` over all pairs, from A's and B's distance rows (vectorised)."""
    cnt = 0
    for j in range(ra.shape[0]):
        cnt += (ra[j] < r2) & (rb[j] < r2) & (j != ia) & (j != ib)
    return cnt + (2 if ra[ib] < r2 else 0)


@jit_inline
def _nearest_in_row(row, i, skip, best_d2, best_j, K):
    """The K nearest UAVs of UAV i other than i and ``skip``, from i's distance row: the K
    smallest (squared distance, index) pairs in lexicographic order (ties to the lower
    index; a non-finite distance never among them), the rest of the list (inf, -1).
    Writes inf into row[i] and row[skip]."""
    reset_nearest(best_d2, best_j)
    row[i] = np.inf  # (an infinite distance is never taken: insert_nearest)
    if skip >= 0:
        row[skip] = np.inf
    worst = np.inf  # best_d2[K - 1], kept in a register
    for j in range(row.shape[0] if K > 0 else 0):
        d = row[j]
        if d <= worst:
            insert_nearest(best_d2, best_j, K, d, j)
            worst = best_d2[K - 1]


@jit_inline
def _write_neighbors(q, p, b, m, i, best_j, nbr_pos, nbr_vel, nbr_mask, three):
    """Offsets of agent m's (UAV i's) K nearest, zero-padded where fewer exist."""
    for s in range(nbr_pos.shape[2]):
        j = best_j[s]
        if j >= 0:
            nbr_mask[b, m, s] = 1.0
            for k in range(3 if three else 2):
                nbr_pos[b, m, s, k] = q[b, j, k] - q[b, i, k]
                nbr_vel[b, m, s, k] = p[b, j, k] - p[b, i, k]
        else:
            nbr_mask[b, m, s] = 0.0
            for k in range(3 if three else 2):
                nbr_pos[b, m, s, k] = 0.0
                nbr_vel[b, m, s, k] = 0.0


@jit_kernel
def _pair_swarms(q, p, agents, partners, r2, out, work, g, dims):
    """Every swarm: on the grid where ``g`` holds it, else from each agent's distance row.
    ``dims``: a tuple of ``dim`` entries, so that 2-D and 3-D compile apart."""
    shared, nbr_pos, nbr_vel, nbr_mask = out
    best_d2, best_j, rows = work
    K = nbr_pos.shape[2]
    three = len(dims) == 3
    for b in range(q.shape[0]):
        on_grid = g is not None and g.ok[b]
        for m in range(0, agents.shape[0], 2):  # agents come in (A, B)
            ia, ib = agents[m], agents[m + 1]
            if on_grid:
                shared[b, m // 2] = _shared_count(q, b, ia, ib, r2, g)
            else:
                _dist_row(q, b, ia, rows[0], three)
                _dist_row(q, b, ib, rows[1], three)
                shared[b, m // 2] = _shared_in_rows(rows[0], rows[1], ia, ib, r2)
            for t in range(2):
                i, skip = agents[m + t], partners[m + t]
                if on_grid:
                    k_nearest_grid(q, b, i, skip, g, best_d2, best_j, K)
                else:
                    _nearest_in_row(rows[t], i, skip, best_d2, best_j, K)
                _write_neighbors(q, p, b, m + t, i, best_j, nbr_pos, nbr_vel, nbr_mask, three)


@jit_kernel
def _pair_kernel(q, p, agents, partners, r2, dims, sh, n_pos, n_vel, n_mask, b_d2, b_j, rows):
    out = (sh, n_pos, n_vel, n_mask)
    _pair_swarms(q, p, agents, partners, r2, out, (b_d2, b_j, rows), None, dims)


@jit_kernel
def _pair_grid_kernel(
    q, p, agents, partners, r2, dims, sh, n_pos, n_vel, n_mask, b_d2, b_j, rows, *grid
):
    out = (sh, n_pos, n_vel, n_mask)
    _pair_swarms(q, p, agents, partners, r2, out, (b_d2, b_j, rows), GridArrays(*grid), dims)


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
    B, N, D = shape
    M = agents.shape[0]
    K = n_neighbors
    check_grid(grid, tuple(shape), radius**2, "radius")
    if out is None or out["nbr_pos"].shape != (B, M, K, D) or out["_rows"].shape != (2, N):
        out = {
            "shared": np.empty((B, M // 2)),
            "nbr_pos": np.empty((B, M, K, D)),
            "nbr_vel": np.empty((B, M, K, D)),
            "nbr_mask": np.empty((B, M, K)),
            "_best_d2": np.empty(max(K, 1)),
            "_best_j": np.empty(max(K, 1), np.int64),
            "_rows": np.empty((2, N)),
        }
    keys = ("shared", "nbr_pos", "nbr_vel", "nbr_mask", "_best_d2", "_best_j", "_rows")
    tail = (agents, partners, radius**2, (0,) * D, *(out[k] for k in keys))
    if grid is None:
        return BoundKernel(_pair_kernel, tail, out)
    return BoundKernel(_pair_grid_kernel, (*tail, *grid.arrays), out)
