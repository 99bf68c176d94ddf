"""API views over :class:`pairflock_env.core.PairFlockCore`."""

from .parallel import PairFlockParallelEnv, agent_name, env, parallel_env, raw_env

__all__ = ["PairFlockParallelEnv", "agent_name", "env", "parallel_env", "raw_env"]
