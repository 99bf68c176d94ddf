"""API views over :class:`pairflock_env.core.PairFlockCore`.

PettingZoo (``parallel_env``, ``env``), Gymnasium (``PairFlockGymEnv``, ``PairFlockVectorEnv``)
and stable-baselines3 (``PairFlockVecEnv``, imported on first use so that SB3 and torch are
loaded only by code that needs them).
"""

from .parallel import PairFlockParallelEnv, agent_name, env, parallel_env, raw_env
from .single import ENV_ID, PairFlockGymEnv
from .vector import PairFlockVectorEnv

__all__ = [
    "ENV_ID",
    "PairFlockGymEnv",
    "PairFlockParallelEnv",
    "PairFlockVecEnv",
    "PairFlockVectorEnv",
    "agent_name",
    "env",
    "parallel_env",
    "raw_env",
]


def __getattr__(name: str):
    if name == "PairFlockVecEnv":  # lazy: imports stable-baselines3 (and torch)
        from .sb3 import PairFlockVecEnv

        return PairFlockVecEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
