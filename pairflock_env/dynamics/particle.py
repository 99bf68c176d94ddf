"""The particle model of eq. 1: a double integrator q' = p, p' = u."""

from __future__ import annotations

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.kernels import jit_kernel

__all__ = ["ParticleModel"]


class ParticleModel:
    """Double integrator under a held acceleration.

    ``integrator="semi_implicit"`` (symplectic Euler, the paper's): per physics step h,
    p <- p + u h, then q <- q + p h. ``integrator="exact"``: q <- q + p h + u h^2 / 2,
    p <- p + u h, the exact solution for a constant u (substeps then change nothing).
    """

    name = "particle"

    def __init__(self, config: PairFlockConfig, num_swarms: int) -> None:
        self.h = config.physics_dt
        self.substeps = config.substeps
        self.exact = config.integrator == "exact"

    def reset_rows(self, rows: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
        pass

    def advance(self, q: np.ndarray, p: np.ndarray, a_des: np.ndarray) -> None:
        if a_des.shape != q.shape:
            return self._advance_numpy(q, p, a_des)
        _advance_kernel(q, p, a_des, self.h, self.substeps, self.exact)

    def _advance_numpy(self, q: np.ndarray, p: np.ndarray, a_des: np.ndarray) -> None:
        h = self.h
        if self.exact:
            T = h * self.substeps
            q += p * T + (0.5 * T * T) * a_des
            p += a_des * T
            return
        dv = a_des * h
        for _ in range(self.substeps):
            p += dv
            q += p * h

    def info(self) -> dict[str, np.ndarray]:
        return {}


@jit_kernel
def _advance_kernel(q, p, a, h, substeps, exact):
    """:meth:`ParticleModel.advance` element by element (the same operations, in order)."""
    T = h * substeps
    c = 0.5 * T * T
    for b in range(q.shape[0]):
        for i in range(q.shape[1]):
            for k in range(q.shape[2]):
                if exact:
                    q[b, i, k] += p[b, i, k] * T + c * a[b, i, k]
                    p[b, i, k] += a[b, i, k] * T
                    continue
                dv = a[b, i, k] * h
                pe, qe = p[b, i, k], q[b, i, k]
                for _ in range(substeps):
                    pe += dv
                    qe += pe * h
                p[b, i, k], q[b, i, k] = pe, qe
