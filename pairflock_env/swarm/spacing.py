"""Initial placement with a minimum spacing, in O(N) memory and O(N) work per round.

The rejection sampler is the one the core has always used, so every random draw, and
therefore every initial state, stays the same: draw every free UAV uniformly in its start
box; then, round after round, redraw (in index order, one ``uniform`` call per round) every
free UAV that is closer than the spacing to a fixed UAV or to a UAV of lower index. Only the
conflict test changed: a :class:`~pairflock_env.swarm.grid.NeighborGrid` with cells of the
spacing finds the same conflicting set as the N x N distance matrix did, comparing the same
floating-point squared distances.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import jit_inline, jit_kernel
from pairflock_env.swarm.grid import (
    GridArrays,
    NeighborGrid,
    dist2,
    one_ring,
)

__all__ = ["place", "redraw_conflicts"]


@jit_inline
def _is_conflict(q, fixed, s2, i, j):
    return j != i and (j < i or fixed[j]) and dist2(q, 0, i, j) < s2


@jit_kernel
def _conflicts(q, fixed, s2, out, *grid):
    """Mark the free UAVs closer than sqrt(s2) to a fixed UAV or a lower index; count them."""
    g = GridArrays(*grid)
    N = q.shape[1]
    n = 0
    for i in range(N):
        hit = False
        if not fixed[i] and g.ok[0]:
            n_bk = one_ring(q, 0, i, g, g.buckets)
            for t in range(n_bk):
                bk = g.buckets[t]
                for s in range(g.start[0, bk], g.start[0, bk + 1]):
                    hit = hit or _is_conflict(q, fixed, s2, i, g.order[0, s])
        elif not fixed[i]:
            for j in range(N):
                hit = hit or _is_conflict(q, fixed, s2, i, j)
        out[i] = hit
        n += hit
    return n


def redraw_conflicts(
    rng: np.random.Generator,
    q: np.ndarray,
    half: np.ndarray,
    fixed: np.ndarray,
    min_spacing: float,
    max_rounds: int = 1000,
) -> bool:
    """Redraw conflicting free UAVs of ``q`` in place until none is left.

    Args:
        rng: the swarm's generator; one ``uniform(-1, 1, (n, dim))`` draw per round with a
            conflict (n conflicting UAVs, in index order).
        q: (N, dim) float64 positions relative to the box centre, updated in place.
        half: (N, dim) or (N, 1) half-widths of each UAV's start box.
        fixed: (N,) bool, UAVs that never move (e.g. pair members placed in corners).
        min_spacing: no free UAV may end closer than this to a fixed or lower-index UAV.
        max_rounds: rounds before giving up.

    Returns:
        True when no conflict is left, False after ``max_rounds`` rounds.
    """
    N, D = q.shape
    if not min_spacing > 0:
        return True
    grid = NeighborGrid(1, N, D, cell_size=float(min_spacing))
    s2 = float(min_spacing) ** 2
    conflict = np.zeros(N, np.bool_)
    fixed = np.ascontiguousarray(fixed, dtype=np.bool_)
    q3 = q[None]
    for _ in range(max_rounds):
        grid.build(q3)
        if _conflicts(q3, fixed, s2, conflict, *grid.arrays) == 0:
            return True
        idx = np.flatnonzero(conflict)
        q[idx] = rng.uniform(-1.0, 1.0, (idx.size, D)) * half[idx]
    return False


def place(
    rng: np.random.Generator,
    half: np.ndarray,
    fixed_q: np.ndarray,
    fixed: np.ndarray,
    min_spacing: float,
    center: np.ndarray,
    max_rounds: int = 1000,
) -> np.ndarray:
    """Initial positions of one swarm: free UAVs uniform in their boxes, spaced apart.

    Args:
        rng: the swarm's generator (draws: one ``uniform`` for every free UAV, then one per
            round of :func:`redraw_conflicts`).
        half: (N, dim) or (N, 1) half-widths of each UAV's start box around ``center``.
        fixed_q: (N, dim) positions relative to ``center``; only the rows of fixed UAVs are
            read.
        fixed: (N,) bool, UAVs placed by the caller.
        min_spacing: smallest distance between a free UAV and any fixed or lower-index UAV
            (0 = no constraint).
        center: (dim,) centre of the start box.

    Returns:
        (N, dim) absolute positions.

    Raises:
        ValueError: when ``max_rounds`` rounds leave a conflict (the boxes are too crowded).
    """
    fixed = np.asarray(fixed, dtype=np.bool_)
    fixed_q = np.asarray(fixed_q, dtype=np.float64)
    q = np.empty(fixed_q.shape)
    q[fixed] = fixed_q[fixed]
    free = np.flatnonzero(~fixed)
    q[free] = rng.uniform(-1.0, 1.0, (free.size, q.shape[1])) * half[free]
    if not redraw_conflicts(rng, q, half, fixed, min_spacing, max_rounds):
        raise ValueError(
            f"min_spacing={min_spacing!r} is invalid: cannot place {q.shape[0]} UAVs that far "
            f"apart in their start boxes within {max_rounds} rounds"
        )
    return q + center
