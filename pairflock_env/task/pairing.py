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

try:  # what np.einsum calls (same numbers), without its Python dispatch: ~1 us per call
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:  # pragma: no cover - another numpy layout
    _einsum = np.einsum

__all__ = [
    "agent_pair_state",
    "dot",
    "pair_error",
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
        (m), ``pair_error`` ||y|| - d_m (m), ``sliding_surface`` s (m^2/s).
    """
    # take: q[:, agent_uavs] (the same values, C-ordered) at a fifth of the cost
    qa, pa = q.take(agent_uavs, axis=1), p.take(agent_uavs, axis=1)
    off = q.take(partner_uavs, axis=1) - qa
    vel = p.take(partner_uavs, axis=1) - pa
    yy = dot(off, off)  # once for the distance and eq. 24 (the same numbers either way)
    dist = np.sqrt(yy)
    return {
        "q": qa,
        "p": pa,
        "offset": off,
        "velocity": vel,
        "pair_distance": dist,
        "pair_error": dist - d_m,
        # sliding_surface(off, vel, d_m, c) with y.y reused: c (y.y - d_m^2) + 2 y.y'
        "sliding_surface": c * (yy - np.square(d_m)) + 2.0 * dot(off, vel),
    }
