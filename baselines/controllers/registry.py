"""The controller registry: names (and ``"prefix:"`` entries) -> factories, and
:func:`make_pair_policy`, which builds a controller by name."""

from __future__ import annotations

import difflib
from collections.abc import Callable
from typing import Any

from baselines.controllers.base import ZeroPolicy
from baselines.controllers.braking import BrakingCurveController
from baselines.controllers.proportional import ProportionalController
from baselines.controllers.sb3 import load_sb3_policy
from baselines.controllers.sliding_mode import SlidingModeController

__all__ = ["POLICIES", "make_pair_policy"]


#: name -> factory(env, **gains); a prefix entry "name:" takes the text after the colon
POLICIES: dict[str, Callable[..., Any]] = {
    "smc": SlidingModeController,
    "proportional": ProportionalController,
    "braking": BrakingCurveController,
    "zero": ZeroPolicy,
    "sb3:": load_sb3_policy,  # a model saved by python -m train, or a packaged one
}


def make_pair_policy(name: str, env: Any, **gains: Any) -> Any:
    """Build a pair controller by name for ``env`` (any pairflock view, core or config).

    The result has SB3's ``predict(observation, state=None, episode_start=None,
    deterministic=True) -> (action, state)`` and acts per agent from that agent's
    observation.
    """
    if not isinstance(name, str):
        raise TypeError(f"name={name!r} is invalid: must be a string such as 'smc'")
    if ":" in name:
        prefix, arg = name.split(":", 1)
        factory = POLICIES.get(prefix + ":")
        if factory is None:
            raise ValueError(
                f"name={name!r} is invalid: unknown prefix {prefix!r}; valid: "
                f"{', '.join(sorted(POLICIES))}"
            )
        return factory(arg, env, **gains)
    if name not in POLICIES:
        hint = difflib.get_close_matches(name, list(POLICIES), n=1)
        extra = f" (did you mean {hint[0]!r}?)" if hint else ""
        raise ValueError(
            f"name={name!r} is invalid{extra}: must be one of {', '.join(sorted(POLICIES))}"
        )
    return POLICIES[name](env, **gains)
