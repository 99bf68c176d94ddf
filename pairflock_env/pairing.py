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

__all__ = ["pair_error", "sliding_surface", "square_error", "square_error_rate"]


def _dot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.einsum("...k,...k->...", x, y)


def square_error(y: np.ndarray, d_m: np.ndarray | float) -> np.ndarray:
    """e = ||y||^2 - d_m^2 (eq. 24), in m^2."""
    return _dot(y, y) - np.square(d_m)


def square_error_rate(y: np.ndarray, ydot: np.ndarray) -> np.ndarray:
    """e' = 2 y.y' (eq. 25), in m^2/s."""
    return 2.0 * _dot(y, ydot)


def sliding_surface(
    y: np.ndarray, ydot: np.ndarray, d_m: np.ndarray | float, c: float
) -> np.ndarray:
    """s = c e + e' (eq. 26), in m^2/s."""
    return c * square_error(y, d_m) + square_error_rate(y, ydot)


def pair_error(y: np.ndarray, d_m: np.ndarray | float) -> np.ndarray:
    """||y|| - d_m, in m (positive when the pair is too far apart)."""
    return np.sqrt(_dot(y, y)) - d_m
