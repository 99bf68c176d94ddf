"""Virtual-leader trajectories (q_gamma, p_gamma of eq. 19).

A trajectory is any object with ``state(t) -> (q, p)`` where ``t`` has shape (B,) (the sim
time of each swarm) and ``q``, ``p`` have shape (B, dim). Trajectories are pure functions of
time, so a batch of swarms at different times (after auto-resets) is handled naturally.
New trajectory types register in :data:`LEADERS` and are picked by ``config.leader``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from .config import PairFlockConfig

__all__ = ["LeaderTrajectory", "ConstantVelocityLeader", "LEADERS", "make_leader"]


class LeaderTrajectory(Protocol):
    dim: int

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position and velocity, each (B, dim), at times ``t`` (B,)."""
        ...


class ConstantVelocityLeader:
    """q(t) = q0 + v t, p(t) = v (Sec. VI-A)."""

    def __init__(self, position: np.ndarray, velocity: np.ndarray) -> None:
        self.q0 = np.asarray(position, dtype=np.float64)
        self.v = np.asarray(velocity, dtype=np.float64)
        self.dim = self.q0.shape[0]

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=np.float64)[:, None]
        q = self.q0 + t * self.v
        p = np.broadcast_to(self.v, q.shape).copy()
        return q, p


LEADERS: dict[str, Callable[[PairFlockConfig], LeaderTrajectory]] = {
    "constant_velocity": lambda cfg: ConstantVelocityLeader(
        cfg.vector("leader_position"), cfg.vector("leader_velocity")
    ),
}


def make_leader(config: PairFlockConfig) -> LeaderTrajectory:
    return LEADERS[config.leader](config)
