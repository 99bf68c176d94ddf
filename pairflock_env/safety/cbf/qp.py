"""Exact projection onto halfspaces intersected with a ball, in 1 to 3 dimensions.

The filter's per-agent problem is the small QCQP

    minimise ||u - u_nom||^2   subject to   g_k . u >= b_k  (k = 1..K),   ||u|| <= U

with unit normals g_k. It is solved exactly by enumerating active sets, which is cheap because
dim <= 3 and the filter passes only the constraints that the bound does not already imply.
With more than 16 of them it is solved on a working set: the 16 least satisfied, then the
most violated added until the answer satisfies all (exact; the filter stops at 32 and
reports such a step infeasible, so that a dense crowd cannot make a step take minutes).

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
max_k |b_k|))`` (m/s^2), the ball within a relative 1e-12; a set of normals counts as
dependent when a Cholesky pivot of its Gram matrix falls below 1e-10 of its diagonal entry.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.safety.cbf.kernels import (
    STATUS_INFEASIBLE,
    STATUS_NOMINAL,
    STATUS_PROJECTED,
    _max_margin,
    _solve_ws,
)

__all__ = ["STATUS_INFEASIBLE", "STATUS_NOMINAL", "STATUS_PROJECTED", "max_margin", "project"]


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
    return np.zeros((4, 4, 4)), np.zeros(5, np.int64), np.zeros(3), np.zeros(3)


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
    K = G.shape[0]
    Gp = np.zeros((max(K, 1), 3))
    Gp[:K, :D] = G
    n = K + 4  # working-set scratch, uncapped: exact for any K (docs in _kernels._solve_ws)
    Gw, bw, ws, marg = np.zeros((n, 3)), np.zeros(n), np.zeros(n, np.int64), np.zeros(max(K, 1))
    status, t = _solve_ws(un, Gp, b.copy(), K, U, D, W, idx, cand, best, out, Gw, bw, ws, marg, K)
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
