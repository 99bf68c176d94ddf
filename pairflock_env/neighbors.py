"""Neighbour search: the distance and K-nearest primitives, and a uniform grid (cell list).

Every consumer of neighbours (the flocking sweep, separations, collisions, connectivity, the
shared-neighbour count of eq. 28, the K nearest for observations, pinning, placement and the
safety filter) reads distances through the primitives here, so the all-pairs path and the
grid path compare exactly the same floating-point numbers and give the same answers.

The grid
--------
:class:`NeighborGrid` keeps one cell list per swarm of a batch (B swarms, N UAVs, in 2-D or
3-D). Cells are cubes of edge ``h`` slightly above the requested ``cell_size`` (so that two
UAVs closer than ``cell_size`` always sit in the same or adjacent cells despite rounding), laid
out from the swarm's lowest corner. Building is a counting sort, O(N + C) per swarm, where C
(the number of buckets, ``4 N + 64`` by default) bounds the memory whatever the swarm's extent:
when the extent needs more cells than C, the longest axes are folded (cell coordinates taken
modulo the axis length, as in a spatial hash), so far-apart cells may share a bucket. Queries
filter candidates by their true distance, never visit a bucket twice, and therefore stay exact;
folding only costs extra candidates. Swarms with non-finite coordinates, or coordinates beyond
about 2^36 cells, are marked not ``ok`` and every consumer falls back to all pairs for them.

Within a bucket UAVs are listed in increasing index order (the counting sort is stable), which
lets the flocking sweep reproduce the all-pairs summation order bit for bit.
"""

from __future__ import annotations

import functools
from collections import namedtuple

import numpy as np
from numba import njit

__all__ = ["GridArrays", "NeighborGrid", "nearest_indices"]

#: cells are this much (relative) larger than requested, so that rounding of cell coordinates
#: (at most ``_ROUNDING`` cells) never separates two UAVs closer than the requested size by
#: more than one cell
_CELL_MARGIN = 1e-3
#: bound on the rounding error of a computed cell coordinate, in cells, valid while the
#: coordinate stays below ``_MAX_CELLS`` (3 roundings of 2^-53 relative error each)
_ROUNDING = 1e-4
_MAX_CELLS = 2.0**36

# Every kernel here and in the sweeps is compiled without numba's reference counting: they
# never allocate, and the count updates that numba adds around inlined helpers taking arrays
# inside branchy loops (which its pruning pass cannot remove, numba issue #2350) cost 5-30x
# in the pair loops.
jit_kernel = functools.partial(njit, cache=True, nogil=True, _nrt=False)
jit_inline = functools.partial(njit, cache=True, inline="always", _nrt=False)

GridArrays = namedtuple(
    "GridArrays",
    ["h", "inv_h", "origin", "dims", "wrap", "ok", "cell", "start", "order", "buckets"],
)
GridArrays.__doc__ = """The arrays of a :class:`NeighborGrid`, as numba kernels take them.

``h`` / ``inv_h``: cell edge (m) and its inverse; ``origin`` (B, 3): lowest corner of each
swarm; ``dims`` (B, 3) buckets per axis (1 on unused axes); ``wrap`` (B, 3): axis folded;
``ok`` (B,): grid usable; ``cell`` (B, N, 3) cell coordinates of each UAV; ``start`` (B, C + 1)
and ``order`` (B, N): bucket c holds UAVs ``order[b, start[b, c]:start[b, c + 1]]``;
``buckets`` (C,): scratch for the bucket list of one query.
"""


# ---------------------------------------------------------------------------------------
# primitives shared by the all-pairs and the grid paths
# ---------------------------------------------------------------------------------------
@jit_inline
def dist2(q, b, i, j):
    """Squared distance of UAVs i and j of swarm b, summed over axes in order (from 0.0)."""
    d2 = 0.0
    for k in range(q.shape[2]):
        x = q[b, j, k] - q[b, i, k]
        d2 += x * x
    return d2


@jit_inline
def reset_nearest(best_d2, best_j):
    """Empty a K-nearest list (distance inf, index -1)."""
    for s in range(best_d2.shape[0]):
        best_d2[s] = np.inf
        best_j[s] = -1


@jit_inline
def insert_nearest(best_d2, best_j, K, d2, j):
    """Insert candidate j into the sorted K-nearest list.

    The list holds the K smallest (d2, index) pairs in lexicographic order: ties in distance
    go to the lower index, whatever order candidates arrive in.
    """
    if K == 0:
        return
    last = K - 1
    if not (d2 < best_d2[last] or (d2 == best_d2[last] and j < best_j[last])):
        return
    s = last
    while s > 0 and (best_d2[s - 1] > d2 or (best_d2[s - 1] == d2 and best_j[s - 1] > j)):
        best_d2[s] = best_d2[s - 1]
        best_j[s] = best_j[s - 1]
        s -= 1
    best_d2[s] = d2
    best_j[s] = j


