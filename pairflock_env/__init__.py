"""pairflock_env: UAV swarm flocking with pairwise control, as a PettingZoo environment.

    >>> from pairflock_env import parallel_env
    >>> env = parallel_env(preset="paper", n_uavs=20)

The batched engine is :class:`PairFlockCore`; the PettingZoo views are ``parallel_env``
(ParallelEnv), ``env`` / ``raw_env`` (AEC).
"""

from .config import PRESETS, PairFlockConfig, make_config, preset_names
from .core import AGENT_INFO_KEYS, SWARM_INFO_KEYS, PairFlockCore, StepResult
from .envs import PairFlockParallelEnv, agent_name, env, parallel_env, raw_env
from .observations import ObsField, ObsLayout

__version__ = "0.1.0"

__all__ = [
    "AGENT_INFO_KEYS",
    "ObsField",
    "ObsLayout",
    "PRESETS",
    "PairFlockConfig",
    "PairFlockCore",
    "PairFlockParallelEnv",
    "SWARM_INFO_KEYS",
    "StepResult",
    "__version__",
    "agent_name",
    "env",
    "make_config",
    "parallel_env",
    "preset_names",
    "raw_env",
]
