"""The swarm layer's numba kernels (``safety_scope="swarm"``, docs/swarm-safety.md): every
UAV of every swarm filters its whole command with the pair filter's barrier rows, exact
solver and far-UAV skip (:mod:`.kernels`).

UAV i's problem, in its variable x = a_i - c_i (c_i = 0 for an unpaired UAV; its flocking
command f_i for a paired one, so that a paired UAV keeps the pair filter's variable and
ball):

    minimise ||x - x_nom||^2   subject to   ||x|| <= U_i   and, for every UAV j it senses,
    n_ij . (c_i + x) >= alpha_i / (alpha_i + alpha_j) sigma_min(e_ij, v_ij; alpha_i + alpha_j)

j writes the same row with n_ji = -n_ij and its own share, so the two add up to the pair
filter's relative condition n_ij . (a_i - a_j) >= sigma_min: the reciprocal split of Wang,
Ames and Egerstedt, weighted by brake capacity alpha. One exception (``pair_alone``): a
paired UAV that out-brakes an unpaired UAV's whole bound U_s by at least that UAV's own brake
(alpha_p - U_s >= alpha_s: 780 >= 16 m/s^2 in the paper's task) takes its rows against
unpaired UAVs alone, as the pair filter does, with the unpaired UAV's acceleration at most
U_s, which its ball guarantees: n_ij . a_i >= sigma_min(alpha_p - U_s) + U_s. The unpaired
UAVs then have no rows against paired ones, so a pair closing on an unpaired UAV from two
sides cannot make it infeasible.

Two unpaired UAVs sense each other within ``swarm_radius2``, a pair of UAVs of which one is
paired within ``pair_radius2`` (a partner at any distance): both sides of a pair see the same
rows. Each search is shortened to where the far-UAV skip would drop every UAV, under a
bound on relative speeds fitted to the swarm's velocity field, and uses the grid of a ladder
that suits its radius (:mod:`.search`). Where the rows with paired UAVs are shared,
an unpaired UAV's paired candidates come from a contact list that each paired UAV fills with
one search, so a swarm costs O(N + M k), not O(N M).

The rows come from :func:`~.kernels._constrain_one` and the solver is
:func:`~.kernels._solve_ws`; numba's on-disk cache keys a compiled function on its own file
only, so after editing :mod:`.kernels` or ``swarm/grid.py``, clear the numba cache (the
``__pycache__`` folders) before trusting a run of this layer.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import KernelParams, jit_inline, jit_kernel
from pairflock_env.safety.cbf.kernels import (
    STATUS_INFEASIBLE,
    STATUS_PROJECTED,
    WS_MAX,
    _constrain_one,
    _far_constants,
    _grid_usable,
    _margin,
    _put,
    _solve_ws,
)
from pairflock_env.safety.cbf.search import (
    GRID,
    SCAN,
    SWEEP,
    candidates,
    outlier_split,
    prefix_sums,
    radius_table,
    shortened,
    sort_by_x,
    tabulated,
    velocity_field,
)

__all__ = ["SWARM", "VEC_ROWS", "swarm_kernel"]

#: the swarm layer's parameters (squared radii: the kernel compares squared distances;
#: ``pair_alone`` 1: a paired UAV takes its rows against unpaired UAVs alone, counting on
#: their whole command being at most ``other_accel`` (U_s); ``skip_far`` 1 drops the UAVs
#: too far to bind, 0 evaluates every sensed UAV)
SWARM = KernelParams(
    "Swarm",
    (
        "barrier_distance",
        "dt",
        "position_gain",
        "decay",
        "reaction_time",
        "pair_radius2",
        "swarm_radius2",
        "other_accel",
        "pair_alone",
        "skip_far",
    ),
)
_S = SWARM.index

#: rows of the (VEC_ROWS, 3) float scratch: UAV i's centre c_i, the solver's candidate and
#: best point, x_nom, x, a row's normal
_CTR, _CAND, _BEST, _XIN, _XOUT, _NV = range(6)
VEC_ROWS = 6
#: relative pad of the drop threshold S over the rounding of (U + |c|) (alpha_ij / alpha_i)
_S_PAD = 1e-12


@jit_inline
def _far_of(pr, a_i, a_j, U_i, cn, A_i, A_j):
    """:func:`~.kernels._far_constants` of UAV i (brake a_i, ball U_i around a centre of norm
    cn, |a_i| <= A_i) against a UAV of brake a_j with |a_j| <= A_j. i's row against it
    needs n . x >= share sigma_min - n . c_i, which the ball implies once share sigma_min
    <= -(U_i + cn), i.e. sigma_min <= -S with S = (U_i + cn) (a_i + a_j) / a_i."""
    a = a_i + a_j
    S = (U_i + cn) * (a / a_i) * (1.0 + _S_PAD)
    R = np.sqrt(max(pr[_S.pair_radius2], pr[_S.swarm_radius2]))
    Ds, T, c = pr[_S.barrier_distance], pr[_S.dt], pr[_S.position_gain]
    return _far_constants(Ds, T, c, pr[_S.decay], pr[_S.reaction_time], a, S, A_i + A_j, R, a_i / a)


@jit_inline
def _far_alone(pr, a_i, U_i, cn, A_i, A_o):
    """:func:`~.kernels._far_constants` of a paired UAV taking its row against an unpaired
    UAV alone (``pair_alone``): the unpaired UAV's command is at most A_o = U_s (its ball),
    so i needs n . a_i >= sigma_min + A_o with alpha_ij = a_i - A_o, implied by i's ball
    once sigma_min <= -(U_i + cn + A_o)."""
    S = (U_i + cn + A_o) * (1.0 + _S_PAD)
    R = np.sqrt(max(pr[_S.pair_radius2], pr[_S.swarm_radius2]))
    Ds, T, c = pr[_S.barrier_distance], pr[_S.dt], pr[_S.position_gain]
    a = a_i - A_o
    return _far_constants(Ds, T, c, pr[_S.decay], pr[_S.reaction_time], a, S, A_i + A_o, R, 1.0)


@jit_kernel
def _class_values(paired, alpha, bound):
    """The brake and the bound of the unpaired UAVs and the brake of the paired ones (each
    class shares its values; 1 for a class with no UAV)."""
    a_u, U_u, a_p = 1.0, 1.0, 1.0
    for j in range(paired.shape[0] - 1, -1, -1):
        if paired[j]:
            a_p = alpha[j]
        else:
            a_u, U_u = alpha[j], bound[j]
    return a_u, U_u, a_p


@jit_kernel
def _abounds(f, b, paired, bound, abound):
    """Each UAV's bound on its own command into ``abound`` (U_j for an unpaired UAV, |f_j| +
    U_j for a paired one); returns the largest of each class (Au, Ap)."""
    Au, Ap = 0.0, 0.0
    for j in range(f.shape[1]):
        if paired[j]:
            s = 0.0
            for k in range(f.shape[2]):
                s += f[b, j, k] * f[b, j, k]
            abound[j] = np.sqrt(s) + bound[j]
            Ap = max(Ap, abound[j])
        else:
            abound[j] = bound[j]
            Au = max(Au, abound[j])
    return Au, Ap


@jit_kernel
def _contacts(q, p, b, paired, agents, alpha, bound, abound, pr, mode, gs, xs, sep, hits,
              far_up, a_u, Au, fld, res, cstart, cnt, clist):  # fmt: skip
    """For every unpaired UAV i, the paired UAVs j close enough for the row of (i, j) to
    bind from either side, in agent order, as clist[cstart[i]:cstart[i + 1]]: each paired
    UAV searches once, out to the larger search radius of both sides (j's, and ``far_up``,
    an unpaired UAV's against a paired one; at most the pairs' sensing radius) under the
    relative-speed bound of :func:`~.search.velocity_field` (``fld``, ``res``)."""
    N = q.shape[1]
    for i in range(N + 1):
        cstart[i] = 0
    for fill in range(2):  # count, then fill
        for m in range(agents.shape[0]):
            j = agents[m]
            cn = abound[j] - bound[j]
            far_j = _far_of(pr, alpha[j], a_u, bound[j], cn, abound[j], Au)
            r2 = pr[_S.pair_radius2]
            if pr[_S.skip_far] != 0.0:
                r2 = max(shortened(r2, far_j, fld, res[j]), shortened(r2, far_up, fld, res[j]))
            nh = candidates(q, b, j, r2, mode, gs, xs, sep, hits)
            for t in range(nh):
                i = hits[t]
                if paired[i]:
                    continue
                if fill == 0:
                    cstart[i + 1] += 1
                else:
                    clist[cnt[i]] = j
                    cnt[i] += 1
        if fill == 0:
            prefix_sums(cstart, cnt, N)


@jit_inline
def _uav_rows(q, p, b, i, ints, pr, far_u, far_p, U, r2, mode, gs, xs, sep, hits, vec, G, rhs,
              ocon):  # fmt: skip
    """UAV i's rows into G, rhs: the unpaired UAVs within its (shortened) squared search
    radius r2 and those of its outlier list (``ocon`` of :func:`~.search.outlier_contacts`;
    both in increasing index, merged), then the paired ones (every agent, for a paired i;
    its contact list, for an unpaired one unless the paired UAVs take those rows alone).
    ``far_u`` / ``far_p``: i's far constants against the two classes; ``ints`` = (paired,
    mate, agents, coop_u, coop_p, cstart, clist), coop_* telling, for an unpaired and for a
    paired i, which UAVs share its rows. Returns (K, min H, ok)."""
    paired, mate, agents, coop_u, coop_p, cstart, clist = ints
    ostart, _, olist = ocon
    Ds, T, c, lam = pr[_S.barrier_distance], pr[_S.dt], pr[_S.position_gain], pr[_S.decay]
    tau, prune, A_o = pr[_S.reaction_time], pr[_S.skip_far] != 0.0, pr[_S.other_accel]
    R2p = pr[_S.pair_radius2]
    Rs2 = max(R2p, pr[_S.swarm_radius2])
    coop = coop_p if paired[i] else coop_u
    nh = candidates(q, b, i, r2, mode, gs, xs, sep, hits)
    K, hmin, ctr, nv = 0, np.inf, vec[_CTR], vec[_NV]
    o, o1 = ostart[i], ostart[i + 1]
    R2 = r2 if o == o1 else pr[_S.swarm_radius2]  # outliers lie beyond r2; the skip drops
    t = 0
    while t < nh or o < o1:  # the hits and the outlier list, merged in increasing index
        if o >= o1 or (t < nh and hits[t] <= olist[o]):
            j = hits[t]
            t += 1
            if o < o1 and olist[o] == j:
                o += 1
        else:
            j = olist[o]
            o += 1
        if paired[j]:
            continue
        K, hmin, ok = _constrain_one(
            b, i, j, -1, q, p, ctr, paired, coop, Ds, A_o, R2, lam, T, c, tau, U, G, rhs, nv,
            K, hmin, far_u, far_p, prune, Rs2,
        )  # fmt: skip
        if not ok:
            return 0, np.nan, False
    m0, m1 = (0, agents.shape[0]) if paired[i] else (cstart[i], cstart[i + 1])
    for t in range(m0, m1):
        j = agents[t] if paired[i] else clist[t]
        if j == i:
            continue
        K, hmin, ok = _constrain_one(
            b, i, j, mate[i], q, p, ctr, paired, coop, Ds, A_o, R2p, lam, T, c, tau, U, G, rhs,
            nv, K, hmin, far_u, far_p, prune, Rs2,
        )  # fmt: skip
        if not ok:
            return 0, np.nan, False
    return K, hmin, True


@jit_inline
def _solve_uav(a_nom, b, i, U, K, ok, vec, G, rhs, solver):
    """x for UAV i (x_nom = a_nom - c_i) into vec[_XOUT]; returns (violated, status)."""
    W, idx, Gw, bw, ws, marg = solver
    D = a_nom.shape[2]
    xin, xout, ctr = vec[_XIN], vec[_XOUT], vec[_CTR]
    n2 = 0.0
    for k in range(D):
        xin[k] = a_nom[b, i, k] - ctr[k]
        n2 += xin[k] * xin[k]
    if not ok:  # a non-finite state (a diverged swarm): pass the command through
        _put(xout, xin, D)
        return True, STATUS_INFEASIBLE
    if K == 0 and n2 <= U * U:  # nothing binds: the nominal (what the solver returns too)
        _put(xout, xin, D)
        return False, 0
    if K == 0:  # only the ball: the solver's radial projection, the same operations
        rho, dist = np.sqrt(max(U * U - 0.0, 0.0)), np.sqrt(max(n2 - 0.0, 0.0))
        for k in range(D):
            xout[k] = 0.0 + (rho / dist) * (xin[k] - 0.0)
        return False, STATUS_PROJECTED
    violated = _margin(G, rhs, K, D, xin) < 0.0
    cand, best = vec[_CAND], vec[_BEST]
    status, _ = _solve_ws(xin, G, rhs, K, U, D, W, idx, cand, best, xout, Gw, bw, ws, marg, WS_MAX)
    return violated, status


@jit_kernel
def _filter_swarm(q, p, a_nom, f, b, ints, reals, pr, use_grid, gs, sep, outs, work, solver):
    """Every UAV of swarm b (see :func:`swarm_kernel` for the arguments)."""
    paired, mate, agents, coop_u, coop_p, slot = ints
    alpha, bound, abound = reals
    a_out, u_out, active, corr, infeas, hmin = outs
    hits, cstart, cnt, clist, G, rhs, vec, fit, res, table, pos, mark, outl, xorder = work
    ocon = outl[2:]
    xs = (xorder[b], pos, mark)
    D = q.shape[2]
    mode = SCAN
    if use_grid and _grid_usable(q, p, b, gs[0]):
        mode = GRID
    elif not use_grid and sort_by_x(q, p, b, xorder[b], pos):
        mode = SWEEP
    a_u, U_u, a_p = _class_values(paired, alpha, bound)
    Au, Ap = _abounds(f, b, paired, bound, abound)
    fld = velocity_field(q, p, b, paired, fit, res)
    alone = pr[_S.pair_alone] != 0.0
    far_uu = _far_of(pr, a_u, a_u, U_u, 0.0, Au, Au)
    far_up = _far_of(pr, a_u, a_p, U_u, 0.0, Au, Ap)
    if alone:  # the unpaired UAVs have no rows against paired ones
        for i in range(q.shape[1] + 1):
            cstart[i] = 0
    else:
        _contacts(q, p, b, paired, agents, alpha, bound, abound, pr, mode, gs, xs, sep, hits,
                  far_up, a_u, Au, fld, res, cstart, cnt, clist)  # fmt: skip
    rows = (paired, mate, agents, coop_u, coop_p, cstart, clist)
    prune = pr[_S.skip_far] != 0.0
    R2u = pr[_S.swarm_radius2]
    de, L = radius_table(R2u, far_uu, fld, table, q.shape[1]) if prune else (0.0, 0)
    # the unpaired UAVs at most e_t search with e_t for every other residual (table_t), the
    # few above it (the outliers) out to every residual, finding their rows for the others
    e_t, table_t, de_t, L_t = outlier_split(q, b, paired, res, R2u, far_uu, fld, table, de, L,
                                            prune and mode != SCAN, mode, gs, xs, sep, hits,
                                            outl)  # fmt: skip
    ctr = vec[_CTR]
    for i in range(q.shape[1]):
        U = bound[i]
        far_u, far_p = far_uu, far_up
        for k in range(D):
            ctr[k] = f[b, i, k] if paired[i] else 0.0
        if paired[i]:  # its own constants: its ball is around its flocking command
            cn = abound[i] - bound[i]
            if alone:
                far_u = _far_alone(pr, alpha[i], U, cn, abound[i], pr[_S.other_accel])
            else:
                far_u = _far_of(pr, alpha[i], a_u, U, cn, abound[i], Au)
            far_p = _far_of(pr, alpha[i], a_p, U, cn, abound[i], Ap)
        # out to where the skip drops every unpaired UAV
        if paired[i]:
            r2 = pr[_S.pair_radius2]
            if prune:
                r2 = shortened(r2, far_u, fld, res[i])
        elif not prune:
            r2 = R2u
        elif res[i] > e_t:  # an outlier: out to every residual
            r2 = tabulated(table, de, L, res[i])
        else:
            r2 = tabulated(table_t, de_t, L_t, res[i])
        K, h, ok = _uav_rows(q, p, b, i, rows, pr, far_u, far_p, U, r2, mode, gs, xs, sep, hits,
                             vec, G, rhs, ocon)  # fmt: skip
        violated, status = _solve_uav(a_nom, b, i, U, K, ok, vec, G, rhs, solver)
        hmin[b, i] = h
        x, xin = vec[_XOUT], vec[_XIN]
        dc = 0.0
        for k in range(D):
            a_out[b, i, k] = ctr[k] + x[k]
            dc += (x[k] - xin[k]) ** 2
            if slot[i] >= 0:
                u_out[b, slot[i], k] = x[k]
        corr[b, i] = np.sqrt(dc)
        active[b, i] = violated or status == STATUS_INFEASIBLE
        infeas[b, i] = status == STATUS_INFEASIBLE


@jit_kernel
def swarm_kernel(q, p, a_nom, f, ints, reals, pr, use_grid, gs, sep, outs, work, solver):
    """The swarm layer over every swarm: each UAV's filtered whole command.

    Args:
        q, p: (B, N, dim) positions and velocities; a_nom: (B, N, dim) nominal commands
            (flocking + pair term); f: (B, N, dim) flocking commands.
        ints: (paired (N,) bool, mate (N,) partner or -1, agents (M,), coop_u (N,) all True,
            coop_p (N,) the UAVs that share a paired UAV's rows (all, or with ``pair_alone``
            the paired ones), slot (N,) each UAV's agent column or -1).
        reals: (alpha (N,) brake, bound (N,) U_i, abound (N,) scratch).
        pr: :data:`SWARM` vector; use_grid, gs: three grids of q (GridArrays, fine to coarse;
            the same grid thrice is valid) and reach (1,), the largest r2 a grid search
            used (to be zeroed by the caller), to search, or not.
        sep: (B, N) each UAV's squared distance to its nearest non-partner UAV (zeros:
            unknown), for :func:`~.search.candidates` to skip searches shorter than it.
        outs: (a_out (B, N, dim), u_out (B, M, dim) the agents' x, active, correction,
            infeasible, barrier (B, N)).
        work: (hits (N + 1,), cstart (N + 1,), cnt (N,), clist (N M,), G (N, 3), rhs (N,),
            vec (VEC_ROWS, 3), fit (FIT_ROWS, 3), res (N,), table (RADIUS_LEVELS + 1,),
            pos (N,), mark (N // 64 + 2,) uint64 zeros, outl (table_t like table, hist
            (RADIUS_LEVELS + 1,) int, ostart (N + 1,), ocnt (N,), olist (any,) int: the
            outlier split's scratch), xorder (B, N): each swarm's UAVs in x order, kept
            across calls).
        solver: (W (4, 4, 4), idx (5,), Gw, bw, ws, marg) of :func:`~.kernels._solve_ws`.
    """
    for b in range(q.shape[0]):
        _filter_swarm(q, p, a_nom, f, b, ints, reals, pr, use_grid, gs, sep, outs, work, solver)
