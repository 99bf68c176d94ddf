"""The decision-period hold of a learned policy: one implementation for the learning views
and the ``sb3:`` policy loader.

A learning interface decides every ``decision_period`` control steps
(:mod:`pairflock_env.interfaces`). In between, each row (a paired UAV) keeps its last policy
action, and every control step decodes that held action against the *fresh* physical
observation, so the pair frame and the feed-forward stay current. The views hold for a whole
decision inside one ``step``; the loader is called once per control step and carries the hold
in SB3's ``predict`` state. Both go through :class:`DecisionHold`, so training and evaluation
apply a held action the same way.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.interfaces import LearningInterface

__all__ = ["DecisionHold"]


class DecisionHold:
    """Held policy actions (..., dim) and their age in control steps (...), one per row.

    Args:
        interface: the learning interface that decodes the held actions.
        held: policy actions (..., dim), float64 (used as given, not copied).
        age: control steps since each row's decision (...), int64.
    """

    def __init__(self, interface: LearningInterface, held: np.ndarray, age: np.ndarray) -> None:
        self.interface = interface
        self.held = held
        self.age = age

    @classmethod
    def decided(cls, interface: LearningInterface, actions: np.ndarray) -> DecisionHold:
        """A hold in which every row has just decided ``actions`` (..., dim)."""
        held = np.asarray(actions, dtype=np.float64)
        return cls(interface, held, np.zeros(held.shape[:-1], np.int64))

    @classmethod
    def empty(cls, interface: LearningInterface, n_rows: int) -> DecisionHold:
        """A hold of ``n_rows`` rows that all have to decide (zero actions, age 0)."""
        dim = interface.config.dim
        return cls(interface, np.zeros((n_rows, dim)), np.zeros(n_rows, np.int64))

    def due(self, episode_start: np.ndarray | None = None) -> np.ndarray:
        """Rows whose held action has run for a whole decision period, or whose episode
        starts (``episode_start``), as a bool mask."""
        due = self.age % self.interface.decision_period == 0
        if episode_start is not None:
            due = due | episode_start
        return due

    def decide(self, rows: np.ndarray, actions: np.ndarray) -> None:
        """Rows ``rows`` (a mask or indices) take new policy actions; their age restarts."""
        self.held[rows] = actions
        self.age[rows] = 0

    def env_action(self, obs: np.ndarray) -> np.ndarray:
        """This control step's env action (..., dim): the held actions decoded against the
        physical observation ``obs`` (..., obs_size). Every row ages by one step."""
        out = self.interface.decode(obs, self.held)
        self.age += 1
        return out
