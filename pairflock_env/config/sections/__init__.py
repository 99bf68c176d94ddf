"""The sections of :class:`~pairflock_env.config.PairFlockConfig`, one module per section,
named after it. A vehicle model, safety filter, leader or observation field declares the
section of its own parameters beside its code (the quadrotor's:
:mod:`pairflock_env.dynamics.quadrotor.section`) and adds it when it registers
(:mod:`pairflock_env.config.registry`).

The order of :data:`SECTIONS` is the order of the docs tables and of ``to_dict``; rules and
derived quantities are checked as soon as their fields are. Plug-ins add their own sections
when they register (:mod:`pairflock_env.config.registry`).
"""

from __future__ import annotations

from pairflock_env.config.sections import (
    flocking,
    initial_state,
    leader,
    meta,
    observation,
    pair_task,
    reward,
    robustness,
    safety,
    swarm,
    timing,
)

__all__ = ["DERIVED", "RULES", "SECTIONS"]

_MODULES = (
    meta,
    swarm,
    timing,
    flocking,
    leader,
    pair_task,
    initial_state,
    reward,
    observation,
    robustness,
    safety,
)

SECTIONS = tuple(s for m in _MODULES for s in m.SECTIONS)
RULES = tuple(r for m in _MODULES for r in getattr(m, "RULES", ()))
DERIVED = tuple(d for m in _MODULES for d in getattr(m, "DERIVED", ()))
