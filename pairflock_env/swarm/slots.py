"""The flocking sweep's working memory: UAVs in slot order, candidate lists, the union-find
forest of the interaction graph, and the sort that puts a candidate list in index order.

Slots are the order in which a sweep visits the UAVs: index order for all pairs, cell order on
a grid (:class:`~pairflock_env.swarm.grid.NeighborGrid`), so that on a grid the positions,
velocities and the forest a sweep touches lie in memory as the UAVs lie in space.
"""

from __future__ import annotations

from pairflock_env.kernels import jit_inline
from pairflock_env.swarm.grid import sort_ints

__all__ = ["copy_slots", "find", "gather", "join", "largest_component", "row_d2", "sort_indices"]

# Rows of the float scratch of a pass (each of length N rounded up to whole 64-bit words):
# positions and velocities of every UAV in slot order, then of the current candidate list,
# then the squared distances from one UAV to its candidates (and their bits, as uint64).
QS, PS, CQ, CP, ROW = 0, 3, 6, 9, 12
# Rows of the int scratch: the UAV in each slot and the slot of each UAV; the candidates'
# indices, their slots and where each slot sits in the list; the union-find forest over
# slots (parent, size); one UAV's neighbours (positions in the candidate list).
ORDER, SLOT_OF, CIDX, CSLOT, POS_OF, PARENT, SIZE, NB, TMP, HIST = range(10)


@jit_inline
def sort_indices(a, n, tmp, hist, n_max):
    """Sort the distinct indices a[:n] (each < n_max) in place: insertion for short lists,
    else a radix sort by bytes (lowest first), whose cost does not depend on the order
    the indices come in (a bitmap's or an insertion sort's does)."""
    if n <= 16:
        sort_ints(a, n)
        return
    shift = 0
    src, dst = a, tmp
    while shift == 0 or (n_max - 1) >> shift > 0:
        for d in range(256):
            hist[d] = 0
        for c in range(n):
            hist[(src[c] >> shift) & 255] += 1
        total = 0
        for d in range(256):
            total, hist[d] = total + hist[d], total
        for c in range(n):
            d = (src[c] >> shift) & 255
            dst[hist[d]] = src[c]
            hist[d] += 1
        src, dst = dst, src
        shift += 8
    if src is not a:
        for c in range(n):
            a[c] = src[c]


@jit_inline
def copy_slots(q, p, b, order, fw, iw, three):
    """Positions and velocities of swarm b in slot order (slot s holds UAV ``order[s]``),
    and the slot of every UAV."""
    for s in range(q.shape[1]):
        i = order[s]
        iw[SLOT_OF, i] = s
        for k in range(3 if three else 2):
            fw[QS + k, s] = q[b, i, k]
            fw[PS + k, s] = p[b, i, k]


@jit_inline
def gather(n, fw, iw, three):
    """The candidate list's positions and velocities (from their slots), and where each
    candidate's slot sits in the list."""
    for c in range(n):
        s = iw[CSLOT, c]
        iw[POS_OF, s] = c
        for k in range(3 if three else 2):
            fw[CQ + k, c] = fw[QS + k, s]
            fw[CP + k, c] = fw[PS + k, s]


@jit_inline
def row_d2(fw, n, x0, x1, x2, three):
    """Squared distances from (x0, x1, x2) to the first n candidates, summed over axes in
    order as :func:`~pairflock_env.swarm.grid.dist2` (the same numbers; this vectorises)."""
    for c in range(n):
        a = fw[CQ, c] - x0
        e = fw[CQ + 1, c] - x1
        d2 = a * a + e * e
        if three:
            z = fw[CQ + 2, c] - x2
            d2 += z * z
        fw[ROW, c] = d2


@jit_inline
def find(parent, x):
    """Root of x in the union-find forest, halving the path on the way."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@jit_inline
def join(parent, size, x, j):
    """Join the component of root x and that of UAV j, the smaller under the larger
    (shallow trees); returns the root of the joined component."""
    y = find(parent, j)
    if x == y:
        return x
    if size[x] > size[y]:
        x, y = y, x
    parent[x] = y
    size[y] += size[x]
    return y


@jit_inline
def largest_component(parent, size):
    best = 0
    for i in range(parent.shape[0]):
        if parent[i] == i and size[i] > best:
            best = size[i]
    return best
