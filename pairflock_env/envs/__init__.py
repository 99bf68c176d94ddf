"""API views over :class:`pairflock_env.core.PairFlockCore`.

PettingZoo (``parallel_env``, ``env``: :class:`PairFlockParallelEnv`,
:class:`~pairflock_env.envs.aec.PairFlockAECEnv`), Gymnasium (:class:`PairFlockGymEnv`,
:class:`PairFlockGymVectorEnv`: one row per swarm) and stable-baselines3
(``PairFlockSB3VecEnv``: one row per paired UAV, loaded on first use so that SB3 and torch
are imported only by code that needs them). Every view is a
:class:`~pairflock_env.envs._base.SwarmView`.
"""

import importlib
from typing import Any

from pairflock_env.envs.aec import PairFlockAECEnv, env, raw_env
from pairflock_env.envs.parallel import PairFlockParallelEnv, agent_name, parallel_env
from pairflock_env.envs.single import ENV_ID, PairFlockGymEnv
from pairflock_env.envs.vector import PairFlockGymVectorEnv

__all__ = [
    "ENV_ID",
    "PairFlockAECEnv",
    "PairFlockGymEnv",
    "PairFlockGymVectorEnv",
    "PairFlockParallelEnv",
    "PairFlockSB3VecEnv",
    "agent_name",
    "env",
    "parallel_env",
    "raw_env",
]


def __getattr__(name: str) -> Any:
    if name == "PairFlockSB3VecEnv":  # lazy: imports SB3 (and torch)
        return importlib.import_module("pairflock_env.envs.sb3").PairFlockSB3VecEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
