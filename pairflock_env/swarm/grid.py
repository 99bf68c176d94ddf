"""Neighbour search: the distance and K-nearest primitives, and a uniform grid (cell list).

Every consumer of neighbours (the flocking pass, separations, collisions, connectivity, the
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
lets the flocking pass reproduce the all-pairs summation order bit for bit.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from pairflock_env.kernels import jit_inline, jit_kernel, low_bit

__all__ = ["GridArrays", "NeighborGrid", "nearest_indices"]

#: cells are this much (relative) larger than requested, so that rounding of cell coordinates
#: (at most ``_ROUNDING`` cells) never separates two UAVs closer than the requested size by
#: more than one cell
_CELL_MARGIN = 1e-3
#: bound on the rounding error of a computed cell coordinate, in cells, valid while the
#: coordinate stays below ``_MAX_CELLS`` (3 roundings of 2^-53 relative error each)
_ROUNDING = 1e-4
_MAX_CELLS = 2.0**36


GridArrays = namedtuple(
    "GridArrays",
    [
        "h",
        "inv_h",
        "origin",
        "dims",
        "wrap",
        "pad",
        "stride",
        "ring",
        "n_ring",
        "ok",
        "bucket",
        "start",
        "order",
        "buckets",
        "mark",
    ],
)
GridArrays.__doc__ = """The arrays of a :class:`NeighborGrid`, as numba kernels take them.

Per swarm b: ``origin`` (B, 3) lowest corner; ``dims`` (B, 3) cells per axis (1 on unused
axes); ``wrap`` (B, 3) axis folded; ``pad`` (B, 3) 1 where a border of empty cells surrounds
the axis; ``stride`` (B, 3) bucket = sum_k (cell_k + pad_k) stride_k; ``ring`` (B, 27) and
``n_ring`` (B,) bucket offsets of the one-ring (0 offsets when folded); ``ok`` (B,) grid
usable; ``bucket`` (B, N) each UAV's bucket; ``start`` (B, C + 1) and ``order`` (B, N):
bucket t holds UAVs ``order[b, start[b, t]:start[b, t + 1]]``. ``h`` / ``inv_h``: cell edge
(m) and its inverse; ``buckets`` (C,): scratch for the bucket list of one query; ``mark``
(ceil(N / 64),) uint64: a zeroed bitmap over the UAV indices, scratch of one query.
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
    """Insert candidate j into the sorted K-nearest list (K >= 1).

    The list holds the K smallest (d2, index) pairs in lexicographic order: ties in distance
    go to the lower index, whatever order candidates arrive in.
    """
    last = K - 1
    # one comparison rejects almost every candidate
    if d2 <= best_d2[last] and (d2 < best_d2[last] or j < best_j[last]):
        s = last
        while s > 0 and (best_d2[s - 1] > d2 or (best_d2[s - 1] == d2 and best_j[s - 1] > j)):
            best_d2[s] = best_d2[s - 1]
            best_j[s] = best_j[s - 1]
            s -= 1
        best_d2[s] = d2
        best_j[s] = j


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
def _swarm_layout(q, b, g):
    """Origin, cells per axis, folding, padding, strides and one-ring offsets of swarm b;
    False if no grid can hold it."""
    D = q.shape[2]
    n = g.dims[b]
    for k in range(3):
        g.origin[b, k], n[k], g.wrap[b, k], g.pad[b, k] = 0.0, 1, False, 0
        if k < D:
            g.origin[b, k], n[k] = _axis_extent(q, b, k, g.inv_h)
            if n[k] == 0:
                return False
    n_buckets = g.start.shape[1] - 1
    # float products: no integer overflow whatever the extent
    if float(n[0] + 2) * float(n[1] + 2) * float(n[2] + 2 * (D == 3)) <= n_buckets:
        for k in range(D):  # a border of empty cells: the one-ring never leaves the grid
            g.pad[b, k] = 1
    else:  # fold the longest axis until the cells fit
        while float(n[0]) * float(n[1]) * float(n[2]) > n_buckets:
            k = np.argmax(n)
            n[k] = (n[k] + 1) // 2
            g.wrap[b, k] = True
    g.stride[b, 2] = 1
    g.stride[b, 1] = n[2] + 2 * g.pad[b, 2]
    g.stride[b, 0] = g.stride[b, 1] * (n[1] + 2 * g.pad[b, 1])
    m = 0
    if g.pad[b, 0]:
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                for dz in range(-(D == 3), (D == 3) + 1):
                    g.ring[b, m] = dx * g.stride[b, 0] + dy * g.stride[b, 1] + dz
                    m += 1
    g.n_ring[b] = m
    return True


