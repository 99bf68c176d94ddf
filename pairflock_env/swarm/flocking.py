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
density). Swarms a grid cannot hold (non-finite coordinates) use all pairs.

How the sweep runs: each UAV *gathers* its own command (no UAV writes another's), from a
candidate list of the UAVs within its reach (all of them, or its one-ring of cells), put in
increasing index order and copied into contiguous per-axis rows. Squared distances, the
separation (a minimum taken on the bits of the distances, which order like the values) and
the collision count run as vectorised loops over that list; the neighbours are read off a
bitmask in increasing index; their forces are added after the pinning term, in that order.
That is the order in which the symmetric sweep (f_ij added to i and subtracted from j over
the pairs i < j in turn) forms each sum, and f_ji = -f_ij bit for bit, so all pairs, the grid
and the symmetric sweep agree to the last bit (tests/reference_flocking.py keeps that sweep as
the reference). On the grid, the UAVs of a cell share one candidate list and are taken in
cell order, with positions, velocities and the union-find forest in the same (slot) order:
memory follows space, so a flight whose UAV indices are scrambled in space costs what a
sorted one costs. Kernels are specialised per dimension (``dims``), so 2-D and 3-D unroll.
The per-pair pass for observations and eq. 28 (``pair_pass``) lives in
:mod:`pairflock_env.swarm.pair_pass`.

This is the only implementation of these equations; every view and vehicle model calls it.
The kernels run single-threaded under numba (compiled code is cached on disk); the small
helpers below are compiled into the kernels that call them.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.config.sections.flocking import repulsion_floor
from pairflock_env.config.sections.reward import collision_ellipsoid
from pairflock_env.exp import exp_lane, in_fast_range
from pairflock_env.kernels import (
    BoundKernel,
    KernelParams,
    bits_float,
    float_bits,
    jit_inline,
    jit_kernel,
    low_bit,
)
from pairflock_env.swarm.grid import (
    GridArrays,
    NeighborGrid,
    check_grid,
    nearest_d2,
    one_ring,
    ring_bound2,
)
from pairflock_env.swarm.slots import (
    ACC,
    CIDX,
    CP,
    CQ,
    CSLOT,
    EXP,
    HIST,
    MD,
    NB,
    ORDER,
    PARENT,
    POS_OF,
    PRT,
    PS,
    QS,
    ROW,
    SIZE,
    TMP,
    copy_slots,
    find,
    gather,
    join,
    largest_component,
    put_slots,
    row_d2,
    sort_indices,
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
        "collision_squash",
        "collision_height2",
    ),
)
FlockScalars = namedtuple("FlockScalars", FLOCKING.names)
FlockScalars.__doc__ = "The flocking parameters held in registers by the kernels."
_F = FLOCKING.index


def flocking_params(cfg: PairFlockConfig) -> np.ndarray:
    """The flocking pass's parameter vector (:data:`FLOCKING`) of a config (the repulsion
    floor: :func:`~pairflock_env.config.sections.flocking.repulsion_floor`; the collision
    ellipsoid's squash: :func:`~pairflock_env.config.sections.reward.collision_ellipsoid`,
    1 for the sphere)."""
    floor_radius2, floor_gain = repulsion_floor(cfg)
    ellipsoid = collision_ellipsoid(cfg)
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
        collision_squash=1.0 if ellipsoid is None else ellipsoid[1],
        collision_height2=(cfg.collision_height or cfg.collision_distance) ** 2,
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
        v[_F.collision_squash],
        v[_F.collision_height2],
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
def _three(dims):
    """Whether ``dims`` (see :data:`_DIMS`) is a 3-D kernel's."""
    return len(dims) % 2 == 1


@jit_inline
def _floor(dims):
    """Whether ``dims`` (see :data:`_DIMS`) is a kernel's with the repulsion floor."""
    return ((len(dims) - 2) >> 1) & 1 == 1


@jit_inline
def _ellipse(dims):
    """Whether ``dims`` (see :data:`_DIMS`) is a kernel's with the collision ellipsoid."""
    return ((len(dims) - 2) >> 2) & 1 == 1


