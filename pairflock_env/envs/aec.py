"""PettingZoo AEC view: the parallel env stepped one agent at a time.

PettingZoo's converter (``parallel_to_aec``) stores each agent's action and checks nothing
until the last agent of the cycle acts, so a bad action of the first agent surfaced at the
second agent's call and kept failing until ``reset()``. Here every ``step(action)`` validates
its own action first (the parallel env's check), and a rejected call changes nothing. Lifecycle
errors are ``RuntimeError`` with a message, as in the other views: ``step``/``observe``/
``state``/``render`` before ``reset``, an action for an agent whose episode has ended (done
agents are stepped with ``None``), and ``step`` once every agent is gone.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo.utils.conversions import parallel_to_aec_wrapper
from pettingzoo.utils.wrappers import OrderEnforcingWrapper

from pairflock_env.envs.parallel import PairFlockParallelEnv, parallel_env

__all__ = ["PairFlockAECEnv", "PairFlockOrderEnforcing", "env", "raw_env"]

_ENDED = "the episode has ended; call reset()"


class PairFlockAECEnv(parallel_to_aec_wrapper):
    """The AEC env over a :class:`~pairflock_env.envs.parallel.PairFlockParallelEnv`.

    Observations, spaces, rewards, infos, ``state()`` / ``state_space`` and rendering are the
    parallel env's; the physics advances when the last live agent of a cycle has acted.
    """

    def __init__(self, parallel_env: PairFlockParallelEnv) -> None:
        if not isinstance(parallel_env, PairFlockParallelEnv):
            raise TypeError(
                f"parallel_env={parallel_env!r} is invalid: must be a PairFlockParallelEnv"
            )
        super().__init__(parallel_env)

    def step(self, action: Any) -> None:
        """Act for ``agent_selection``: its action (validated now) or ``None`` once it is done."""
        self.env._check_open("step")
        if not getattr(self, "agents", None):
            raise RuntimeError(f"no agent is left to act: {_ENDED}")
        agent = self.agent_selection
        if self.terminations[agent] or self.truncations[agent]:
            if action is not None:
                raise RuntimeError(
                    f"the episode of {agent} has ended: step done agents with None (PettingZoo's "
                    "dead step), or call reset()"
                )
            super().step(None)
            return
        checked = self.env.check_action(agent, action)
        super().step(checked)

    def state(self) -> np.ndarray:
        """The parallel env's global state."""
        return self.env.state()


class PairFlockOrderEnforcing(OrderEnforcingWrapper):
    """PettingZoo's order enforcement with this project's lifecycle errors (``RuntimeError``
    with a message instead of an ``AssertionError``, and no silent ``step`` once the episode
    is over)."""

    def _require_reset(self, method: str) -> None:
        if not self._has_reset:
            raise RuntimeError(f"call reset() before {method}()")

    def step(self, action: Any) -> None:
        self._require_reset("step")
        if not self.agents:
            raise RuntimeError(f"no agent is left to act: {_ENDED}")
        self._has_updated = True
        self.env.step(action)

    def observe(self, agent: Any):
        self._require_reset("observe")
        return super().observe(agent)

    def state(self) -> np.ndarray:
        self._require_reset("state")
        return super().state()

    def render(self):
        # without a render_mode every view warns and returns None, reset or not
        if self.render_mode is not None:
            self._require_reset("render")
        return self.env.render()  # PettingZoo's wrapper would assert a reset first


def raw_env(**kwargs: Any) -> PairFlockOrderEnforcing:
    """The AEC env over the parallel env (order enforced; see :class:`PairFlockAECEnv`)."""
    return PairFlockOrderEnforcing(PairFlockAECEnv(parallel_env(**kwargs)))


def env(**kwargs: Any) -> PairFlockOrderEnforcing:
    """The AEC env (PettingZoo's standard entry point)."""
    return raw_env(**kwargs)
