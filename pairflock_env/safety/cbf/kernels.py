"""The safety filter's numba kernels: the exact per-agent QCQP (:mod:`.qp` explains it) and
the barrier constraints with the batched filter loop (:mod:`.barrier`, docs/safety.md).

They live in one module on purpose: numba's on-disk cache keys a compiled function on its
own source file only, so a kernel calling a jitted function from another file could keep
running a stale compiled copy of it after that file changed. The one call out is the grid
query ``within_radius`` of :mod:`pairflock_env.swarm.grid` (one neighbour search for the whole
project), as in the flocking passes: after editing ``swarm/grid.py``, clear the numba cache
(the ``__pycache__`` folders) before trusting a run of the filter on the grid.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pairflock_env.kernels import KernelParams
from pairflock_env.swarm.grid import within_radius

#: the barrier kernel's parameters (:class:`~pairflock_env.safety.cbf.params.SafetyParams`,
#: squared where the kernel compares squared distances; ``skip_far`` 1 drops the UAVs too
#: far to bind (:func:`_far`), 0 evaluates them all)
BARRIER = KernelParams(
    "Barrier",
    (
        "barrier_distance",
        "brake_accel",
        "other_accel",
        "sensing_radius2",
        "decay",
        "dt",
        "position_gain",
        "accel_limit",
        "reaction_time",
        "skip_far",
    ),
)
_B = BARRIER.index

#: the nominal command satisfied every constraint and the bound (returned unchanged)
STATUS_NOMINAL = 0
#: the nominal command was projected onto the (non-empty) feasible set
STATUS_PROJECTED = 1
#: no command within the bound satisfies every constraint: the max-margin fallback was used
#: (or, in the filter, the working set of a crowd reached WS_MAX constraints: see _solve_ws)
STATUS_INFEASIBLE = 2

_RANK_TOL = 1e-10
_BALL_TOL = 1e-12


# The solver is compiled without numba's reference counting (it never allocates: the
# caller passes all scratch), for the reason given at _constraints.
@njit(cache=True, nogil=True, _nrt=False, inline="always")
def _put(dst, src, D):
    """dst[:D] = src[:D] (a loop: a slice assignment would need numba's runtime)."""
    for k in range(D):
        dst[k] = src[k]


@njit(cache=True, nogil=True, _nrt=False)
def _factor(A, s, D, L):
    """Cholesky factor of the Gram matrix of the first s rows of A into L; False if the rows
    are (numerically) linearly dependent."""
    for a in range(s):
        for c in range(a + 1):
            acc = 0.0
            for k in range(D):
                acc += A[a, k] * A[c, k]
            L[a, c] = acc
    for a in range(s):
        orig = L[a, a]
        for c in range(a + 1):
            acc = L[a, c]
            for k in range(c):
                acc -= L[a, k] * L[c, k]
            if c < a:
                L[a, c] = acc / L[c, c]
            else:
                if not (acc > _RANK_TOL * orig) or orig <= 0.0:
                    return False
                L[a, a] = np.sqrt(acc)
    return True


@njit(cache=True, nogil=True, _nrt=False)
def _min_norm(A, s, D, L, r, y, z):
    """z = A^T (A A^T)^-1 r (first s rows of A, factor L from _factor); y is scratch."""
    for a in range(s):
        acc = r[a]
        for c in range(a):
            acc -= L[a, c] * y[c]
        y[a] = acc / L[a, a]
    for a in range(s - 1, -1, -1):
        acc = y[a]
        for c in range(a + 1, s):
            acc -= L[c, a] * y[c]
        y[a] = acc / L[a, a]
    for k in range(D):
        acc = 0.0
        for a in range(s):
            acc += A[a, k] * y[a]
        z[k] = acc


@njit(cache=True, nogil=True, _nrt=False)
def _next_comb(idx, s, K):
    """Advance idx[:s] to the next s-subset of range(K) in lexicographic order."""
    a = s - 1
    while a >= 0 and idx[a] == K - s + a:
        a -= 1
    if a < 0:
        return False
    idx[a] += 1
    for c in range(a + 1, s):
        idx[c] = idx[c - 1] + 1
    return True


@njit(cache=True, nogil=True, _nrt=False)
def _margin(G, b, K, D, u):
    """Smallest constraint margin min_k (g_k . u - b_k); +inf when K = 0."""
    m = np.inf
    for k in range(K):
        acc = -b[k]
        for j in range(D):
            acc += G[k, j] * u[j]
        if acc < m:
            m = acc
    return m


@njit(cache=True, nogil=True, _nrt=False)
def _feasible(G, b, K, D, u, ftol, hint):
    """Whether every margin of u is >= -ftol; checks constraint hint[0] first and stores
    the first violated one there (a candidate usually fails where the previous one did)."""
    h = hint[0]
    for i in range(K + 1 if K > 0 else 0):
        k = h if i == 0 else i - 1
        if i > 0 and k == h:
            continue
        acc = -b[k]
        for j in range(D):
            acc += G[k, j] * u[j]
        if acc < -ftol:
            hint[0] = k
            return False
    return True


@njit(cache=True, nogil=True, _nrt=False)
def _projection_candidate(un, G, b, idx, s, U, D, W, cand):
    """Candidate of active set idx[:s] (module docstring) into cand. Returns 0 (none), 1 (a
    candidate) or 2 (a candidate whose KKT multipliers are all >= 0: if it is feasible, it
    is the optimum)."""
    A, L, r, y, pi, u0, y1 = W[0], W[1], W[2, 0], W[2, 1], W[2, 2], W[2, 3], W[3, 0]
    for a in range(s):
        acc = b[idx[a]]
        for k in range(D):
            A[a, k] = G[idx[a], k]
            acc -= G[idx[a], k] * un[k]
        r[a] = acc
    if s > 0 and not _factor(A, s, D, L):
        return 0
    _min_norm(A, s, D, L, r, y1, pi)  # pi = un + A^T y1: y1 are the multipliers off the ball
    for k in range(D):
        pi[k] += un[k]
        r[k] = b[idx[k]] if k < s else 0.0
    _min_norm(A, s, D, L, r, y, u0)  # u0 = A^T y
    n_pi = 0.0
    n_u0 = 0.0
    for k in range(D):
        n_pi += pi[k] * pi[k]
        n_u0 += u0[k] * u0[k]
    U2 = U * U
    mu = 0.0
    if n_pi <= U2:
        _put(cand, pi, D)
    else:
        if n_u0 > U2 * (1.0 + _BALL_TOL):
            return 0
        rho = np.sqrt(max(U2 - n_u0, 0.0))
        dist = np.sqrt(max(n_pi - n_u0, 0.0))
        if rho <= 0.0 or dist <= 0.0:
            _put(cand, u0, D)
            return 1
        for k in range(D):
            cand[k] = u0[k] + (rho / dist) * (pi[k] - u0[k])
        mu = dist / rho - 1.0  # ball multiplier; the linear ones are then y1 + mu y
    for a in range(s):
        if y1[a] + mu * y[a] < 0.0:
            return 1
    return 2


@njit(cache=True, nogil=True, _nrt=False)
def _project(un, G, b, K, U, D, ftol, W, idx, cand, out):
    """Nearest feasible candidate to un into out; True if one exists. Stops at the first
    feasible candidate with non-negative multipliers (the unique KKT point)."""
    best = np.inf
    hint = idx[4:5]  # idx[:s] holds the subset, s <= 3 here
    hint[0] = 0
    for s in range(min(D, K) + 1):
        for a in range(s):
            idx[a] = a
        while True:
            kind = _projection_candidate(un, G, b, idx, s, U, D, W, cand)
            if kind > 0:
                n2 = 0.0
                d2 = 0.0
                for k in range(D):
                    n2 += cand[k] * cand[k]
                    d2 += (cand[k] - un[k]) ** 2
                ok = (d2 < best or kind == 2) and n2 <= U * U * (1.0 + _BALL_TOL)
                if ok and _feasible(G, b, K, D, cand, ftol, hint):
                    best = d2
                    _put(out, cand, D)
                    if kind == 2:
                        return True
            if s == 0 or not _next_comb(idx, s, K):
                break
    return best < np.inf


@njit(cache=True, nogil=True, _nrt=False)
def _margin_candidate(G, b, idx, s, U, D, W, cand):
    """Maximiser of the common margin of idx[:s] over the ball (module docstring)."""
    A, L, r, y, c, u0 = W[0], W[1], W[2, 0], W[2, 1], W[2, 2], W[2, 3]
    i0 = idx[0]
    h = s - 1
    for a in range(h):
        r[a] = b[idx[a + 1]] - b[i0]
        for k in range(D):
            A[a, k] = G[idx[a + 1], k] - G[i0, k]
    if h > 0 and not _factor(A, h, D, L):
        return False
    _min_norm(A, h, D, L, r, y, u0)
    for a in range(h):
        acc = 0.0
        for k in range(D):
            acc += A[a, k] * G[i0, k]
        r[a] = acc
    _min_norm(A, h, D, L, r, y, c)
    n_u0 = 0.0
    n_c = 0.0
    for k in range(D):
        c[k] = G[i0, k] - c[k]
        n_u0 += u0[k] * u0[k]
        n_c += c[k] * c[k]
    if n_u0 > U * U * (1.0 + _BALL_TOL):
        return False
    rho = np.sqrt(max(U * U - n_u0, 0.0))
    # with h = D independent differences the affine set is the point u0 (c is rounding noise)
    scale = rho / np.sqrt(n_c) if h < D and n_c > 1e-24 else 0.0
    n2 = 0.0
    for k in range(D):
        cand[k] = u0[k] + scale * c[k]
        n2 += cand[k] * cand[k]
    return n2 <= U * U * (1.0 + _BALL_TOL)  # a candidate outside the ball bounds nothing


@njit(cache=True, nogil=True, _nrt=False)
def _margin_above(G, b, K, D, u, floor, hint):
    """Smallest margin of u, or -inf as soon as one margin is <= floor (constraint hint[0]
    first, as in _feasible)."""
    h = hint[0]
    m = np.inf
    for i in range(K + 1 if K > 0 else 0):
        k = h if i == 0 else i - 1
        if i > 0 and k == h:
            continue
        acc = -b[k]
        for j in range(D):
            acc += G[k, j] * u[j]
        if acc <= floor:
            hint[0] = k
            return -np.inf
        m = min(m, acc)
    return m


@njit(cache=True, nogil=True, _nrt=False)
def _max_margin(G, b, K, U, D, W, idx, cand, out):
    """t* (module docstring) and a maximiser into out."""
    best = -np.inf
    hint = idx[4:5]  # idx[:s] holds the subset, s <= 4 here
    hint[0] = 0
    for s in range(1, min(D + 1, K) + 1):
        for a in range(s):
            idx[a] = a
        while True:
            if _margin_candidate(G, b, idx, s, U, D, W, cand):
                t = _margin_above(G, b, K, D, cand, best, hint)
                if t > best:
                    best = t
                    _put(out, cand, D)
            if not _next_comb(idx, s, K):
                break
    return best


@njit(cache=True, nogil=True, _nrt=False)
def _solve(un, G, b, K, U, D, W, idx, cand, u_best, out, ftol=-1.0):
    """The filter's QCQP for one agent; returns (status, t*) and writes the command to out.

    W: scratch (4, 4, 4); idx: (5,) int; cand, u_best: (3,). b is shifted in place by t*
    when the problem is infeasible (the caller's constraint buffer). ``ftol`` < 0: the
    tolerance of these constraints (module docstring of :mod:`.qp`); :func:`_solve_ws`
    passes the one of the whole problem."""
    n2 = 0.0
    for k in range(D):
        n2 += un[k] * un[k]
    if ftol < 0.0:
        ftol = _ftol(un, b, K, D)
    if n2 <= U * U and _margin(G, b, K, D, un) >= 0.0:
        _put(out, un, D)
        return STATUS_NOMINAL, np.inf
    hopeless = False  # a constraint asking for more than U along a unit normal
    for k in range(K):
        hopeless |= b[k] > U + ftol
    if not hopeless and _project(un, G, b, K, U, D, ftol, W, idx, cand, out):
        return STATUS_PROJECTED, 0.0
    t = _max_margin(G, b, K, U, D, W, idx, cand, u_best)
    for k in range(K):
        b[k] += t
    if not _project(un, G, b, K, U, D, ftol, W, idx, cand, out):
        _put(out, u_best, D)  # the max-margin set is this one point (up to ftol)
    return (STATUS_INFEASIBLE if t < -ftol else STATUS_PROJECTED), t


@njit(cache=True, nogil=True, _nrt=False)
def _ftol(un, b, K, D):
    """Constraint tolerance 1e-9 (1 + max(||un||, max_k |b_k|)) (m/s^2)."""
    n2 = 0.0
    for k in range(D):
        n2 += un[k] * un[k]
    scale = 1.0 + np.sqrt(n2)
    for k in range(K):
        scale = max(scale, 1.0 + abs(b[k]))
    return 1e-9 * scale


#: more constraints than this are solved on a working set of them (:func:`_solve_ws`)
WS_DIRECT = 16
#: the filter's working set stops growing here (the step is then reported infeasible)
WS_MAX = 32
#: constraints added to the working set per round (the most violated first)
WS_ADD = 4


@njit(cache=True, nogil=True, _nrt=False)
def _solve_ws(un, G, b, K, U, D, W, idx, cand, u_best, out, Gw, bw, ws, marg, cap):
    """:func:`_solve` for many constraints, in time bounded by ``cap``. Up to WS_DIRECT
    constraints it is :func:`_solve`. Beyond, it solves on a working set (first the WS_DIRECT
    least satisfied by ``un``), checks the answer against all K, adds the WS_ADD most
    violated and solves again. That is exact: a working set's optimum that satisfies every
    constraint is the optimum, and a max-margin point whose margin over all K is its set's
    t* attains t* (t* of a subset is an upper bound). Enumeration costs about K^(D+1), so a
    working set that would grow beyond ``cap`` ends the search: the last command (within
    the ball) is returned with STATUS_INFEASIBLE and its margin over all K.

    Gw (cap + WS_ADD, 3), bw, ws (int) (cap + WS_ADD,) and marg (K,) are scratch; b is not
    changed."""
    if K <= WS_DIRECT:
        return _solve(un, G, b, K, U, D, W, idx, cand, u_best, out)
    n2 = 0.0
    for k in range(D):
        n2 += un[k] * un[k]
    ftol = _ftol(un, b, K, D)  # the whole problem's, for every subset too
    low = np.inf
    for k in range(K):
        acc = -b[k]
        for j in range(D):
            acc += G[k, j] * un[j]
        marg[k] = acc
        low = min(low, acc)
    if n2 <= U * U and low >= 0.0:
        _put(out, un, D)
        return STATUS_NOMINAL, np.inf
    kw = _ws_add(marg, K, ws, 0, WS_DIRECT, np.inf)
    while True:
        for a in range(kw):
            bw[a] = b[ws[a]]
            for j in range(3):
                Gw[a, j] = G[ws[a], j]
        status, t = _solve(un, Gw, bw, kw, U, D, W, idx, cand, u_best, out, ftol)
        need = t - ftol if status == STATUS_INFEASIBLE else -ftol
        for k in range(K):
            acc = -b[k]
            for j in range(D):
                acc += G[k, j] * out[j]
            marg[k] = acc
        grown = _ws_add(marg, K, ws, kw, WS_ADD, need)
        if grown == kw:
            return status, t
        if grown > cap:
            return STATUS_INFEASIBLE, _margin(G, b, K, D, out)
        kw = grown


@njit(cache=True, nogil=True, _nrt=False)
def _ws_add(marg, K, ws, kw, n, below):
    """Append to ws[:kw] up to n constraints not in it whose margin is < ``below``, the
    smallest first; returns the new count."""
    for _ in range(n):
        best = -1
        for k in range(K):
            if marg[k] < below and (best < 0 or marg[k] < marg[best]):
                seen = False
                for a in range(kw):
                    seen |= ws[a] == k
                if not seen:
                    best = k
        if best < 0:
            break
        ws[kw] = best
        kw += 1
    return kw


@njit(cache=True, nogil=True, _nrt=False)
def _sigma_min(e, v, eps, a, T, c, lam, tau=0.0):
    """(H, sigma_min): the barrier and the smallest line-of-sight relative acceleration
    that keeps H(next) >= (1 - lam) H, E(next) >= min(E, 0) and e(next) >= min(e, 0)
    (module docstring). With a reaction time tau the barrier is taken at the gap left
    after coasting tau at the current range rate, E = e + tau v (tau = 0: E = e)."""
    beta = (c - 0.5) * a * T
    E = e + tau * v
    H = np.sign(E) * np.sqrt(2.0 * a * abs(E)) + v + beta
    K = v - eps + beta - (1.0 - lam) * H
    cT2 = c * T * T
    g = cT2 + tau * T  # d E(next) / d sigma
    s0 = -(E + T * v - tau * eps) / g  # sigma at which the projected next E is 0
    R0 = -(T * s0 + K)
    Ac = a * c * T + a * tau  # a g / T (written so that tau = 0 repeats the plain barrier)
    R = abs(R0)
    den = T * (R + Ac + np.sqrt(Ac * (2.0 * R + Ac)))
    z = R * R / den if den > 0.0 else 0.0  # den = 0 only for R = 0 with Ac underflowed
    s_b = s0 + z if R0 >= 0.0 else s0 - z
    s_a = s0 + min(E, 0.0) / g
    s_e = -(e + T * v) / cT2 + min(e, 0.0) / cT2  # the distance: e(next) >= min(e, 0)
    return H, max(s_a, s_b, s_e)


#: relative and absolute slack of :func:`_far` over the rounding of the exact threshold
_FAR_REL = 1e-6
_FAR_ABS = 1e-9
#: :func:`_far` pads S by _FAR_ROUND eps (R_s + (T + 2 tau) W + tau eps_m) / (c T^2): the
#: rounding of sigma_min, whose terms reach (e + T v) / (c T^2) before they cancel
_FAR_ROUND = 64.0 * 2.0**-52


@njit(cache=True, nogil=True, _nrt=False, inline="always")  # see _constraints
def _far_radius(W, far):
    """The distance from which :func:`_far` skips a UAV closing at relative speed W at
    most; non-decreasing in W, in floating point too (each step is)."""
    Ds, T, tau, lam, beta, g, S, epsm, k1, k2, _, k3, R, _, _ = far
    S = S + k3 * (R + (T + 2.0 * tau) * W + tau * epsm)  # covers the rounding of sigma_min
    Q = max(lam * (W - beta) + T * S + epsm, 0.0)
    Dm = (T + tau) * W + tau * epsm + g * S
    Y = tau * W + Q * Q * k1 + Dm * k2
    return Ds + Y * (1.0 + _FAR_REL) + _FAR_ABS


@njit(cache=True, nogil=True, _nrt=False, inline="always")  # see _constraints
def _far(d2, w2, far):
    """Whether a UAV at squared distance d2 and squared relative speed w2 is too far for its
    constraint to bind, i.e. its right-hand side is <= -U whatever the direction, without
    computing the barrier (docs/safety.md, "Skipping far UAVs"). ``far``: :func:`_far_terms`
    of the agent for that kind of UAV; only for a UAV within the sensing radius (the pad for
    rounding is bounded with R_s)."""
    r = _far_radius(np.sqrt(w2), far)
    return d2 >= r * r


@njit(cache=True, nogil=True, _nrt=False, inline="always")
def _far_constants(Ds, T, c, lam, tau, a, S, Sa, R, share):
    """The constants of :func:`_far` (and of a row of :func:`_constrain_one`) for a barrier
    at distance Ds with alpha_ij = a whose row is dropped when sigma_min <= -S, where
    |a_i - a_j| <= Sa (the rotation term), the agent's share of the relative condition is
    ``share`` and R bounds the distances the skip is used at (its rounding pad)."""
    den = 2.0 * a * lam * lam  # underflows only for a subnormal alpha_ij: then skip none
    cT2 = c * T * T
    return (
        Ds, T, tau, lam, (c - 0.5) * a * T, cT2 + tau * T, S,
        2.0 * (1.0 - c) * T * Sa, 1.0 / den if den > 0.0 else np.inf, 2.0 / lam, a,
        _FAR_ROUND / cT2 if cT2 > 0.0 else np.inf, R, Sa, share,
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, inline="always")
def _far_terms(pr, fn, coop):
    """:func:`_far_constants` of an agent of the pair filter whose flocking command has norm
    fn, against an unpaired UAV (``coop`` False) or another filtered one (True); entry 6 is
    S, the bound on the relative acceleration, and entry 10 the barrier's alpha_ij."""
    Ds, alpha, A_o = pr[_B.barrier_distance], pr[_B.brake_accel], pr[_B.other_accel]
    lam, T, c, U = pr[_B.decay], pr[_B.dt], pr[_B.position_gain], pr[_B.accel_limit]
    tau = pr[_B.reaction_time]
    # the barrier's alpha_ij, and S: the constraint is dropped when sigma_min <= -S
    a = 2.0 * alpha if coop else alpha - A_o
    S = 2.0 * (fn + U) if coop else fn + U + A_o
    # alpha / (alpha + alpha) is 0.5 exactly: each of two filtered UAVs takes half
    share = alpha / a if coop else 1.0
    return _far_constants(Ds, T, c, lam, tau, a, S, S, np.sqrt(pr[_B.sensing_radius2]), share)


@njit(cache=True, nogil=True, _nrt=False, inline="always")  # see _constraints
def _constrain_one(
    b, i, j, mate, q, p, f, kind_of, coop, Ds, A_o, R2, lam, T, c, tau, U, G, rhs, n, K, hmin,
    far_o, far_c, prune, Rs2,
):  # fmt: skip
    """Agent i's constraint against UAV j, appended to G, rhs when it binds; returns (K, hmin,
    ok), ok False for a non-finite pair (the caller then stops). UAVs other than ``mate``
    at squared distance >= R2 are left out; ``Rs2`` is the sensing radius squared, within
    which the far-UAV skip applies.

    Its variable is x = a_i - f (f: the centre of its ball ||x|| <= U). j's row uses
    ``far_c`` where ``kind_of[j]``, else ``far_o`` (:func:`_far_constants`: alpha_ij, the
    rotation bound and i's share). A j that filters too (``coop[j]``) takes the rest of the
    relative condition: i asks n . a_i >= share sigma_min. Else j is assumed to accelerate
    towards i at most A_o and i asks n . a_i >= sigma_min + A_o. The pair filter passes its
    agents as both ``kind_of`` and ``coop`` (share 1/2); the swarm layer
    (:mod:`.swarm`) has every UAV filter, weighted by brake capacity."""
    D = q.shape[2]
    d2 = 0.0
    w2 = 0.0
    for k in range(D):
        d2 += (q[b, i, k] - q[b, j, k]) ** 2
        w2 += (p[b, i, k] - p[b, j, k]) ** 2
    if not (np.isfinite(d2) and np.isfinite(w2)):
        return K, hmin, False
    if d2 >= R2 and j != mate:
        return K, hmin, True
    kind = far_c if kind_of[j] else far_o
    if prune and d2 < Rs2 and _far(d2, w2, kind):  # the partner beyond R_s: always evaluated
        return K, hmin, True
    d = np.sqrt(d2)
    for k in range(D):
        n[k] = (q[b, i, k] - q[b, j, k]) / d if d > 0.0 else 0.0
    if d == 0.0:  # coincident: any direction, opposite for the two UAVs
        n[0] = 1.0 if i < j else -1.0
    v = 0.0
    nf = 0.0
    for k in range(D):
        v += n[k] * (p[b, i, k] - p[b, j, k])
        nf += n[k] * f[k]
    a = kind[10]  # the barrier's alpha_ij
    eps = 0.0
    if c < 1.0:  # rotation of n within the step (docs/safety.md)
        amax = kind[13]  # the bound on the relative acceleration
        den = d + min(d, Ds)  # 0 for coincident UAVs: n may then turn by anything (cap 2)
        geo = min(2.0, 2.0 * T * (np.sqrt(w2) + c * T * amax) / den) if den > 0.0 else 2.0
        eps = (1.0 - c) * T * amax * geo
    H, smin = _sigma_min(d - Ds, v, eps, a, T, c, lam, tau)
    hmin = min(hmin, H)
    need = kind[14] * smin if coop[j] else smin + A_o
    if need - nf <= -U:
        return K, hmin, True  # implied by ||u|| <= U
    for k in range(D):
        G[K, k] = n[k]
    rhs[K] = need - nf
    return K + 1, hmin, True


# Called once per UAV and agent, so compiled without numba's reference counting (it never
# allocates): the count updates numba adds around a call taking arrays cost several times the
# call itself (as in pairflock_env.swarm.grid).
@njit(cache=True, nogil=True, _nrt=False)
def _constraints(b, i, mate, q, p, f, coop, pr, G, rhs, n, grid, g, hits, pt, vo, vc, M):
    """Fill G, rhs with agent i's non-redundant constraints; return (count, min H, ok).
    UAV ``mate`` (the partner; -1: none) is constrained at any distance, the others within
    the sensing radius (squared: R2).

    ``grid`` True: the candidates are the UAVs the neighbour grid ``g`` finds within the
    sensing radius (``within_radius``, in increasing index order, into ``hits``),
    with the partner merged in at its index: the same UAVs in the same order as the scan of
    all N, so the same constraints (the caller uses it only for a swarm the grid holds whose
    state is finite and bounded, where the scan would skip exactly the UAVs out of range).
    With the far-UAV skip on, both look only out to where :func:`_far` would skip every UAV
    whatever its speed, given ``vo`` and ``vc`` (bounds on the speeds of the unpaired and the
    filtered UAVs, inf if unknown) and ``M`` (the number of filtered UAVs): the
    UAVs left out are ones the skip would drop, so the constraints are the same."""
    N, D = q.shape[1], q.shape[2]
    Ds, A_o, R2 = pr[_B.barrier_distance], pr[_B.other_accel], pr[_B.sensing_radius2]
    lam, T, c, U = pr[_B.decay], pr[_B.dt], pr[_B.position_gain], pr[_B.accel_limit]
    tau = pr[_B.reaction_time]
    prune = pr[_B.skip_far] != 0.0
    K = 0
    hmin = np.inf
    fn = 0.0
    for k in range(D):
        fn += f[k] * f[k]
    fn = np.sqrt(fn)
    if not np.isfinite(fn):
        return 0, np.nan, False
    far_o, far_c = _far_terms(pr, fn, False), _far_terms(pr, fn, True)
    w = 0.0
    for k in range(D):
        pt[k] = q[b, i, k]
        w += p[b, i, k] * p[b, i, k]
    r2 = R2
    if prune:  # look only out to where the skip takes every UAV: W <= |p_i| + |p_j|
        wi = np.sqrt(w)
        r = _far_radius((wi + vo) * (1.0 + 1e-9), far_o)  # the 1e-9: rounding of |p_i - p_j|
        others = M - 1 - (1 if mate >= 0 and coop[mate] else 0)  # filtered, not i or mate
        if others > 0:
            r = max(r, _far_radius((wi + vc) * (1.0 + 1e-9), far_c))
        if r * r < R2:  # not when a speed is not finite (r is then inf)
            r2 = r * r
    nc = _with_partner(hits, within_radius(q, b, pt, r2, i, g, hits), mate) if grid else N
    for t in range(nc):
        j = hits[t] if grid else t
        if j == i:
            continue
        K, hmin, ok = _constrain_one(
            b, i, j, mate, q, p, f, coop, coop, Ds, A_o, r2, lam, T, c, tau, U, G, rhs,
            n, K, hmin, far_o, far_c, prune, R2,
        )  # fmt: skip
        if not ok:
            return 0, np.nan, False
    return K, hmin, True


@njit(cache=True, nogil=True, _nrt=False)
def _with_partner(hits, nh, mate):
    """Insert ``mate`` (>= 0) into the increasing indices hits[:nh] unless it is there;
    returns the new count (hits has room for one more)."""
    if mate < 0:
        return nh
    t = nh
    while t > 0 and hits[t - 1] > mate:
        t -= 1
    if t > 0 and hits[t - 1] == mate:
        return nh
    for s in range(nh, t, -1):
        hits[s] = hits[s - 1]
    hits[t] = mate
    return nh + 1


@njit(cache=True, nogil=True, _nrt=False)
def _scan_free(q, p, b):
    """Whether a search of swarm b may skip UAVs the scan of all N would visit: every
    position and velocity is finite with |p| < 1e150, so that no skipped pair could have
    made the scan stop at a non-finite distance or speed."""
    for j in range(q.shape[1]):
        for k in range(q.shape[2]):
            if not (np.isfinite(q[b, j, k]) and abs(p[b, j, k]) < 1e150):
                return False
    return True


@njit(cache=True, nogil=True, _nrt=False)
def _grid_usable(q, p, b, g):
    """Whether swarm b may take its candidates from the grid: the grid holds it, and
    :func:`_scan_free`."""
    return g.ok[b] and _scan_free(q, p, b)


@njit(cache=True, nogil=True, _nrt=False)
def _speed_bounds(p, b, coop):
    """The largest speed of swarm b's unpaired UAVs and of its filtered ones (each bounds,
    with an agent's own speed, the relative speed of that kind of UAV); inf if a velocity is
    not finite."""
    vo = 0.0
    vc = 0.0
    for j in range(p.shape[1]):
        s2 = 0.0
        for k in range(p.shape[2]):
            s2 += p[b, j, k] * p[b, j, k]
        if not np.isfinite(s2):
            return np.inf, np.inf
        if coop[j]:
            vc = max(vc, s2)
        else:
            vo = max(vo, s2)
    return np.sqrt(vo), np.sqrt(vc)


@njit(cache=True, nogil=True)
def _filter_kernel(
    q, p, f, un, agents, mates, coop, pr, use_grid, g, u, active, corr, infeas, hmin
):
    B, M, D = un.shape
    N = q.shape[1]
    hits = np.zeros(max(N, 1), np.int64)
    pt = np.zeros(3)
    U = pr[_B.accel_limit]
    G = np.zeros((max(N, 1), 3))
    rhs = np.zeros(max(N, 1))
    W = np.zeros((4, 4, 4))
    idx = np.zeros(5, np.int64)
    cand = np.zeros(3)
    best = np.zeros(3)
    uin = np.zeros(3)
    uo = np.zeros(3)
    nv = np.zeros(3)
    Gw = np.zeros((WS_MAX + WS_ADD, 3))
    bw = np.zeros(WS_MAX + WS_ADD)
    ws = np.zeros(WS_MAX + WS_ADD, np.int64)
    marg = np.zeros(max(N, 1))
    for b in range(B):
        grid = use_grid and _grid_usable(q, p, b, g)
        # only the skip uses the speed bounds
        vo, vc = _speed_bounds(p, b, coop) if pr[_B.skip_far] != 0.0 else (np.inf, np.inf)
        for m in range(M):
            K, h, ok = _constraints(
                b, agents[m], mates[m], q, p, f[b, m], coop, pr, G, rhs, nv, grid, g, hits, pt,
                vo, vc, M,
            )  # fmt: skip
            hmin[b, m] = h
            for k in range(D):
                uin[k] = un[b, m, k]
            violated = True
            if ok:
                violated = _margin(G, rhs, K, D, uin) < 0.0
                status, _ = _solve_ws(
                    uin, G, rhs, K, U, D, W, idx, cand, best, uo, Gw, bw, ws, marg, WS_MAX
                )
            else:  # non-finite state (a diverged swarm): pass the command through
                status = STATUS_INFEASIBLE
                _put(uo, uin, D)
            dc = 0.0
            for k in range(D):
                u[b, m, k] = uo[k]
                dc += (uo[k] - uin[k]) ** 2
            corr[b, m] = np.sqrt(dc)
            active[b, m] = violated or status == STATUS_INFEASIBLE
            infeas[b, m] = status == STATUS_INFEASIBLE
