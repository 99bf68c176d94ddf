"""The sections of :class:`~pairflock_env.config.PairFlockConfig`, one module per topic.

The order of :data:`SECTIONS` is the order of the docs tables and of ``to_dict``; rules and
derived quantities are checked as soon as their fields are.
"""

from __future__ import annotations

from pairflock_env.config.sections import (
    flocking,
    leader,
    pairs,
    quadrotor,
    reward,
    safety,
    sensing,
    swarm,
)

__all__ = ["DERIVED", "RULES", "SECTIONS"]

_MODULES = (swarm, flocking, leader, pairs, reward, sensing, quadrotor, safety)

SECTIONS = tuple(s for m in _MODULES for s in m.SECTIONS)
RULES = tuple(r for m in _MODULES for r in getattr(m, "RULES", ()))
DERIVED = tuple(d for m in _MODULES for d in getattr(m, "DERIVED", ()))
