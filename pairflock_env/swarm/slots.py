"""The flocking sweep's working memory: UAVs in slot order, candidate lists, the union-find
forest of the interaction graph, and the sort that puts a candidate list in index order.

Slots are the order in which a sweep visits the UAVs: index order for all pairs, cell order on
a grid (:class:`~pairflock_env.swarm.grid.NeighborGrid`), so that on a grid the positions,
velocities and the forest a sweep touches lie in memory as the UAVs lie in space.
"""

from __future__ import annotations

from pairflock_env.kernels import jit_inline
from pairflock_env.swarm.grid import bitmap_sort, word_span

__all__ = [
    "copy_slots",
    "find",
    "gather",
    "join",
    "largest_component",
    "put_slots",
    "row_d2",
    "sort_indices",
]

# Rows of the float scratch of a pass (each of length N rounded up to whole 64-bit words):
# positions and velocities of every UAV in slot order, then of the current candidate list,
# then the squared distances from one UAV to its candidates (and their bits, as uint64),
# then each UAV's flocking command and separation in slot order, then the exponentials of
# one UAV's neighbours.
QS, PS, CQ, CP, ROW, ACC, MD, EXP = 0, 3, 6, 9, 12, 13, 16, 17
# Rows of the int scratch: the UAV in each slot (all pairs); the candidates' indices, their
# slots and where each slot sits in the list; the union-find forest over
# slots (parent, size); one UAV's neighbours (positions in the candidate list); scratch of
# the sort; each UAV's partner in slot order; each UAV's slot (by index); a histogram of
# 256 (the last row).
ORDER, CIDX, CSLOT, POS_OF, PARENT, SIZE, NB, TMP, PRT, SLOT_OF, HIST = range(11)


#: lists up to this long are sorted by rank (n^2 vectorised comparisons)
_RANK_SORT = 40


@jit_inline
def sort_indices(a, n, tmp, hist, mark, n_max):
    """Sort the distinct indices a[:n] (each < n_max) in place, at a cost that does not grow
    with disorder (an insertion sort's does, and a flight scrambles the order): short lists
    by rank (each index goes where the count of smaller ones puts it; the counts
    vectorise); longer ones through the bitmap ``mark`` (zeroed, one bit per index; left
    zeroed: :func:`~pairflock_env.swarm.grid.bitmap_sort`) when the words their indices
    span are fewer than the radix sort's steps, else by a radix sort in as few passes of
    as narrow digits as ``n_max`` allows (two passes of 7 bits below 16,384)."""
    if n <= _RANK_SORT:
        for i in range(n):
            x, r = a[i], 0
            for j in range(n):
                r += a[j] < x
            tmp[r] = x
        for i in range(n):
            a[i] = tmp[i]
        return
    lo, hi = word_span(a, n)
    bits = 1
    while (n_max - 1) >> bits > 0:
        bits += 1
    passes = (bits + 7) >> 3
    digit = (bits + passes - 1) // passes
    if hi - lo < passes * (2 << digit):  # n + (hi - lo) steps against the passes'
        bitmap_sort(a, n, mark, lo, hi)
        return
    size = 1 << digit
    src, dst = a, tmp
    for shift in range(0, digit * passes, digit):
        for d in range(size):
            hist[d] = 0
        for c in range(n):
            hist[(src[c] >> shift) & (size - 1)] += 1
        total = 0
        for d in range(size):
            total, hist[d] = total + hist[d], total
        for c in range(n):
            d = (src[c] >> shift) & (size - 1)
            dst[hist[d]] = src[c]
            hist[d] += 1
        src, dst = dst, src
    if src is not a:
        for c in range(n):
            a[c] = src[c]


@jit_inline
def copy_slots(q, p, b, order, partner, acc, fw, iw, three):
    """Positions, velocities, partners and pinning terms (``acc``) of swarm b in slot order
    (slot s holds UAV ``order[s]``): read here in one loop whatever the order of the
    indices, so that the sweep reads and writes only memory in slot order."""
    for s in range(q.shape[1]):
        i = order[s]
        iw[SLOT_OF, i] = s
        iw[PRT, s] = partner[i]
        for k in range(3 if three else 2):
            fw[QS + k, s] = q[b, i, k]
            fw[PS + k, s] = p[b, i, k]
            fw[ACC + k, s] = acc[b, i, k]


@jit_inline
def put_slots(b, order, acc, min_d2, fw, three):
    """The flocking commands and separations of the sweep, from slot order to the UAVs."""
    for s in range(acc.shape[1]):
        i = order[s]
        min_d2[b, i] = fw[MD, s]
        for k in range(3 if three else 2):
            acc[b, i, k] = fw[ACC + k, s]


@jit_inline
def gather(n, fw, iw, three):
    """The candidate list's slots, positions and velocities (from their indices), and where
    each candidate's slot sits in the list."""
    for c in range(n):
        s = iw[CSLOT, c] = iw[SLOT_OF, iw[CIDX, c]]
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
