"""API views over :class:`pairflock_env.core.PairFlockCore`.

PettingZoo (``parallel_env``, ``env``: :class:`PairFlockParallelEnv`,
:class:`~pairflock_env.envs.aec.PairFlockAECEnv`), Gymnasium (:class:`PairFlockGymEnv`,
:class:`PairFlockGymVectorEnv`: one row per swarm) and stable-baselines3
(``PairFlockSB3VecEnv``: one row per paired UAV, imported on first use so that SB3 and torch
are loaded only by code that needs them). ``PairFlockVectorEnv`` and ``PairFlockVecEnv`` are
the deprecated former names of the two vector envs.
"""

from typing import Any

from pairflock_env.envs._base import deprecated_attr
from pairflock_env.envs.aec import PairFlockAECEnv
from pairflock_env.envs.parallel import PairFlockParallelEnv, agent_name, env, parallel_env, raw_env
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

_DEPRECATED = {
    "PairFlockVectorEnv": "PairFlockGymVectorEnv",
    "PairFlockVecEnv": "PairFlockSB3VecEnv",
}


def __getattr__(name: str) -> Any:
    namespace = globals()
    if name in ("PairFlockSB3VecEnv", "PairFlockVecEnv"):  # lazy: imports SB3 (and torch)
        from pairflock_env.envs import sb3

        if name == "PairFlockSB3VecEnv":
            return sb3.PairFlockSB3VecEnv
        namespace = vars(sb3)
    return deprecated_attr(__name__, name, _DEPRECATED, namespace)