@jit_kernel
def k_nearest_all_pairs(q, b, i, skip, best_d2, best_j, K):
    """K nearest UAVs of UAV i other than i and ``skip`` by scanning every UAV."""
    reset_nearest(best_d2, best_j)
    for j in range(q.shape[1]):
        if j in (i, skip):
            continue
        insert_nearest(best_d2, best_j, K, dist2(q, b, i, j), j)


# ---------------------------------------------------------------------------------------
# grid construction
# ---------------------------------------------------------------------------------------
@jit_kernel
def _axis_extent(q, b, k, inv_h):
    """Lowest coordinate of swarm b along axis k and the cells its extent spans (0 if the
    coordinates are not finite or span more cells than a grid can index)."""
    lo, hi = np.inf, -np.inf
    for i in range(q.shape[1]):
        x = q[b, i, k]
        if not np.isfinite(x):
            return 0.0, 0
        lo = min(lo, x)
        hi = max(hi, x)
    span = (hi - lo) * inv_h
    if not span < _MAX_CELLS:
        return 0.0, 0
    return lo, int(span) + 1


@jit_kernel
def _swarm_dims(q, b, g):
    """Origin, buckets per axis and folding of swarm b; False if no grid can hold it."""
    for k in range(3):
        g.origin[b, k] = 0.0
        g.wrap[b, k] = False
        g.dims[b, k] = 1
        if k < q.shape[2]:
            g.origin[b, k], g.dims[b, k] = _axis_extent(q, b, k, g.inv_h)
            if g.dims[b, k] == 0:
                return False
    n = g.dims[b]
    # fold the longest axis until the buckets fit (float product: no integer overflow)
    while float(n[0]) * float(n[1]) * float(n[2]) > g.start.shape[1] - 1:
        k = np.argmax(n)
        n[k] = (n[k] + 1) // 2
        g.wrap[b, k] = True
    return True


@jit_inline
def _bucket(g, b, c0, c1, c2):
    n1, n2 = g.dims[b, 1], g.dims[b, 2]
    return ((c0 % g.dims[b, 0]) * n1 + c1 % n1) * n2 + c2 % n2


@jit_kernel
def _build(q, g):
    B, N, D = q.shape
    for b in range(B):
        g.ok[b] = _swarm_dims(q, b, g)
        if not g.ok[b]:
            continue
        start = g.start[b]
        start[:] = 0
        for i in range(N):
            for k in range(3):
                c = 0
                if k < D:
                    c = int(np.floor((q[b, i, k] - g.origin[b, k]) * g.inv_h))
                g.cell[b, i, k] = c
            c = g.cell[b, i]
            start[_bucket(g, b, c[0], c[1], c[2]) + 1] += 1
        for t in range(1, start.shape[0]):
            start[t] += start[t - 1]
        # stable scatter: start[c] runs from the bucket's first slot to its end ...
        for i in range(N):
            c = g.cell[b, i]
            t = _bucket(g, b, c[0], c[1], c[2])
            g.order[b, start[t]] = i
            start[t] += 1
        # ... and is shifted back to the bucket's first slot
        for t in range(start.shape[0] - 1, 0, -1):
            start[t] = start[t - 1]
        start[0] = 0


# ---------------------------------------------------------------------------------------
# block queries: the buckets within L cells of a cell, each once
# ---------------------------------------------------------------------------------------
@jit_inline
def _axis_range(c, n, wrap, L):
    """Cell coordinates lo..hi to visit along one axis, and whether that is the whole axis."""
    if wrap:
        if n <= 2 * L + 1:
            return 0, n - 1, True
        return c - L, c + L, False
    lo = max(c - L, 0)
    hi = min(c + L, n - 1)
    return lo, hi, c - L <= 0 and c + L >= n - 1


@jit_inline
def block_buckets(g, b, c, L, out):
    """Buckets of the cells within L (Chebyshev, in cells) of cell ``c``, into ``out``.

    Returns (count, covered): covered means every bucket of the swarm was listed, so the
    query examined every UAV. Otherwise every UAV not listed is farther than
    ``(L - _ROUNDING) * h`` from any point of cell ``c``.
    """
    lo0, hi0, a0 = _axis_range(c[0], g.dims[b, 0], g.wrap[b, 0], L)
    lo1, hi1, a1 = _axis_range(c[1], g.dims[b, 1], g.wrap[b, 1], L)
    lo2, hi2, a2 = _axis_range(c[2], g.dims[b, 2], g.wrap[b, 2], L)
    m = 0
    for x in range(lo0, hi0 + 1):
        for y in range(lo1, hi1 + 1):
            for z in range(lo2, hi2 + 1):
                out[m] = _bucket(g, b, x, y, z)
                m += 1
    return m, a0 and a1 and a2


