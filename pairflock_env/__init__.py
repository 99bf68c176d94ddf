"""pairflock_env: UAV swarm flocking with pairwise control, as a PettingZoo environment.

    >>> from pairflock_env import parallel_env
    >>> env = parallel_env(preset="paper", n_uavs=20)

The batched engine is :class:`PairFlockCore`; the PettingZoo views are ``parallel_env``
(ParallelEnv), ``env`` / ``raw_env`` (AEC). Importing the package registers the Gymnasium env
``"pairflock/PairFlock-v0"`` (``gymnasium.make``; ``gymnasium.make_vec`` runs B swarms in one
core through its ``vector_entry_point``, :class:`PairFlockGymVectorEnv`, one row per swarm);
the SB3 VecEnv with one row per paired UAV is ``pairflock_env.envs.PairFlockSB3VecEnv``
(imported on first use). Seeds: :mod:`pairflock_env.seeding`; observation and state bounds:
:mod:`pairflock_env.task.spaces`.
"""

import gymnasium

from pairflock_env.config import PRESETS, PairFlockConfig, make_config, preset_names
from pairflock_env.config.registry import load_plugins
from pairflock_env.core import AGENT_INFO_KEYS, SWARM_INFO_KEYS, PairFlockCore, StepResult
from pairflock_env.envs import (
    ENV_ID,
    PairFlockAECEnv,
    PairFlockGymEnv,
    PairFlockGymVectorEnv,
    PairFlockParallelEnv,
    agent_name,
    env,
    parallel_env,
    raw_env,
)
from pairflock_env.task.observations import ObsLayout

# The one place the version is written: pyproject.toml reads it from here at build time.
__version__ = "0.1.0"


def _register_gymnasium() -> None:
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="pairflock_env.envs.single:PairFlockGymEnv",
            vector_entry_point="pairflock_env.envs.vector:PairFlockGymVectorEnv",
        )


_register_gymnasium()
load_plugins()


__all__ = [
    "AGENT_INFO_KEYS",
    "ENV_ID",
    "PRESETS",
    "SWARM_INFO_KEYS",
    "ObsLayout",
    "PairFlockAECEnv",
    "PairFlockConfig",
    "PairFlockCore",
    "PairFlockGymEnv",
    "PairFlockGymVectorEnv",
    "PairFlockParallelEnv",
    "StepResult",
    "__version__",
    "agent_name",
    "env",
    "make_config",
    "parallel_env",
    "preset_names",
    "raw_env",
]