@jit_inline
def _wrap(x, n):
    """x modulo n, without the division when x is already in range."""
    if 0 <= x < n:
        return x
    return x % n


@jit_inline
def _bucket(g, b, c0, c1, c2):
    """Bucket of the cell (c0, c1, c2) (coordinates folded onto the grid when needed)."""
    return (
        (_wrap(c0, g.dims[b, 0]) + g.pad[b, 0]) * g.stride[b, 0]
        + (_wrap(c1, g.dims[b, 1]) + g.pad[b, 1]) * g.stride[b, 1]
        + _wrap(c2, g.dims[b, 2])
        + g.pad[b, 2]
    )


@jit_inline
def uav_cell(q, b, i, g):
    """Cell coordinates of UAV i of swarm b (0 on unused axes)."""
    c0 = int(np.floor((q[b, i, 0] - g.origin[b, 0]) * g.inv_h))
    c1 = int(np.floor((q[b, i, 1] - g.origin[b, 1]) * g.inv_h))
    c2 = 0
    if q.shape[2] == 3:
        c2 = int(np.floor((q[b, i, 2] - g.origin[b, 2]) * g.inv_h))
    return c0, c1, c2


@jit_kernel
def _build(q, g):
    B, N = q.shape[0], q.shape[1]
    for b in range(B):
        g.ok[b] = _swarm_layout(q, b, g)
        if not g.ok[b]:
            continue
        start = g.start[b]
        start[:] = 0
        for i in range(N):
            c0, c1, c2 = uav_cell(q, b, i, g)
            t = _bucket(g, b, c0, c1, c2)
            g.bucket[b, i] = t
            start[t + 1] += 1
        for t in range(1, start.shape[0]):
            start[t] += start[t - 1]
        # stable scatter: start[t] runs from the bucket's first slot to its end ...
        for i in range(N):
            t = g.bucket[b, i]
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
def block_count(g, b, c0, c1, c2, L):
    """The number of buckets :func:`block_buckets` lists for the same block."""
    m = 1
    for k, c in ((0, c0), (1, c1), (2, c2)):
        lo, hi, _ = _axis_range(c, g.dims[b, k], g.wrap[b, k], L)
        m *= max(hi - lo + 1, 0)
    return m


@jit_inline
def block_buckets(g, b, c0, c1, c2, L, out):
    """Buckets of the cells within L (Chebyshev, in cells) of cell (c0, c1, c2), into
    ``out``.

    Returns (count, covered): covered means every bucket of the swarm was listed, so the
    query examined every UAV. Otherwise every UAV not listed is farther than
    ``(L - _ROUNDING) * h`` from any point of that cell.
    """
    n0, n1, n2 = g.dims[b, 0], g.dims[b, 1], g.dims[b, 2]
    lo0, hi0, a0 = _axis_range(c0, n0, g.wrap[b, 0], L)
    lo1, hi1, a1 = _axis_range(c1, n1, g.wrap[b, 1], L)
    lo2, hi2, a2 = _axis_range(c2, n2, g.wrap[b, 2], L)
    # walk the cell coordinates with wrap-around instead of a modulo per bucket
    m = 0
    x = _wrap(lo0, n0)
    for _ in range(hi0 - lo0 + 1):
        y = _wrap(lo1, n1)
        for _ in range(hi1 - lo1 + 1):
            z = _wrap(lo2, n2)
            base = (x + g.pad[b, 0]) * g.stride[b, 0] + (y + g.pad[b, 1]) * g.stride[b, 1]
            for _ in range(hi2 - lo2 + 1):
                out[m] = base + z + g.pad[b, 2]
                m += 1
                z = z + 1 if z + 1 < n2 else 0
            y = y + 1 if y + 1 < n1 else 0
        x = x + 1 if x + 1 < n0 else 0
    return m, a0 and a1 and a2