@jit_inline
def point_cell(g, b, point, c):
    """Cell coordinates of an arbitrary point into ``c``; False if too far for the grid."""
    for k in range(3):
        c[k] = 0
        if k < point.shape[0]:
            v = (point[k] - g.origin[b, k]) * g.inv_h
            if not abs(v) < _MAX_CELLS:
                return False
            c[k] = int(np.floor(v))
    return True


@jit_inline
def ring_bound2(g, L):
    """Squared distance below which a search of L rings has seen every UAV."""
    r = (L - _ROUNDING) * g.h
    return r * r


@jit_kernel
def nearest_d2(q, b, i, skip, g, L):
    """Exact squared distance from UAV i to the nearest UAV other than i and ``skip``
    (inf if none): blocks of L, 2L, 4L, ... cells until the nearest one is proven."""
    c = g.cell[b, i]
    while True:
        best = np.inf
        nb, covered = block_buckets(g, b, c, L, g.buckets)
        for t in range(nb):
            bk = g.buckets[t]
            for s in range(g.start[b, bk], g.start[b, bk + 1]):
                j = g.order[b, s]
                if j != i and j != skip:
                    best = min(best, dist2(q, b, i, j))
        if covered or best < ring_bound2(g, L):
            return best
        L *= 2


@jit_kernel
def k_nearest_grid(q, b, i, skip, g, best_d2, best_j, K):
    """:func:`k_nearest_all_pairs` on the grid: the same list, found by expanding blocks."""
    c = g.cell[b, i]
    L = 1
    while True:
        reset_nearest(best_d2, best_j)
        nb, covered = block_buckets(g, b, c, L, g.buckets)
        for t in range(nb):
            bk = g.buckets[t]
            for s in range(g.start[b, bk], g.start[b, bk + 1]):
                j = g.order[b, s]
                if j != i and j != skip:
                    insert_nearest(best_d2, best_j, K, dist2(q, b, i, j), j)
        if covered or K == 0 or (best_j[K - 1] >= 0 and best_d2[K - 1] < ring_bound2(g, L)):
            return
        L *= 2


@jit_inline
def sort_ints(a, n):
    """Insertion sort of a[:n] (short lists)."""
    for t in range(1, n):
        x = a[t]
        s = t
        while s > 0 and a[s - 1] > x:
            a[s] = a[s - 1]
            s -= 1
        a[s] = x


@jit_inline
def _point_d2(q, b, j, point):
    d2 = 0.0
    for k in range(q.shape[2]):
        x = q[b, j, k] - point[k]
        d2 += x * x
    return d2


@jit_kernel
def within_radius(q, b, point, r2, exclude, g, c, out):
    """Indices of the UAVs of swarm b with squared distance to ``point`` below ``r2``
    (``exclude`` left out), in increasing order, into ``out``; returns their number.
    Swarms the grid does not hold, and points far outside it, are scanned in full."""
    n = 0
    if g.ok[b] and point_cell(g, b, point, c):
        L = int(np.ceil(np.sqrt(r2) * g.inv_h + _ROUNDING))
        nb, _ = block_buckets(g, b, c, max(L, 1), g.buckets)
        for t in range(nb):
            bk = g.buckets[t]
            for s in range(g.start[b, bk], g.start[b, bk + 1]):
                j = g.order[b, s]
                if j != exclude and _point_d2(q, b, j, point) < r2:
                    out[n] = j
                    n += 1
        sort_ints(out, n)
        return n
    for j in range(q.shape[1]):
        if j != exclude and _point_d2(q, b, j, point) < r2:
            out[n] = j
            n += 1
    return n


