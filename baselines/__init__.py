"""Pair controllers for the pairflock action slot, and the paper's reproduction.

    >>> from baselines import make_pair_policy
    >>> policy = make_pair_policy("smc", env)          # eq. 28
    >>> action, _ = policy.predict(obs["uav_0"])        # SB3's predict signature

Names: ``"smc"`` (sliding mode, eq. 28), ``"proportional"`` (eq. 44), ``"zero"`` (flocking
only), ``"sb3:<path>"`` (a model trained with ``python -m train``). Gains are keyword
arguments (``make_pair_policy("smc", env, k=200)``).

The package has four layers, each importing only the ones before it:

* :mod:`baselines.controllers` - the controllers and their registry (re-exported here);
* :mod:`baselines.evaluation` - batched rollouts, jobs and their backends, CLI specs, files;
* :mod:`baselines.reporting` - tables, acceptance criteria, figures, video;
* :mod:`baselines.experiments` - the CLIs (``python -m baselines.benchmark``, ``reproduce``,
  ``quadrotor_experiment``, ``quadrotor_invariants``).

The controller names are loaded on first use, so that importing a submodule (e.g. the
thread pinning of :mod:`baselines.evaluation.parallel`) does not load numpy first.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from baselines._moved import install_aliases

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

install_aliases()


def __getattr__(name: str) -> Any:
    if name in __all__:
        return getattr(importlib.import_module("baselines.controllers"), name)
    raise AttributeError(f"module 'baselines' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
