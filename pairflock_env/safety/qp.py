"""Exact projection onto halfspaces intersected with a ball, in 1 to 3 dimensions.

The filter's per-agent problem is the small QCQP

    minimise ||u - u_nom||^2   subject to   g_k . u >= b_k  (k = 1..K),   ||u|| <= U

with unit normals g_k. It is solved exactly by enumerating active sets, which is cheap because
dim <= 3 and the filter passes only the few constraints that the bound does not already imply.

*Why enumeration is exact.* The objective is strictly convex, so the optimum u* is unique.
When the feasible set has an interior point (Slater), KKT multipliers exist at u*; by
Caratheodory's theorem for cones the linear part of the multiplier sum can be carried by a
set S of at most dim constraints with linearly independent normals. u* then also solves the
problem restricted to "g_k . u = b_k for k in S, ||u|| <= U", whose solution is closed-form:
with pi the projection of u_nom onto the affine set A_S and u0 the point of A_S nearest the
origin (u0 is orthogonal to pi - u0), it is pi when ||pi|| <= U, else the point of the disk
A_S cap ball (centre u0, radius sqrt(U^2 - ||u0||^2)) nearest pi. So u* is one of the
candidates; every candidate that satisfies all constraints is feasible, hence u* is the
feasible candidate nearest u_nom. No iteration count or step size is involved.

*Infeasible problems.* When no candidate is feasible, the filter maximises the smallest
constraint margin within the bound,

    t* = max_{||u|| <= U} min_k (g_k . u - b_k),

and returns the command nearest u_nom among those achieving it (the same projection with
b_k + t*). t* is found by enumeration as well: at an optimum the tight constraints S (at most
dim + 1, affinely independent normals) have equal margins, so u lies in the affine set
{(g_k - g_1) . u = b_k - b_1}; on that set the common margin g_1 . u - b_1 is maximised over
the ball in closed form (the set's nearest point to the origin, moved to the sphere along
the projection of g_1 onto the set's directions, or left in place when that projection is
zero). Each candidate lies in the ball, so its smallest margin is a lower bound of t*, and
the largest over all candidates is t*.

Tolerances: a constraint counts as satisfied within ``ftol = 1e-9 (1 + max(||u_nom||,
max_k |b_k|))`` (m/s^2), the ball within a relative 1e-12; a set of normals counts as dependent when a Cholesky pivot of
its Gram matrix falls below 1e-10 of its diagonal entry.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["STATUS_INFEASIBLE", "STATUS_NOMINAL", "STATUS_PROJECTED", "max_margin", "project"]

#: the nominal command satisfied every constraint and the bound (returned unchanged)
STATUS_NOMINAL = 0
#: the nominal command was projected onto the (non-empty) feasible set
STATUS_PROJECTED = 1
#: no command within the bound satisfies every constraint: the max-margin fallback was used
STATUS_INFEASIBLE = 2

_RANK_TOL = 1e-10
_BALL_TOL = 1e-12


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def _projection_candidate(un, G, b, idx, s, U, D, W, cand):
    """Candidate of active set idx[:s] (see the module docstring) into cand; False if none."""
    A, L, r, y, pi, u0 = W[0], W[1], W[2, 0], W[2, 1], W[2, 2], W[2, 3]
    for a in range(s):
        acc = b[idx[a]]
        for k in range(D):
            A[a, k] = G[idx[a], k]
            acc -= G[idx[a], k] * un[k]
        r[a] = acc
    if s > 0 and not _factor(A, s, D, L):
        return False
    _min_norm(A, s, D, L, r, y, pi)
    for k in range(D):
        pi[k] += un[k]
        r[k] = b[idx[k]] if k < s else 0.0
    _min_norm(A, s, D, L, r, y, u0)
    n_pi = 0.0
    n_u0 = 0.0
    for k in range(D):
        n_pi += pi[k] * pi[k]
        n_u0 += u0[k] * u0[k]
    U2 = U * U
    if n_pi <= U2:
        cand[:D] = pi[:D]
        return True
    if n_u0 > U2 * (1.0 + _BALL_TOL):
        return False
    rho = np.sqrt(max(U2 - n_u0, 0.0))
    dist = np.sqrt(max(n_pi - n_u0, 0.0))
    for k in range(D):
        cand[k] = u0[k] + (rho / dist) * (pi[k] - u0[k]) if dist > 0.0 else u0[k]
    return True


@njit(cache=True, nogil=True)
def _project(un, G, b, K, U, D, ftol, W, idx, cand, out):
    """Nearest feasible candidate to un into out; True if one exists."""
    best = np.inf
    for s in range(min(D, K) + 1):
        for a in range(s):
            idx[a] = a
        while True:
            if _projection_candidate(un, G, b, idx, s, U, D, W, cand):
                n2 = 0.0
                d2 = 0.0
                for k in range(D):
                    n2 += cand[k] * cand[k]
                    d2 += (cand[k] - un[k]) ** 2
                ok = d2 < best and n2 <= U * U * (1.0 + _BALL_TOL)
                if ok and _margin(G, b, K, D, cand) >= -ftol:
                    best = d2
                    out[:D] = cand[:D]
            if s == 0 or not _next_comb(idx, s, K):
                break
    return best < np.inf


@njit(cache=True, nogil=True)
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
    scale = rho / np.sqrt(n_c) if n_c > 1e-24 else 0.0
    for k in range(D):
        cand[k] = u0[k] + scale * c[k]
    return True


@njit(cache=True, nogil=True)
def _max_margin(G, b, K, U, D, W, idx, cand, out):
    """t* (module docstring) and a maximiser into out."""
    best = -np.inf
    for s in range(1, min(D + 1, K) + 1):
        for a in range(s):
            idx[a] = a
        while True:
            if _margin_candidate(G, b, idx, s, U, D, W, cand):
                t = _margin(G, b, K, D, cand)
                if t > best:
                    best = t
                    out[:D] = cand[:D]
            if not _next_comb(idx, s, K):
                break
    return best


@njit(cache=True, nogil=True)
def _solve(un, G, b, K, U, D, W, idx, cand, u_best, out):
    """The filter's QCQP for one agent; returns (status, t*) and writes the command to out.

    W: scratch (3, 4, 4); idx: (4,) int; cand, u_best: (3,). b is shifted in place by t*
    when the problem is infeasible (the caller's constraint buffer)."""
    n2 = 0.0
    for k in range(D):
        n2 += un[k] * un[k]
    scale = 1.0 + np.sqrt(n2)
    for k in range(K):
        scale = max(scale, 1.0 + abs(b[k]))
    ftol = 1e-9 * scale
    if n2 <= U * U and _margin(G, b, K, D, un) >= 0.0:
        out[:D] = un[:D]
        return STATUS_NOMINAL, np.inf
    if _project(un, G, b, K, U, D, ftol, W, idx, cand, out):
        return STATUS_PROJECTED, 0.0
    t = _max_margin(G, b, K, U, D, W, idx, cand, u_best)
    for k in range(K):
        b[k] += t
    if not _project(un, G, b, K, U, D, ftol, W, idx, cand, out):
        out[:D] = u_best[:D]  # the max-margin set is this one point (up to ftol)
    return (STATUS_INFEASIBLE if t < -ftol else STATUS_PROJECTED), t


def _check_problem(G, b, U, u_nom=None):
    G = np.ascontiguousarray(G, dtype=np.float64)
    b = np.array(b, dtype=np.float64).reshape(-1)
    if G.ndim != 2 or not 1 <= G.shape[1] <= 3 or G.shape[0] != b.shape[0]:
        raise ValueError(
            f"G has shape {G.shape} and b {b.shape}; expected (K, dim) and (K,) with dim 1-3"
        )
    if not (np.isfinite(G).all() and np.isfinite(b).all()):
        raise ValueError("G and b must be finite")
    if G.shape[0] and np.abs(np.linalg.norm(G, axis=1) - 1.0).max() > 1e-9:
        raise ValueError("the rows of G must be unit vectors (the margins are in units of b)")
    if not (np.isfinite(U) and U > 0):
        raise ValueError(f"U={U!r} is invalid: must be a finite number > 0")
    if u_nom is not None:
        u_nom = np.array(u_nom, dtype=np.float64).reshape(-1)
        if u_nom.shape != (G.shape[1],) or not np.isfinite(u_nom).all():
            raise ValueError(f"u_nom must be a finite vector of length {G.shape[1]}")
    return G, b, float(U), u_nom


def _scratch():
    return np.zeros((3, 4, 4)), np.zeros(4, np.int64), np.zeros(3), np.zeros(3)


def project(u_nom, G, b, U):
    """The command nearest ``u_nom`` with ``G @ u >= b`` and ``||u|| <= U`` (exact).

    Args:
        u_nom: (dim,) nominal command, dim in 1..3.
        G: (K, dim) unit constraint normals.  b: (K,) right-hand sides.  U: the bound (> 0).

    Returns:
        ``(u, status, t)``: the command, one of ``STATUS_NOMINAL`` / ``STATUS_PROJECTED`` /
        ``STATUS_INFEASIBLE``, and the largest achievable smallest margin t* when the
        problem needed the fallback (``inf`` when the nominal was feasible, 0 otherwise).
        When infeasible, ``u`` is the command nearest ``u_nom`` among those whose smallest
        margin is t*.
    """
    G, b, U, u_nom = _check_problem(G, b, U, u_nom)
    W, idx, cand, best = _scratch()
    out = np.zeros(3)
    D = G.shape[1]
    un = np.zeros(3)
    un[:D] = u_nom
    Gp = np.zeros((max(G.shape[0], 1), 3))
    Gp[: G.shape[0], :D] = G
    status, t = _solve(un, Gp, b.copy(), G.shape[0], U, D, W, idx, cand, best, out)
    return out[:D].copy(), int(status), float(t)


def max_margin(G, b, U):
    """``t* = max_{||u|| <= U} min_k (g_k . u - b_k)`` and a maximiser (exact enumeration).

    Returns ``(t, u)``; ``t = inf`` and ``u = 0`` when there is no constraint.
    """
    G, b, U, _ = _check_problem(G, b, U)
    D = G.shape[1]
    if G.shape[0] == 0:
        return np.inf, np.zeros(D)
    W, idx, cand, _ = _scratch()
    out = np.zeros(3)
    Gp = np.zeros((G.shape[0], 3))
    Gp[:, :D] = G
    t = _max_margin(Gp, b, G.shape[0], U, D, W, idx, cand, out)
    return float(t), out[:D].copy()
