"""Pair actions: the one input check behind every view, and the decode stage of a core step.

What counts as an action value is what :func:`~pairflock_env.config.arrays.real_array`
accepts (real numbers of any numeric dtype; bool, complex, strings and masked entries are
refused; finite values beyond float64 saturate, then the core clips every component to
[-1, 1], reported as ``action_clipped``).

Decoding (:func:`decode_pair_actions`) clips to [-1, 1] and scales by ``pair_accel_limit``,
giving the pair command u (m/s^2) of each paired UAV.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.config.arrays import real_array
from pairflock_env.kernels import all_finite, jit_kernel

__all__ = ["add_pair_command", "check_pair_actions", "decode_pair_actions"]


def check_pair_actions(
    actions: Any, num_swarms: int, n_agents: int, dim: int, agent_uavs: np.ndarray
) -> np.ndarray:
    """Pair actions as float64 (B, M, dim); (M, dim) is accepted when B = 1.

    Raises ``TypeError`` for non-real input and ``ValueError`` for another shape or a NaN/inf
    (naming the swarm, the agent and its UAV). Nothing is changed by a rejected call.
    """
    B, M, D = num_swarms, n_agents, dim
    a = real_array(actions, "actions")
    if a.shape != (B, M, D):
        if B == 1 and a.shape == (M, D):
            a = a[None]
        else:
            raise ValueError(f"actions have shape {a.shape}, expected ({B}, {M}, {D})")
    if not all_finite(a):
        bad = np.argwhere(~np.isfinite(a).all(axis=-1))[0]
        raise ValueError(
            f"actions contain NaN or inf (swarm {bad[0]}, agent {bad[1]}, UAV "
            f"{agent_uavs[bad[1]]}); actions must be finite"
        )
    return a


@jit_kernel
def _decode_kernel(actions, limit, u, clipped):
    for b in range(actions.shape[0]):
        for m in range(actions.shape[1]):
            out = False
            for k in range(actions.shape[2]):
                a = actions[b, m, k]
                out |= abs(a) > 1.0
                u[b, m, k] = min(max(a, -1.0), 1.0) * limit
            clipped[b, m] = out


def decode_pair_actions(actions: np.ndarray, accel_limit: float) -> tuple[np.ndarray, np.ndarray]:
    """Decode checked actions (B, M, dim) into the pair command.

    Returns:
        ``u`` (B, M, dim): each component clipped to [-1, 1] and scaled by ``accel_limit``
        (m/s^2); ``clipped`` (B, M) bool: some component of that agent's action was outside
        [-1, 1].
    """
    u = np.empty(actions.shape)
    clipped = np.empty(actions.shape[:2], np.bool_)
    _decode_kernel(actions, float(accel_limit), u, clipped)
    return u, clipped


@jit_kernel
def _add_kernel(acc, agents, u, out):
    for b in range(acc.shape[0]):
        for i in range(acc.shape[1]):
            for k in range(acc.shape[2]):
                out[b, i, k] = acc[b, i, k]
        for m in range(agents.shape[0]):
            for k in range(acc.shape[2]):
                out[b, agents[m], k] += u[b, m, k]


def add_pair_command(acc: np.ndarray, agent_uavs: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``acc`` (B, N, dim) with the pair command ``u`` (B, M, dim) added on the agents' rows
    ``agent_uavs`` (M,), as a new array: the flocking command plus f^x (eq. 11)."""
    out = np.empty(acc.shape)
    _add_kernel(acc, agent_uavs, u, out)
    return out