@jit_inline
def one_ring(q, b, i, g, out):
    """Buckets of UAV i's cell and its neighbour cells into ``out``; returns their number.
    Every UAV closer than the grid's ``cell_size`` to UAV i is in one of them."""
    if g.n_ring[b] > 0:  # padded grid: fixed offsets from the UAV's bucket
        t0 = g.bucket[b, i]
        for t in range(g.n_ring[b]):
            out[t] = t0 + g.ring[b, t]
        return g.n_ring[b]
    c0, c1, c2 = uav_cell(q, b, i, g)
    return block_buckets(g, b, c0, c1, c2, 1, out)[0]


@jit_inline
def _coord(x, lo, inv_h):
    """Cell coordinate of x along an axis starting at lo; 2^62 when out of the grid's reach."""
    v = (x - lo) * inv_h
    return int(np.floor(v)) if abs(v) < _MAX_CELLS else 2**62


@jit_inline
def point_cell(g, b, point):
    """Cell coordinates of an arbitrary point, and False if it is too far for the grid."""
    c0 = _coord(point[0], g.origin[b, 0], g.inv_h)
    c1 = _coord(point[1], g.origin[b, 1], g.inv_h)
    c2 = _coord(point[2], g.origin[b, 2], g.inv_h) if point.shape[0] == 3 else 0
    return c0, c1, c2, max(abs(c0), abs(c1), abs(c2)) < 2**62


@jit_inline
def ring_bound2(g, L):
    """Squared distance below which a search of L rings has seen every UAV."""
    r = (L - _ROUNDING) * g.h
    return r * r


@jit_inline
def _border_margin(q, b, i, g):
    """Distance in cells from UAV i to the nearest face of its cell, less the rounding: a
    search of L rings around UAV i has seen every UAV closer than (L + margin) h."""
    m = 1.0
    for k in range(q.shape[2]):
        v = (q[b, i, k] - g.origin[b, k]) * g.inv_h
        f = v - np.floor(v)
        m = min(m, f, 1.0 - f)
    return m - _ROUNDING


@jit_kernel
def nearest_d2(q, b, i, skip, g, best, L):
    """Exact squared distance from UAV i to the nearest UAV other than i and ``skip`` (inf if
    none). ``best``: the nearest over the block of L rings around UAV i (inf and 0 when
    nothing was searched yet); blocks of 2L, 4L, ... rings follow until it is proven."""
    c0, c1, c2 = uav_cell(q, b, i, g)
    margin = _border_margin(q, b, i, g)
    covered = False
    while not (covered or best < ((L + margin) * g.h) ** 2):
        L = max(2 * L, 1)
        best = np.inf
        nb, covered = block_buckets(g, b, c0, c1, c2, L, g.buckets)
        for t in range(nb):
            bk = g.buckets[t]
            for s in range(g.start[b, bk], g.start[b, bk + 1]):
                j = g.order[b, s]
                if j != i and j != skip:
                    best = min(best, dist2(q, b, i, j))
    return best


