"""pairflock_env: UAV swarm flocking with pairwise control, as a PettingZoo environment.

    >>> from pairflock_env import parallel_env
    >>> env = parallel_env(preset="paper", n_uavs=20)

The batched engine is :class:`PairFlockCore`; the PettingZoo views are ``parallel_env``
(ParallelEnv), ``env`` / ``raw_env`` (AEC). Importing the package registers the Gymnasium env
``"pairflock/PairFlock-v0"`` (``gymnasium.make``; ``gymnasium.make_vec`` runs B swarms in one
core through its ``vector_entry_point``); the SB3 VecEnv is
``pairflock_env.envs.PairFlockVecEnv`` (imported on first use).
"""

from .config import PRESETS, PairFlockConfig, make_config, preset_names
from .core import AGENT_INFO_KEYS, SWARM_INFO_KEYS, PairFlockCore, StepResult
from .envs import (
    ENV_ID,
    PairFlockGymEnv,
    PairFlockParallelEnv,
    PairFlockVectorEnv,
    agent_name,
    env,
    parallel_env,
    raw_env,
)
from .observations import ObsField, ObsLayout

# The one place the version is written: pyproject.toml reads it from here at build time.
__version__ = "0.1.0"


def _register_gymnasium() -> None:
    import gymnasium

    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="pairflock_env.envs.single:PairFlockGymEnv",
            vector_entry_point="pairflock_env.envs.vector:PairFlockVectorEnv",
        )


_register_gymnasium()

__all__ = [
    "AGENT_INFO_KEYS",
    "ENV_ID",
    "PRESETS",
    "SWARM_INFO_KEYS",
    "ObsField",
    "ObsLayout",
    "PairFlockConfig",
    "PairFlockCore",
    "PairFlockGymEnv",
    "PairFlockParallelEnv",
    "PairFlockVectorEnv",
    "StepResult",
    "__version__",
    "agent_name",
    "env",
    "make_config",
    "parallel_env",
    "preset_names",
    "raw_env",
]