@jit_inline
def _ellipse_hit(prm, a, e, z):
    """Whether offset (a, e, z) lies inside the collision ellipsoid: a^2 + e^2 + squash z^2
    < collision_distance^2, squash = (collision_distance / collision_height)^2."""
    return a * a + e * e + prm.collision_squash * (z * z) < prm.collision_distance2


@jit_inline
def _gauss_rows(prm, row, nb, k, gauss):
    """gauss[t] = exp(-rho^2 / sigma^2) of eq. 16 at the squared distances row[nb[t]], t <
    k: libm's exponential bit for bit, vectorised (:mod:`pairflock_env.exp`), with libm's
    own call for the arguments outside its fast range (coincident UAVs, extreme configs)."""
    for t in range(k):  # the distances first, so that the next loop reads only gauss[t]
        gauss[t] = row[nb[t]]
    slow = 0
    for t in range(k):  # (this loop vectorises)
        x = -gauss[t] * prm.inv_sigma2
        gauss[t] = exp_lane(x)
        slow += not in_fast_range(x)
    for t in range(k if slow else 0):
        x = -row[nb[t]] * prm.inv_sigma2
        if not in_fast_range(x):
            gauss[t] = np.exp(x)


@jit_inline
def _weight(prm, d2, gauss, floor):
    """The weight w = a - g_r(rho) of a pair at squared distance d2, from its exponential
    ``gauss`` (:func:`_gauss_rows`). With the swarm layer's floor (floor_radius2 > 0) the
    repulsion closer than rho* is at least F* rho* / rho (w multiplies q_j - q_i, of length
    rho)."""
    w = prm.attraction - prm.repulsion * gauss
    if floor and d2 < prm.floor_radius2 and d2 > 0.0:
        w = min(w, -prm.floor_gain / d2)
    return w


@jit_inline
def _weighted_force(prm, w, dq0, dq1, dq2, dp0, dp1, dp2):
    """Eqs. 13-18: the force f_ij = w dq + b dp of neighbour j on UAV i, from its weight w
    (:func:`_weight`), the offset dq = q_j - q_i and the relative velocity dp = p_j - p_i
    (three components; the third is zero and unused in 2-D). Odd in (dq, dp), so f_ji =
    -f_ij bit for bit."""
    c = prm.consensus
    return w * dq0 + c * dp0, w * dq1 + c * dp1, w * dq2 + c * dp2


@jit_inline
def _gather_uav(s, x, n, prm, fw, fwu, iw, three, floor, ellipse):
    """UAV x (in slot s) against the candidate list (indices in increasing order, every
    UAV within reach of x among them, x too): x's separation and flocking command, and
    its edges of the interaction graph; returns the collisions seen from x (inside the
    sphere of collision_distance, or with ``ellipse`` the collision ellipsoid).

    UAV x gathers its own command: the pinning term, then f_xj of each neighbour j in
    increasing j. That is the order in which the symmetric sweep of the equations (f_ij
    added to i and subtracted from j, pairs i < j in order) forms the sum, and f_xj = -f_jx
    bit for bit: the command is the same to the last bit, and no UAV writes another's.
    """
    row, rowu, cidx, nb = fw[ROW], fwu[ROW], iw[CIDX], iw[NB]
    sx = iw[POS_OF, s]
    x0, x1, v0, v1 = fw[CQ, sx], fw[CQ + 1, sx], fw[CP, sx], fw[CP + 1, sx]
    x2 = fw[CQ + 2, sx] if three else 0.0
    v2 = fw[CP + 2, sx] if three else 0.0
    row_d2(fw, n, x0, x1, x2, three)
    row[sx] = np.inf  # itself: no neighbour, no separation, no collision
    px = iw[PRT, s]
    inf_bits = float_bits(np.inf)
    m = inf_bits
    nc = 0
    for c in range(n):  # separation (the partner left out) and collisions: vectorised
        v = rowu[c] if cidx[c] != px else inf_bits
        m = v if v < m else m
        if not ellipse:
            nc += row[c] < prm.collision_distance2
    if ellipse:  # (3-D only) offsets by axis, itself left out
        for c in range(n):
            hit = _ellipse_hit(prm, fw[CQ, c] - x0, fw[CQ + 1, c] - x1, fw[CQ + 2, c] - x2)
            nc += hit & (c != sx)
    fw[MD, s] = bits_float(m)
    k = first = 0
    for c in range(n):  # the neighbours, in increasing index (branch-free)
        nb[k] = c
        k += row[c] < prm.radius2
    for t in range(k):  # those before x
        first += nb[t] < sx
    gauss = fw[EXP]
    _gauss_rows(prm, row, nb, k, gauss)  # the exponentials first, vectorised
    f0, f1, f2 = fw[ACC, s], fw[ACC + 1, s], fw[ACC + 2, s] if three else 0.0
    for t in range(k):
        c = nb[t]
        dq2 = fw[CQ + 2, c] - x2 if three else 0.0
        dp2 = fw[CP + 2, c] - v2 if three else 0.0
        dq0, dq1 = fw[CQ, c] - x0, fw[CQ + 1, c] - x1
        dp0, dp1 = fw[CP, c] - v0, fw[CP + 1, c] - v1
        w = _weight(prm, row[c], gauss[t], floor)
        g = _weighted_force(prm, w, dq0, dq1, dq2, dp0, dp1, dp2)
        f0, f1, f2 = f0 + g[0], f1 + g[1], f2 + g[2]
    fw[ACC, s], fw[ACC + 1, s], fw[ACC + 2, s] = f0, f1, f2
    parent, size = iw[PARENT], iw[SIZE]
    # the interaction graph (over slots), each edge once: from x to the neighbours of
    # larger index, which follow x in the candidate list
    root = find(parent, s)
    cslot = iw[CSLOT]
    for t in range(first, k):
        sj = cslot[nb[t]]
        if parent[sj] != root:  # (a child of x's root: joined already, join would say so)
            root = join(parent, size, root, sj)
    return nc