@jit_kernel
def k_nearest_grid(q, b, i, skip, g, best_d2, best_j, K):
    """The K nearest UAVs of UAV i other than i and ``skip`` on the grid, found by expanding
    blocks: the list of :func:`~pairflock_env.swarm.pair_pass._nearest_in_row` (the same K
    smallest (squared distance, index) pairs, the rest (inf, -1))."""
    c0, c1, c2 = uav_cell(q, b, i, g)
    margin = _border_margin(q, b, i, g)
    L = 1
    while True:
        reset_nearest(best_d2, best_j)
        nb, covered = block_buckets(g, b, c0, c1, c2, L, g.buckets)
        for t in range(nb):
            bk = g.buckets[t]
            for s in range(g.start[b, bk], g.start[b, bk + 1]):
                j = g.order[b, s]
                if j != i and j != skip and K > 0:
                    insert_nearest(best_d2, best_j, K, dist2(q, b, i, j), j)
        if covered or K == 0:
            return
        if best_j[K - 1] >= 0 and best_d2[K - 1] < ((L + margin) * g.h) ** 2:
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


#: lists longer than this are put in order through the bitmap, shorter ones by insertion
_SORT_BITMAP = 24


@jit_inline
def bitmap_sort(a, n, mark, lo, hi):
    """Put the indices a[:n] in increasing order through the bitmap ``mark`` (zeroed, one
    bit per index, left zeroed), whose words lo..hi hold them all; returns the number of
    distinct indices (a repeated one is kept once). The cost is n plus hi - lo words."""
    one = np.uint64(1)
    for t in range(n):
        mark[a[t] >> 6] |= one << np.uint64(a[t] & 63)
    m = 0
    for k in range(lo, hi + 1):
        w = mark[k]
        if w == 0:
            continue
        mark[k] = 0
        while w != 0:
            a[m] = 64 * k + low_bit(w)
            w &= w - one
            m += 1
    return m


@jit_inline
def word_span(a, n):
    """The first and last 64-bit words of a bitmap that hold the indices a[:n] (n >= 1)."""
    lo = hi = a[0]
    for t in range(n):
        lo = min(lo, a[t])
        hi = max(hi, a[t])
    return lo >> 6, hi >> 6


@jit_inline
def order_indices(a, n, mark):
    """Put the indices a[:n] in increasing order and return how many are distinct: an
    insertion sort for short lists (distinct indices), else :func:`bitmap_sort`, whose cost
    is n plus the words between the smallest and largest index, not n^2 or n log n."""
    if n <= _SORT_BITMAP:
        sort_ints(a, n)
        return n
    lo, hi = word_span(a, n)
    return bitmap_sort(a, n, mark, lo, hi)


@jit_inline
def _point_d2(q, b, j, point):
    d2 = 0.0
    for k in range(q.shape[2]):
        x = q[b, j, k] - point[k]
        d2 += x * x
    return d2


