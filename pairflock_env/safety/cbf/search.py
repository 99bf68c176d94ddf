"""How far each UAV of the swarm layer searches (docs/swarm-safety.md, "Speed"): a bound
on every relative speed from an affine fit of the swarm's velocities, the search radius it
gives, tabulated per step, and the grid of a ladder each search uses.

The far-UAV skip (:func:`~.kernels._far`) drops a UAV j whose barrier row cannot bind at
its distance and relative speed. A search that stops where the skip would drop every UAV
gives the same rows as one over the whole sensing radius. Bounding every relative speed by
the swarm's largest speed relative to its mean is safe but loose while a spread flock
contracts: each UAV is then fast relative to the mean but nearly at its neighbours' speed,
and searches reached 100 m. The affine fit keeps what neighbours share.

Three more shortcuts, each giving the same hits: the radii are tabulated per step at a few
residual levels; the fastest 5 % of the unpaired UAVs (the outliers, whose residuals would
set every search's reach) search once for everyone and leave contact lists, so that the
others search only as far as the 95th-percentile residual needs; and a search shorter than
the UAV's nearest neighbour (the flocking pass's ``min_d2``) is skipped.

numba's on-disk cache keys a compiled function on its own file only: after editing this
module, clear the numba cache (the ``__pycache__`` folders) before trusting a run.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import jit_inline, jit_kernel
from pairflock_env.safety.cbf.kernels import _far_radius, _scan_free
from pairflock_env.swarm.grid import _point_d2, order_indices, within_radius

__all__ = [
    "FIT_ROWS",
    "GRID",
    "LADDER_REACH",
    "OUTLIER_SHARE",
    "RADIUS_LEVELS",
    "SCAN",
    "SWEEP",
    "candidates",
    "outlier_contacts",
    "outlier_level",
    "outlier_split",
    "prefix_sums",
    "radius_table",
    "search_radius",
    "shortened",
    "sort_by_x",
    "tabulated",
    "velocity_field",
]

#: rows of the (FIT_ROWS, 3) scratch of :func:`velocity_field`: the mean velocity and mean
#: position, then three rows each of the fitted gradient K and of the two sums
_CBAR, _QBAR, _K0, _C0, _P0 = 0, 1, 2, 5, 8
FIT_ROWS = 11
#: the search radius is sought to this relative width (it need not be tight, only safe)
_RADIUS_TOL = 1e-3


@jit_kernel
def velocity_field(q, p, b, paired, fit, res):
    """A bound on every relative speed of swarm b from an affine fit of its velocities.

    Fits p_j ~ cbar + K (q_j - qbar) by least squares (cbar, qbar: the mean velocity and
    position, and K, into ``fit``, (FIT_ROWS, 3) scratch), and writes each UAV's residual
    e_j = |p_j - cbar - K (q_j - qbar)| into ``res``. For any two UAVs then

        |p_i - p_j| <= k |q_i - q_j| + e_i + e_j,   k >= ||K||_2,

    whatever K is (the fit only makes the bound tight: a flock contracting towards its
    leader moves fast relative to its mean, but its neighbours move alike). Returns (k, eo,
    pad): eo the largest residual of an unpaired UAV, pad a bound on the rounding of a
    residual. (inf, inf, inf) when a position or a velocity is not finite."""
    N, D = q.shape[1], q.shape[2]
    cbar, qbar = fit[_CBAR], fit[_QBAR]
    for k in range(3):
        cbar[k] = 0.0
        qbar[k] = 0.0
    for j in range(N):
        for k in range(D):
            cbar[k] += p[b, j, k]
            qbar[k] += q[b, j, k]
    for k in range(D):
        cbar[k] /= N
        qbar[k] /= N
    # the normal equations K Cqq = Cpq, with Cqq lightly regularised (any K is valid)
    C, P = fit[_C0 : _C0 + 3], fit[_P0 : _P0 + 3]
    for r in range(3):
        for s in range(3):
            C[r, s] = 0.0
            P[r, s] = 0.0
    for j in range(N):
        for r in range(D):
            x = q[b, j, r] - qbar[r]
            for s in range(D):
                C[r, s] += x * (q[b, j, s] - qbar[s])
                P[r, s] += (p[b, j, r] - cbar[r]) * (q[b, j, s] - qbar[s])
    tr = 0.0
    for r in range(D):
        tr += C[r, r]
    ok = np.isfinite(tr)
    for r in range(D):
        for s in range(D):
            ok = ok and np.isfinite(P[r, s])
    if not ok:
        return np.inf, np.inf, np.inf
    for r in range(D):
        C[r, r] += 1e-9 * tr + 1e-300
    _solve_gradient(C, P, D, fit)
    # k: the smaller of the Frobenius norm and sqrt(||K||_1 ||K||_inf), both >= ||K||_2
    fro, n1, ninf = 0.0, 0.0, 0.0
    for r in range(D):
        row, col = 0.0, 0.0
        for s in range(D):
            fro += fit[_K0 + r, s] ** 2
            row += abs(fit[_K0 + r, s])
            col += abs(fit[_K0 + s, r])
        ninf, n1 = max(ninf, row), max(n1, col)
    kn = min(np.sqrt(fro), np.sqrt(n1 * ninf))
    if not np.isfinite(kn):  # a degenerate fit: the plain ball around cbar
        kn = 0.0
        for r in range(D):
            for s in range(D):
                fit[_K0 + r, s] = 0.0
    eo, vmax, xmax = 0.0, 0.0, 0.0
    for j in range(N):
        e2, v2, x2 = 0.0, 0.0, 0.0
        for r in range(D):
            e = p[b, j, r] - cbar[r]
            for s in range(D):
                e -= fit[_K0 + r, s] * (q[b, j, s] - qbar[s])
            e2 += e * e
            v2 += p[b, j, r] * p[b, j, r]
            x2 += q[b, j, r] * q[b, j, r]
        res[j] = np.sqrt(e2)
        vmax, xmax = max(vmax, v2), max(xmax, x2)
        if not paired[j]:
            eo = max(eo, res[j])
    c2, m2 = 0.0, 0.0
    for r in range(D):
        c2 += cbar[r] * cbar[r]
        m2 += qbar[r] * qbar[r]
    scale = np.sqrt(vmax) + np.sqrt(c2) + kn * (np.sqrt(xmax) + np.sqrt(m2))
    return kn, eo, 1e-9 * scale


@jit_inline
def _solve_gradient(C, P, D, fit):
    """K = P C^-1 into fit[_K0:_K0 + D] (C symmetric positive definite, D <= 3): Gaussian
    elimination of C K^T = P^T, one right-hand side per row of K."""
    for r in range(D):
        for s in range(D):
            fit[_K0 + r, s] = P[r, s]
    for c in range(D):  # forward elimination on C and on every row of K alike
        piv = C[c, c]
        for r in range(c + 1, D):
            f = C[r, c] / piv
            for s in range(c, D):
                C[r, s] -= f * C[c, s]
            for m in range(D):
                fit[_K0 + m, r] -= f * fit[_K0 + m, c]
    for c in range(D - 1, -1, -1):
        for m in range(D):
            v = fit[_K0 + m, c]
            for s in range(c + 1, D):
                v -= C[c, s] * fit[_K0 + m, s]
            fit[_K0 + m, c] = v / C[c, c]


@jit_inline
def _excess(far, kn, c, d):
    """g(d) of :func:`search_radius`, with a relative margin of 1e-9 on both sides: far
    above the rounding of far_radius, so g(d) <= 0 holds in exact arithmetic too."""
    gap = 1e-9
    return _far_radius(kn * d * (1.0 + gap) + c, far) - d * (1.0 - gap)


@jit_inline
def search_radius(far, kn, c, R):
    """How far UAV i must search for rows of this kind: a radius r <= R such that the
    far-UAV skip drops every UAV j at a distance d in [r, R] whose relative speed is at
    most kn d + c (:func:`velocity_field`; c = e_i + e_j's bound, padded).

    g(d) = far_radius(kn d + c) - d is convex in d (far_radius is convex and
    non-decreasing in the speed), so g <= 0 on [r, R] once it is at both ends. g is a
    quadratic wherever the speed term of far_radius is positive: the quadratic through
    g(0), g(R/2), g(R) gives its root, taken when g confirms it; else bisection, which
    keeps g(hi) <= 0, to a relative width of 1e-3."""
    gR = _excess(far, kn, c, R)
    if gR > 0.0:
        return R
    lo, hi = 0.0, R
    g0, m = _excess(far, kn, c, 0.0), 0.5 * R
    a = (gR - 2.0 * _excess(far, kn, c, m) + g0) / (2.0 * m * m)
    bq = (gR - g0) / R - a * R
    disc = bq * bq - 4.0 * a * g0
    if g0 > 0.0 and disc >= 0.0 and np.sqrt(disc) - bq > 0.0:
        r = min(2.0 * g0 / (np.sqrt(disc) - bq) * (1.0 + 1e-6) + 1e-9, R)
        if _excess(far, kn, c, r) <= 0.0:
            return r
        lo = r
    for _ in range(64):
        if hi - lo <= _RADIUS_TOL * hi:
            break
        mid = 0.5 * (lo + hi)
        if _excess(far, kn, c, mid) > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


@jit_inline
def shortened(r2, far, fld, e_i):
    """The squared search radius of a UAV with residual e_i, for rows of the kind ``far``
    against UAVs whose residual is at most eo: the smaller of the radius from the affine
    bound and r2. ``fld`` = (kn, eo, pad) of :func:`velocity_field`."""
    kn, eo, pad = fld
    c = (e_i + eo) * (1.0 + 1e-9) + 2.0 * pad
    r = search_radius(far, kn, c, np.sqrt(r2))
    return min(r2, r * r)


#: a search uses the finest grid of the ladder whose block reaches at most this many cells
#: from the query's cell (the cells visited grow as its cube; the UAVs checked, as the
#: coarser cells hold more of them)
LADDER_REACH = 3.0


@jit_kernel
def sort_by_x(q, p, b, order, pos):
    """Put ``order`` (swarm b's UAVs, as left by the last step) in increasing x by insertion,
    O(N) while the flock moves little between steps, and its inverse into ``pos``. Returns
    False, leaving both, unless :func:`~.kernels._scan_free` (the grid's test too): then
    only the scan of all N stops where the pair filter's scan would."""
    N = q.shape[1]
    if not _scan_free(q, p, b):
        return False
    for t in range(1, N):
        j = order[t]
        x = q[b, j, 0]
        s = t
        while s > 0 and q[b, order[s - 1], 0] > x:
            order[s] = order[s - 1]
            s -= 1
        order[s] = j
    for t in range(N):
        pos[order[t]] = t
    return True


@jit_inline
def _d2_hit(q, b, j, pt, r2, exclude):
    """Whether UAV j is a hit: the test of the grid's scan, the same operations."""
    return j != exclude and _point_d2(q, b, j, pt) < r2


@jit_inline
def _walk(q, b, pt, r2, exclude, order, start, stop, step, hits, n):
    """The scan's hits among order[start:stop:step] into hits[n:], until the x offset alone
    reaches the radius; returns the new count."""
    for t in range(start, stop, step):
        j = order[t]
        x = q[b, j, 0] - pt[0]
        if x * x >= r2:
            break
        if _d2_hit(q, b, j, pt, r2, exclude):
            hits[n] = j
            n += 1
    return n


@jit_inline
def _sweep(q, b, pt, r2, exclude, xs, hits):
    """The scan's hits around UAV ``exclude`` (at ``pt``) from the x-sorted order ``xs`` =
    (order, pos, mark): walking out both ways from it until the x offset alone
    reaches the radius. Rounding keeps that exact: x - x_i grows along the order, and a
    squared distance is never below its first term."""
    order, pos, mark = xs
    s0 = pos[exclude]
    n = _walk(q, b, pt, r2, exclude, order, s0, q.shape[1], 1, hits, 0)
    n = _walk(q, b, pt, r2, exclude, order, s0 - 1, -1, -1, hits, n)
    return order_indices(hits, n, mark)


#: how :func:`candidates` searches: all N, a grid of the ladder, or the x-sorted order
SCAN, GRID, SWEEP = 0, 1, 2


#: a search is skipped when its squared radius is below this share of the squared distance
#: to the UAV's nearest neighbour (far above the rounding by which two computations of one
#: squared distance can differ)
_SEP_SHARE = 1.0 - 1e-12


@jit_inline
def candidates(q, b, i, r2, mode, gs, xs, sep, hits):
    """The UAVs of swarm b closer than sqrt(r2) to UAV i (itself left out) into ``hits``,
    in increasing index; returns their count. ``mode``: SCAN (all N), GRID (the finest grid
    of the ladder ``gs`` = (g0, g1, g2, reach) whose cells are at least a third of the
    radius; grids fine to coarse, all built from q; reach (1,) keeps the largest r2 a grid
    search used, which grids the next step needs) or SWEEP (the x-sorted order ``xs`` of
    :func:`sort_by_x`). Every mode gives the same list.

    ``sep`` (B, N): each UAV's squared distance to its nearest neighbour other than its
    partner (the flocking pass's ``min_d2`` of this q; zeros when unknown). Under GRID and
    SWEEP (a finite swarm) a radius below it finds nobody but perhaps the partner, which
    is paired and never a candidate: the search is skipped, as most are in a settled flock."""
    pt = q[b, i]
    if mode != SCAN and r2 < sep[b, i] * _SEP_SHARE:
        return 0
    if mode == GRID:
        g0, g1, g2, reach = gs
        reach[0] = max(reach[0], r2)
        if r2 <= (LADDER_REACH * g0.h) ** 2:
            return within_radius(q, b, pt, r2, i, g0, hits)
        if r2 <= (LADDER_REACH * g1.h) ** 2:
            return within_radius(q, b, pt, r2, i, g1, hits)
        return within_radius(q, b, pt, r2, i, g2, hits)
    if mode == SWEEP:
        return _sweep(q, b, pt, r2, i, xs, hits)
    n = 0
    for j in range(q.shape[1]):
        if _d2_hit(q, b, j, pt, r2, i):
            hits[n] = j
            n += 1
    return n


#: the unpaired UAVs' search radii are tabulated at this many residual levels per step
RADIUS_LEVELS = 64


@jit_kernel
def radius_table(r2, far, fld, table, N):
    """The squared search radius of an unpaired UAV (:func:`shortened`) at residual levels
    0, de, 2 de, ... L de = eo (``fld`` = (kn, eo, pad)) into ``table``, L = N / 16 within
    [4, RADIUS_LEVELS]; returns (de, L). The radius grows with the residual, so a UAV whose
    residual is at most l de may use entry l: L + 1 radii per swarm and step, not N."""
    L = min(max(N // 16, 4), table.shape[0] - 1)
    eo = fld[1]
    de = eo / L if np.isfinite(eo) else 0.0
    for lv in range(L + 1):
        e = lv * de * (1.0 + 2e-9) if de > 0.0 else eo
        table[lv] = shortened(r2, far, fld, e)
    return de, L


@jit_inline
def tabulated(table, de, L, e_i):
    """Entry of :func:`radius_table` for a residual e_i <= eo."""
    if not de > 0.0:
        return table[L]
    lv = int(np.ceil(e_i / de))
    return table[min(max(lv, 0), L)]


@jit_inline
def prefix_sums(start, cnt, N):
    """Turn the counts start[1:N + 1] of a count-then-fill list into its offsets, and set
    each row's fill cursor cnt[i] to its start."""
    for i in range(N):
        start[i + 1] += start[i]
        cnt[i] = start[i]


#: the share of a swarm's unpaired UAVs whose residual bounds the others' searches; the
#: fastest rest (the "outliers") search for their rows against the others themselves
#: (:func:`outlier_contacts`)
OUTLIER_SHARE = 0.95


@jit_kernel
def outlier_level(res, paired, de, L, hist):
    """The residual e_t below which ``OUTLIER_SHARE`` of the unpaired UAVs lie, as the upper
    end of a level of :func:`radius_table` (``hist``: (L + 1,) int scratch); inf when no
    level below the top one holds that share (no split)."""
    if not de > 0.0:
        return np.inf
    for lv in range(L + 1):
        hist[lv] = 0
    n = 0
    for j in range(res.shape[0]):
        if not paired[j]:
            hist[min(max(int(np.ceil(res[j] / de)), 0), L)] += 1
            n += 1
    need = int(np.ceil(OUTLIER_SHARE * n))
    cum = 0
    for lv in range(L):
        cum += hist[lv]
        if cum >= need:
            return lv * de * (1.0 + 2e-9)
    return np.inf


@jit_kernel
def outlier_contacts(q, b, paired, res, e_t, table, de, L, mode, gs, xs, sep, hits, ocon):
    """For every unpaired UAV i with residual <= e_t, the unpaired UAVs j above e_t (the
    outliers) that may need a row against it, in increasing j, as olist[ostart[i]:ostart[i
    + 1]] (``ocon`` = (ostart, ocnt, olist)): each outlier searches once, out to its own
    radius (``table``: :func:`radius_table` against every residual), which covers every
    UAV whose residual is at most the largest. Returns False (lists empty) when they would
    not fit in olist."""
    ostart, ocnt, olist = ocon
    N = q.shape[1]
    for i in range(N + 1):
        ostart[i] = 0
    for fill in range(2):  # count, then fill
        for j in range(N):
            if paired[j] or not res[j] > e_t:
                continue
            nh = candidates(q, b, j, tabulated(table, de, L, res[j]), mode, gs, xs, sep, hits)
            for t in range(nh):
                i = hits[t]
                if paired[i] or res[i] > e_t:
                    continue
                if fill == 0:
                    ostart[i + 1] += 1
                else:
                    olist[ocnt[i]] = j
                    ocnt[i] += 1
        if fill == 0:
            prefix_sums(ostart, ocnt, N)
            if ostart[N] > olist.shape[0]:
                for i in range(N + 1):
                    ostart[i] = 0
                return False
    return True


@jit_inline
def outlier_split(q, b, paired, res, r2, far, fld, table, de, L, split, mode, gs, xs, sep,
                  hits, outl):  # fmt: skip
    """The outlier split of swarm b when ``split`` (a finite swarm on the grid or the x order,
    with the far-UAV skip on) and the outliers' lists fit: (e_t, table_t, de_t, L_t), the
    non-outliers' residual bound and radius table (:func:`radius_table` of ``outl[0]``
    against e_t), the contact lists in ``outl``. Else (inf, table, de, L) and empty lists:
    every unpaired UAV searches out to every residual."""
    table_t, hist, ostart, ocnt, olist = outl
    N = q.shape[1]
    if split:
        e_t = outlier_level(res, paired, de, L, hist)
        if e_t < np.inf:
            de_t, L_t = radius_table(r2, far, (fld[0], e_t, fld[2]), table_t, N)
            ocon = (ostart, ocnt, olist)
            if outlier_contacts(q, b, paired, res, e_t, table, de, L, mode, gs, xs, sep, hits,
                                ocon):  # fmt: skip
                return e_t, table_t, de_t, L_t
    for i in range(N + 1):
        ostart[i] = 0
    return np.inf, table, de, L