@jit_kernel
def _sweep_all_pairs(q, p, partner, prm, b, acc, min_d2, fw, fwu, iw, dims):
    """Every UAV of swarm b against every other; returns the number of collisions."""
    three, floor, ellipse = _three(dims), _floor(dims), _ellipse(dims)
    N = q.shape[1]
    for i in range(N):  # slots, and the candidate list, in index order
        iw[ORDER, i] = iw[CIDX, i] = i
    copy_slots(q, p, b, iw[ORDER], partner, acc, fw, iw, three)
    gather(N, fw, iw, three)
    nc = 0
    for x in range(N):
        nc += _gather_uav(x, x, N, prm, fw, fwu, iw, three, floor, ellipse)
    put_slots(b, iw[ORDER], acc, min_d2, fw, three)
    return nc // 2  # each pair was seen from both sides


@jit_inline
def _later_neighbors(prm, row, lo, N, nb):
    """The UAVs j in [lo, N) closer than the radius (squared distances ``row[j]``), in
    increasing order, into ``nb``; returns their number. Word by word through a bitmask
    (the comparisons vectorise): on these rows of up to N = 512 it beats the branch-free
    compaction :func:`_gather_uav` uses on its short candidate lists (that compaction here
    made the flocking pass ~10 % slower at N = 80, B = 32)."""
    k = 0
    one = np.uint64(1)
    for w in range(lo >> 6, (N + 63) >> 6 if lo < N else 0):
        bits = np.uint64(0)
        rw, first = row[64 * w : min(64 * w + 64, N)], lo - 64 * w
        for t in range(rw.shape[0]):
            hit = (rw[t] < prm.radius2) & (t >= first)
            bits |= np.uint64(hit) << np.uint64(t)
        while bits != 0:
            nb[k] = 64 * w + low_bit(bits)
            bits &= bits - one
            k += 1
    return k


