"""Pair quantities of Sec. IV, written once and used by observations, infos, metrics and the
analytic controllers.

For a pair (A, B): y = q_B - q_A (eq. 21), y' = p_B - p_A (eq. 22),
e = y.y - d_m^2 (eq. 24), e' = 2 y.y' (eq. 25), s = c e + e' (eq. 26).

Every function works on arrays whose last axis is the spatial one, with any leading axes.
The quantities are even in (y, y'), so they are the same whether computed from A's view
(partner offset y) or from B's (partner offset -y).
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import jit_inline, jit_kernel

try:  # what np.einsum calls (same numbers), without its Python dispatch: ~1 us per call
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:  # pragma: no cover - another numpy layout
    _einsum = np.einsum

__all__ = [
    "agent_pair_state",
    "dot",
    "dot_axes",
    "pair_error",
    "pair_quantities",
    "sliding_surface",
    "square_error",
    "square_error_rate",
]


def dot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """x.y over the last (spatial) axis, shape (...)."""
    return _einsum("...k,...k->...", x, y)


def square_error(y: np.ndarray, d_m: np.ndarray | float) -> np.ndarray:
    """e = ||y||^2 - d_m^2 (eq. 24), in m^2."""
    return dot(y, y) - np.square(d_m)


def square_error_rate(y: np.ndarray, ydot: np.ndarray) -> np.ndarray:
    """e' = 2 y.y' (eq. 25), in m^2/s."""
    return 2.0 * dot(y, ydot)


def sliding_surface(
    y: np.ndarray, ydot: np.ndarray, d_m: np.ndarray | float, c: float
) -> np.ndarray:
    """s = c e + e' (eq. 26), in m^2/s."""
    return c * square_error(y, d_m) + square_error_rate(y, ydot)


def pair_error(y: np.ndarray, d_m: np.ndarray | float) -> np.ndarray:
    """||y|| - d_m, in m (positive when the pair is too far apart)."""
    return np.sqrt(dot(y, y)) - d_m


@jit_inline
def dot_axes(x0, x1, x2, y0, y1, y2, three):
    """x.y of two vectors given by their components (x2, y2 unused in 2-D), summed in the
    order numpy's einsum (:func:`dot`) sums them: x0 y0 + x1 y1 in 2-D, (x0 y0 + x2 y2) +
    x1 y1 in 3-D (its two-lane inner loop), so that a kernel gives :func:`dot`'s numbers."""
    if three:
        return (x0 * y0 + x2 * y2) + x1 * y1
    return x0 * y0 + x1 * y1


@jit_inline
def pair_quantities(y0, y1, y2, v0, v1, v2, d_m, c, three):
    """||y||, ||y|| - d_m and s = c (y.y - d_m^2) + 2 y.y' (eqs. 21-26) of one agent from its
    partner offset y and relative velocity y' = v (components; y.y computed once)."""
    yy = dot_axes(y0, y1, y2, y0, y1, y2, three)
    dist = np.sqrt(yy)
    return dist, dist - d_m, c * (yy - d_m * d_m) + 2.0 * dot_axes(y0, y1, y2, v0, v1, v2, three)


@jit_kernel
def _pair_state_kernel(q, p, agents, partners, d_m, c, dims, off, vel, out):
    three = len(dims) == 3
    for b in range(q.shape[0]):
        for m in range(agents.shape[0]):
            i, j = agents[m], partners[m]
            for k in range(q.shape[2]):
                off[b, m, k] = q[b, j, k] - q[b, i, k]
                vel[b, m, k] = p[b, j, k] - p[b, i, k]
            y, v = off[b, m], vel[b, m]
            res = pair_quantities(
                y[0], y[1], y[2] if three else 0.0, v[0], v[1], v[2] if three else 0.0,
                d_m[m], c, three,
            )  # fmt: skip
            out[0, b, m], out[1, b, m], out[2, b, m] = res


def agent_pair_state(
    q: np.ndarray,
    p: np.ndarray,
    agent_uavs: np.ndarray,
    partner_uavs: np.ndarray,
    d_m: np.ndarray,
    c: float,
) -> dict[str, np.ndarray]:
    """Every agent's true pair quantities, from positions and velocities q, p (B, N, dim).

    Args:
        agent_uavs, partner_uavs: (M,) each agent's UAV and its partner's.
        d_m: (M,) each agent's target distance (m); c: the surface slope of eq. 26 (1/s).

    Returns:
        dict of ``q``, ``p`` (the agents' own, (B, M, dim)), ``offset`` (y from the agent's
        view, (B, M, dim), m), ``velocity`` (y', m/s), and (B, M): ``pair_distance`` ||y||
        (m), ``pair_error`` ||y|| - d_m (m), ``sliding_surface`` s (m^2/s), each by
        :func:`pair_quantities` (the core's agent pass computes the same numbers).
    """
    q, p = np.asarray(q, dtype=np.float64), np.asarray(p, dtype=np.float64)
    B, _, D = q.shape
    M = len(agent_uavs)
    off, vel, out = np.empty((B, M, D)), np.empty((B, M, D)), np.empty((3, B, M))
    ia = np.asarray(agent_uavs, dtype=np.int64)
    ip = np.asarray(partner_uavs, dtype=np.int64)
    dm = np.ascontiguousarray(np.broadcast_to(np.asarray(d_m, dtype=np.float64), (M,)))
    _pair_state_kernel(q, p, ia, ip, dm, float(c), (0,) * D, off, vel, out)
    return {
        "q": q.take(ia, axis=1),
        "p": p.take(ia, axis=1),
        "offset": off,
        "velocity": vel,
        "pair_distance": out[0],
        "pair_error": out[1],
        "sliding_surface": out[2],
    }