@jit_kernel
def within_radius(q, b, point, r2, exclude, g, out):
    """Indices of the UAVs of swarm b with squared distance to ``point`` below ``r2``
    (``exclude`` left out), in increasing order, into ``out``; returns their number.

    The grid's block of cells around the point is searched, except for swarms the grid
    does not hold, points far outside it, and blocks with more cells than the swarm has UAVs
    (where visiting the cells costs more than checking every UAV): those are scanned in
    full. The result is the same either way."""
    n = 0
    N = q.shape[1]
    c0, c1, c2, near = point_cell(g, b, point)
    L = np.sqrt(r2) * g.inv_h + _ROUNDING
    Li = max(int(np.ceil(L)), 1) if L < _MAX_CELLS else 0
    if g.ok[b] and near and Li > 0 and block_count(g, b, c0, c1, c2, Li) < N:
        nb, _ = block_buckets(g, b, c0, c1, c2, Li, g.buckets)
        for t in range(nb):
            bk = g.buckets[t]
            for s in range(g.start[b, bk], g.start[b, bk + 1]):
                j = g.order[b, s]
                if j != exclude and _point_d2(q, b, j, point) < r2:
                    out[n] = j
                    n += 1
        return order_indices(out, n, g.mark)
    for j in range(N):
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
        num_swarms: number of swarms B.
        n_uavs: UAVs per swarm N.
        dim: 2 or 3.
        cell_size: smallest cell edge (m): the largest distance that the one-ring queries
            (flocking, collisions, shared neighbours) must see, e.g. ``max(radius,
            collision_distance)``. Longer queries (nearest UAV, K nearest, any radius) expand.
        max_cells: buckets per swarm (memory bound); default ``4 N + 64``.

    Call :meth:`build` with the current positions before querying, and again whenever they
    change: a grid describes the positions it was last built from (it keeps a reference to
    that array, not a copy). One thread at a time per grid (queries share scratch space).

    The passes (:func:`~pairflock_env.swarm.flocking.flocking_pass`,
    :func:`~pairflock_env.swarm.pair_pass.pair_pass`) take a grid as ``grid=``; other code
    asks :meth:`within` / :meth:`neighbors_of`, or, inside numba, calls
    ``within_radius(q, b, point, r2, exclude, GridArrays(*grid.arrays), out)``.

    >>> import numpy as np
    >>> q = np.array([[[0.0, 0.0], [1.0, 0.0], [5.0, 0.0]]])
    >>> grid = NeighborGrid(1, 3, 2, cell_size=2.0).build(q)
    >>> grid.within(0, [0.0, 0.0], 2.0).tolist()
    [0, 1]
    """

    def __init__(
        self, num_swarms: int, n_uavs: int, dim: int, cell_size: float, max_cells: int | None = None
    ) -> None:
        for name, v, lo in (("num_swarms", num_swarms, 1), ("n_uavs", n_uavs, 1), ("dim", dim, 2)):
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
        B, N = int(num_swarms), int(n_uavs)
        self.shape = (B, N, int(dim))
        self.cell_size = float(cell_size)
        h = self.cell_size * (1.0 + _CELL_MARGIN)
        C = int(max_cells)
        self.arrays = GridArrays(
            h=h,
            inv_h=1.0 / h,
            origin=np.zeros((B, 3)),
            dims=np.ones((B, 3), np.int64),
            wrap=np.zeros((B, 3), np.bool_),
            pad=np.zeros((B, 3), np.int64),
            stride=np.zeros((B, 3), np.int64),
            ring=np.zeros((B, 27), np.int64),
            n_ring=np.zeros(B, np.int64),
            ok=np.zeros(B, np.bool_),
            bucket=np.zeros((B, N), np.int64),
            start=np.zeros((B, C + 1), np.int64),
            order=np.zeros((B, N), np.int64),
            buckets=np.zeros(max(C, 27), np.int64),
            mark=np.zeros((N + 63) // 64, np.uint64),
        )
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
    def positions(self) -> np.ndarray | None:
        """The positions (B, N, dim) the grid was last built from (the array itself, not a
        copy; None before the first :meth:`build`)."""
        return self._q

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
        n = within_radius(self._q, b, pt, r2, int(exclude), self.arrays, self._hits)
        return self._hits[:n].copy()

    def neighbors_of(self, b: int, i: int, radius: float) -> np.ndarray:
        """Indices (increasing) of the UAVs of swarm b closer than ``radius`` to UAV i."""
        if self._q is None:
            raise RuntimeError("call build(q) before querying the grid")
        if not 0 <= i < self.shape[1]:
            raise ValueError(f"i={i!r} is invalid: must be in [0, {self.shape[1] - 1}]")
        return self.within(b, self._q[b, i], radius, exclude=i)


def check_grid(grid, shape: tuple[int, ...], need2: float, what: str) -> None:
    """Validate the ``grid`` argument of a pass over arrays of ``shape`` whose one-ring must
    reach sqrt(need2) (named ``what``); ``None`` (all pairs) always passes."""
    if grid is None:
        return
    if not isinstance(grid, NeighborGrid):
        raise TypeError(f"grid must be a NeighborGrid or None, got {type(grid).__name__}")
    if grid.shape != shape:
        raise ValueError(f"grid is for arrays of shape {grid.shape}, got {shape}")
    if grid.cell_size**2 < need2:
        raise ValueError(
            f"grid cell_size={grid.cell_size} is too small: it must be at least {what} "
            f"({np.sqrt(need2):g})"
        )


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