@jit_kernel
def _sweep_pairs(q, p, partner, prm, b, acc, min_d2, fw, fwu, iw, wm, lb, dims):
    """:func:`_sweep_all_pairs` with each pair met once: UAV x against the UAVs after it
    (distances, both separations, collisions, weights), the weight of each of its neighbours
    after it kept in ``wm[x, j]`` and x marked in that neighbour's bits ``lb[j]``, so that
    x finds its neighbours before it, in order, with their weights. The same sums in the
    same order; half the distances and exponentials. Needs ``wm`` of N x N."""
    three, floor, ellipse = _three(dims), _floor(dims), _ellipse(dims)
    N = q.shape[1]
    for i in range(N):  # positions and velocities by axis, in index order
        for k in range(3 if three else 2):
            fw[QS + k, i] = q[b, i, k]
            fw[PS + k, i] = p[b, i, k]
        for w in range(lb.shape[1]):
            lb[i, w] = 0
    row, parent, size, nb, gauss = fw[ROW], iw[PARENT], iw[SIZE], iw[NB], fw[EXP]
    cq0, cq1, cp0, cp1 = fw[QS], fw[QS + 1], fw[PS], fw[PS + 1]
    cq2, cp2 = fw[QS + 2], fw[PS + 2]
    inf_bits = float_bits(np.inf)
    one = np.uint64(1)
    nc = 0
    for x in range(N):
        x0, x1, v0, v1 = cq0[x], cq1[x], cp0[x], cp1[x]
        x2 = cq2[x] if three else 0.0
        v2 = cp2[x] if three else 0.0
        # the UAVs after x (loops over views from 0: numba vectorises those)
        lo = x + 1
        r, md = row[lo:N], min_d2[b, lo:N]
        a0, a1, a2 = cq0[lo:N], cq1[lo:N], cq2[lo:N]
        skip = partner[x] - lo  # x's partner: no separation between the two
        m = float_bits(min_d2[b, x])
        near = 0
        for t in range(r.shape[0]):  # distances, both separations, collisions
            a, e = a0[t] - x0, a1[t] - x1
            d2 = a * a + e * e  # summed over axes in order, as grid.dist2
            if three:
                z = a2[t] - x2
                d2 += z * z
            r[t] = d2
            other = t != skip
            v = float_bits(d2) if other else inf_bits
            m = v if v < m else m
            if ellipse:
                nc += _ellipse_hit(prm, a, e, a2[t] - x2)
            else:
                nc += d2 < prm.collision_distance2
            near += d2 < prm.radius2
            mj = md[t]
            md[t] = d2 if (d2 < mj) & other else mj
        min_d2[b, x] = bits_float(m)
        f0, f1, f2 = acc[b, x, 0], acc[b, x, 1], acc[b, x, 2] if three else 0.0
        for w in range((x >> 6) + 1):  # the neighbours before x, in increasing index
            bits = lb[x, w]
            while bits != 0:
                j = 64 * w + low_bit(bits)
                bits &= bits - one
                dq2 = cq2[j] - x2 if three else 0.0
                dp2 = cp2[j] - v2 if three else 0.0
                g = _weighted_force(
                    prm, wm[j, x], cq0[j] - x0, cq1[j] - x1, dq2, cp0[j] - v0, cp1[j] - v1, dp2
                )
                f0, f1, f2 = f0 + g[0], f1 + g[1], f2 + g[2]
        k = _later_neighbors(prm, row, lo, N if near else lo, nb)
        _gauss_rows(prm, row, nb, k, gauss)  # their exponentials first, vectorised
        root = find(parent, x)
        bit_x = one << np.uint64(x & 63)
        for t in range(k):
            j = nb[t]
            dq2 = cq2[j] - x2 if three else 0.0
            dp2 = cp2[j] - v2 if three else 0.0
            wm[x, j] = w = _weight(prm, row[j], gauss[t], floor)
            g = _weighted_force(
                prm, w, cq0[j] - x0, cq1[j] - x1, dq2, cp0[j] - v0, cp1[j] - v1, dp2
            )
            lb[j, x >> 6] |= bit_x
            f0, f1, f2 = f0 + g[0], f1 + g[1], f2 + g[2]
            root = join(parent, size, root, j)
        acc[b, x, 0], acc[b, x, 1] = f0, f1
        if three:
            acc[b, x, 2] = f2
    return nc


