"""Pair controllers for the pairflock action slot, and the experiments that use them.

    >>> from baselines import make_pair_policy
    >>> policy = make_pair_policy("smc", env)          # eq. 28
    >>> action, _ = policy.predict(obs["uav_0"])        # SB3's predict signature

Names: ``"smc"`` (sliding mode, eq. 28), ``"proportional"`` (eq. 44), ``"zero"`` (flocking
only), ``"sb3:<path>"`` (a model trained with ``python -m train``). Gains are keyword
arguments (``make_pair_policy("smc", env, k=200)``).

The package has five layers, each importing only the ones before it:

* :mod:`baselines.runtime` - files, run records, thread pinning, processes, the CLI error path;
* :mod:`baselines.controllers` - the controllers and their registry (re-exported here);
* :mod:`baselines.evaluation` - batched rollouts, jobs and their backends, CLI specs;
* :mod:`baselines.reporting` - tables, statistics, acceptance criteria, figures, video;
* :mod:`baselines.experiments` - one folder per experiment (``benchmark``, ``quadrotor``,
  ``safety``), each with its command lines.

The modules beside this one are the launchers of the documented commands (``python -m
baselines.benchmark``, ``reproduce``, ``quadrotor_experiment``, ``quadrotor_invariants``,
``quadrotor_compare``, ``safety_compare``): each pins one thread per process, then imports
its experiment. So that the pinning comes before numpy loads, this package imports nothing
itself: the controllers' names below are looked up on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the names as static tools (type checkers, the API docs) see them
    from baselines.controllers import (
        POLICIES,
        BrakingCurveController,
        PairPolicy,
        ProportionalController,
        SlidingModeController,
        ZeroPolicy,
        make_pair_policy,
        resolve_env,
    )

__all__ = [
    "POLICIES",
    "BrakingCurveController",
    "PairPolicy",
    "ProportionalController",
    "SlidingModeController",
    "ZeroPolicy",
    "make_pair_policy",
    "resolve_env",
]


def __getattr__(name: str) -> Any:
    if name in __all__:
        return getattr(importlib.import_module("baselines.controllers"), name)
    raise AttributeError(f"module 'baselines' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