# ---------------------------------------------------------------------------------------
# the Python face
# ---------------------------------------------------------------------------------------
class NeighborGrid:
    """Uniform cell lists of B swarms of N UAVs, rebuilt from the positions each step.

    Args:
        num_envs: number of swarms B.
        n_uavs: UAVs per swarm N.
        dim: 2 or 3.
        cell_size: smallest cell edge (m): the largest distance that the one-ring queries
            (flocking, collisions, shared neighbours) must see, e.g. ``max(radius,
            collision_distance)``. Longer queries (nearest UAV, K nearest, any radius) expand.
        max_cells: buckets per swarm (memory bound); default ``4 N + 64``.

    Call :meth:`build` with the current positions before querying; a grid describes the
    positions it was last built from.

    >>> import numpy as np
    >>> q = np.array([[[0.0, 0.0], [1.0, 0.0], [5.0, 0.0]]])
    >>> grid = NeighborGrid(1, 3, 2, cell_size=2.0).build(q)
    >>> grid.within(0, [0.0, 0.0], 2.0).tolist()
    [0, 1]
    """

    def __init__(
        self, num_envs: int, n_uavs: int, dim: int, cell_size: float, max_cells: int | None = None
    ) -> None:
        for name, v, lo in (("num_envs", num_envs, 1), ("n_uavs", n_uavs, 1), ("dim", dim, 2)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
                raise ValueError(f"{name}={v!r} is invalid: must be an integer >= {lo}")
        if dim > 3:
            raise ValueError(f"dim={dim!r} is invalid: must be 2 or 3")
        if not (isinstance(cell_size, (int, float, np.floating)) and 0 < cell_size < np.inf):
            raise ValueError(f"cell_size={cell_size!r} is invalid: must be a finite number > 0")
        if max_cells is None:
            max_cells = 4 * n_uavs + 64
        if isinstance(max_cells, bool) or not isinstance(max_cells, (int, np.integer)):
            raise ValueError(f"max_cells={max_cells!r} is invalid: must be an integer >= 1")
        if max_cells < 1:
            raise ValueError(f"max_cells={max_cells!r} is invalid: must be an integer >= 1")
        B, N = int(num_envs), int(n_uavs)
        self.shape = (B, N, int(dim))
        self.cell_size = float(cell_size)
        h = self.cell_size * (1.0 + _CELL_MARGIN)
        self.arrays = GridArrays(
            h,
            1.0 / h,
            np.zeros((B, 3)),
            np.ones((B, 3), np.int64),
            np.zeros((B, 3), np.bool_),
            np.zeros(B, np.bool_),
            np.zeros((B, N, 3), np.int64),
            np.zeros((B, int(max_cells) + 1), np.int64),
            np.zeros((B, N), np.int64),
            np.zeros(int(max_cells), np.int64),
        )
        self._cell = np.empty(3, np.int64)
        self._hits = np.empty(N, np.int64)
        self._q: np.ndarray | None = None

    def build(self, q: np.ndarray) -> NeighborGrid:
        """Sort the UAVs of ``q`` (B, N, dim) float64 into cells (O(N + C) per swarm)."""
        if not isinstance(q, np.ndarray) or q.dtype != np.float64 or q.shape != self.shape:
            raise ValueError(
                f"q must be a float64 array of shape {self.shape}, got "
                f"{getattr(q, 'dtype', type(q).__name__)} {getattr(q, 'shape', '')}"
            )
        _build(q, self.arrays)
        self._q = q
        return self

    @property
    def ok(self) -> np.ndarray:
        """(B,) bool: swarms the grid holds (the others are searched by all pairs)."""
        return self.arrays.ok

    def within(self, b: int, point, radius: float, exclude: int = -1) -> np.ndarray:
        """Indices (increasing) of swarm b's UAVs closer than ``radius`` to ``point``
        (``exclude``: a UAV index to leave out, e.g. the querying UAV itself)."""
        if self._q is None:
            raise RuntimeError("call build(q) before querying the grid")
        if not 0 <= b < self.shape[0]:
            raise ValueError(f"b={b!r} is invalid: must be in [0, {self.shape[0] - 1}]")
        pt = np.asarray(point, dtype=np.float64).reshape(-1)
        if pt.shape != (self.shape[2],):
            raise ValueError(f"point has shape {pt.shape}, expected ({self.shape[2]},)")
        if not (np.isfinite(radius) and radius >= 0):
            raise ValueError(f"radius={radius!r} is invalid: must be a finite number >= 0")
        r2 = float(radius) ** 2
        n = within_radius(self._q, b, pt, r2, int(exclude), self.arrays, self._cell, self._hits)
        return self._hits[:n].copy()


def nearest_indices(q: np.ndarray, point: np.ndarray, k: int) -> np.ndarray:
    """The k UAVs nearest to ``point`` in O(N): ``argsort(norm(q - point), stable)[:k]``.

    Args:
        q: positions (N, dim); point: (dim,); k: 0 <= k <= N.

    Returns the same indices in the same order as the stable sort of the Euclidean norms
    (ties to the lower index), without sorting all N.
    """
    d = np.linalg.norm(q - point, axis=1)
    if k <= 0:
        return np.zeros(0, np.int64)
    kth = np.partition(d, k - 1)[k - 1] if k < d.shape[0] else np.nan
    if np.isnan(kth):  # all of them, or NaN distances: sort everything (NaN last, as argsort)
        return np.argsort(d, kind="stable")[:k]
    idx = np.flatnonzero(d <= kth)  # increasing, so the stable sort keeps ties in index order
    return idx[np.argsort(d[idx], kind="stable")[:k]]