@jit_kernel
def _sweep_grid(q, p, partner, prm, b, g, acc, min_d2, fw, fwu, iw, dims):
    """:func:`_sweep_all_pairs` on the grid, cell by cell: the UAVs of a cell share one
    candidate list (its one-ring, put in index order once), and UAVs, candidates and the
    union-find forest are all held in slot (cell) order, so that memory follows space
    whatever the indices. The same results."""
    three, floor, ellipse = _three(dims), _floor(dims), _ellipse(dims)
    N = q.shape[1]
    order = g.order[b]
    copy_slots(q, p, b, order, partner, acc, fw, iw, three)
    cidx = iw[CIDX]
    nc = 0
    s = 0
    padded = g.n_ring[b] > 0
    bucket = -1
    while s < N:  # slots s..end-1: the UAVs of one bucket (one UAV when folded)
        if padded:  # the next occupied bucket, and its one-ring
            bucket += 1
            while g.start[b, bucket + 1] == s:
                bucket += 1
            end = g.start[b, bucket + 1]
            n_bk = g.n_ring[b]
            for t in range(n_bk):
                g.buckets[t] = bucket + g.ring[b, t]
        else:
            end = s + 1
            n_bk = one_ring(q, b, order[s], g, g.buckets)
        n = 0
        for t in range(n_bk):
            bk = g.buckets[t]
            for s2 in range(g.start[b, bk], g.start[b, bk + 1]):
                cidx[n] = order[s2]
                n += 1
        sort_indices(cidx, n, iw[TMP], iw[HIST], g.mark, N)
        gather(n, fw, iw, three)
        for s2 in range(s, end):
            nc += _gather_uav(s2, order[s2], n, prm, fw, fwu, iw, three, floor, ellipse)
        s = end
    put_slots(b, order, acc, min_d2, fw, three)
    # the one-ring proves separations shorter than a cell; the others need a wider search
    bound = ring_bound2(g, 1)
    for i in range(N):
        if not min_d2[b, i] < bound:
            min_d2[b, i] = nearest_d2(q, b, i, partner[i], g, min_d2[b, i], 1)
    return nc // 2


@jit_kernel
def _flock_swarms(q, p, ql, pl, h, partner, prm, out, fw, fwu, iw, wm, lb, g, dims):
    """Every swarm: grid pass where ``g`` holds the swarm, all pairs otherwise. ``dims``:
    a tuple of ``dim`` entries, so that each dimension compiles its own kernels."""
    acc, min_d2, n_coll, lcc, bad, vmis, vmax = out
    parent, size = iw[PARENT], iw[SIZE]
    n_unpaired = _count_unpaired(partner)
    for b in range(q.shape[0]):
        _velocity_mismatch(p, pl, partner, n_unpaired, b, vmis, vmax)
        bad[b] = _start_swarm(q, p, ql, pl, h, prm, b, acc, min_d2, parent, size)
        if g is not None and g.ok[b]:
            args = (acc, min_d2, fw, fwu, iw, dims)
            n_coll[b] = _sweep_grid(q, p, partner, prm, b, g, *args)
        elif wm.shape[0] >= q.shape[1]:
            args = (acc, min_d2, fw, fwu, iw, wm, lb, dims)
            n_coll[b] = _sweep_pairs(q, p, partner, prm, b, *args)
        else:
            n_coll[b] = _sweep_all_pairs(q, p, partner, prm, b, acc, min_d2, fw, fwu, iw, dims)
        lcc[b] = largest_component(parent[: q.shape[1]], size)


# The entry points take arrays one by one: the dispatcher types plain arrays fastest, which
# matters for small swarms, where a pass takes a few microseconds.
@jit_kernel
def _flocking_kernel(q, p, ql, pl, h, prt, prm, dims, acc, md2, nc, lcc, bad, vm, vx, *work):
    out = (acc, md2, nc, lcc, bad, vm, vx)
    _flock_swarms(q, p, ql, pl, h, prt, _scalars(prm), out, *work, None, dims)


@jit_kernel
def _flocking_grid_kernel(
    q, p, ql, pl, h, prt, prm, dims, acc, md2, nc, lcc, bad, vm, vx, fw, fu, iw, wm, lb, *grid
):
    out = (acc, md2, nc, lcc, bad, vm, vx)
    g = GridArrays(*grid)
    _flock_swarms(q, p, ql, pl, h, prt, _scalars(prm), out, fw, fu, iw, wm, lb, g, dims)


#: the outputs of a pass, in the kernels' order
_FLOCK_KEYS = ("acc", "min_d2", "collisions", "largest_component", "diverged")
_FLOCK_KEYS += ("velocity_mismatch", "velocity_mismatch_max", "_fw", "_fwu", "_iw", "_wm", "_lb")
#: all pairs meet each pair once (:func:`_sweep_pairs`) up to this many UAVs, whose N x N
#: weights take 2 MB; beyond, each UAV meets the others in turn (:func:`_sweep_all_pairs`)
_PAIRS_MAX = 512
#: the ``dims`` argument of the kernels, keyed by (dimension, repulsion floor, collision
#: ellipsoid): its length is the dimension (2 or 3), plus 2 with the swarm layer's repulsion
#: floor, plus 4 with the collision ellipsoid (3-D only), so that each combination compiles
#: its own kernels (the floor's and the ellipsoid's tests leave the pair loops of the
#: paper's law, whose kernels compile as before)
_DIMS = {
    (D, floor, ellipse): (0,) * (D + 2 * floor + 4 * ellipse)
    for D in (2, 3)
    for floor in (False, True)
    for ellipse in ((False, True) if D == 3 else (False,))
}


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
            with ``cell_size >= max(radius, collision_distance, collision_height)``, built
            from ``q``'s current values. Both give identical results.

    Returns:
        dict with ``acc`` (B, N, dim) m/s^2, ``min_d2`` (B, N) squared distance to the nearest
        non-partner UAV, ``collisions`` (B,) int (pairs inside the collision sphere, or the
        collision ellipsoid when the params' squash is not 1), ``largest_component`` (B,) int,
        ``diverged`` (B,) bool, ``velocity_mismatch`` / ``velocity_mismatch_max`` (B,) mean
        and max of ||p_i - p_leader|| over the unpaired UAVs (all UAVs when every UAV is
        paired). Per-swarm sums run sequentially, so results do not depend on B.
    """
    return flocking_runner(params, q.shape, grid, out)(q, p, leader_q, leader_p, pinned, partner)


def flocking_runner(
    params: np.ndarray,
    shape: tuple[int, int, int],
    grid: NeighborGrid | None = None,
    out: dict[str, np.ndarray] | None = None,
):
    """:func:`flocking_pass` for repeated calls on arrays of ``shape`` (B, N, dim): the grid
    checked and the outputs allocated (or ``out`` reused) once. Returns
    ``run(q, p, leader_q, leader_p, pinned, partner) -> out`` (the same dict every call)."""
    B, N, D = shape
    ellipse = bool(params[_F.collision_squash] != 1.0) and D == 3
    check_grid(
        grid,
        tuple(shape),
        max(params[_F.radius2], params[_F.collision_distance2], params[_F.collision_height2]),
        "max(radius, collision_distance, collision_height)",
    )
    if out is None or out["acc"].shape != tuple(shape):
        words = (N + 63) // 64
        out = {
            "acc": np.empty((B, N, D)),
            "min_d2": np.empty((B, N)),
            "collisions": np.empty(B, np.int64),
            "largest_component": np.empty(B, np.int64),
            "diverged": np.empty(B, np.bool_),
            "velocity_mismatch": np.empty(B),
            "velocity_mismatch_max": np.empty(B),
            # scratch: see pairflock_env.swarm.slots
            "_fw": np.zeros((EXP + 1, 64 * words)),
            "_iw": np.zeros((HIST + 1, max(64 * words, 256)), np.int64),  # HIST: the last
        }
        out["_fwu"] = out["_fw"].view(np.uint64)
        n_wm = N if grid is None and N <= _PAIRS_MAX else 0  # (the grid's fallback: rows)
        out["_wm"] = np.zeros((n_wm, n_wm))
        out["_lb"] = np.zeros((n_wm, words), np.uint64)
    dims = _DIMS[D, bool(params[_F.floor_radius2] > 0), ellipse]
    tail = (params, dims, *(out[k] for k in _FLOCK_KEYS))
    if grid is None:
        return BoundKernel(_flocking_kernel, tail, out)
    return BoundKernel(_flocking_grid_kernel, (*tail, *grid.arrays), out)
