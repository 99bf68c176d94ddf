"""The world interface: the env's observation, action and reward, unchanged."""

from __future__ import annotations

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.interfaces.base import LearningInterface, check_period
from pairflock_env.task.spaces import core_reward_range, physical_observation_bounds

__all__ = ["WorldInterface"]

try:  # the ufunc np.clip ends in for float arrays with both bounds, without ~1 us of dispatch
    from numpy._core.umath import clip as _clip
except ImportError:  # pragma: no cover - another numpy layout
    _clip = np.clip


class WorldInterface(LearningInterface):
    """The identity: the env's observation, action and reward, unchanged."""

    name = "world"
    passes_through = True

    def __init__(self, config: PairFlockConfig, decision_period: int = 1) -> None:
        super().__init__(config)
        self.decision_period = check_period(decision_period)
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def observation_size(self) -> int:
        return self.layout.size

    def _box(self) -> tuple[np.ndarray, np.ndarray]:
        if self._bounds is None:
            self._bounds = physical_observation_bounds(self.config)
        return self._bounds

    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The physical observation's box, derived from the config
        (:func:`~pairflock_env.task.spaces.physical_observation_bounds`)."""
        low, high = self._box()
        return low.copy(), high.copy()

    @property
    def reward_range(self) -> tuple[float, float]:
        """The core's reward range (:func:`~pairflock_env.task.spaces.core_reward_range`)."""
        return core_reward_range(self.config)

    def encode(self, obs: np.ndarray) -> np.ndarray:
        """The physical observation as float32, inside :meth:`observation_bounds` (only
        observation noise beyond ``NOISE_SIGMAS`` standard deviations is ever clipped)."""
        obs = self._check_obs_shape(obs)
        low, high = self._box()
        return _clip(obs.astype(np.float32, copy=False), low, high)

    def decode(self, obs: np.ndarray, action: np.ndarray) -> np.ndarray:
        return self._check_action(action, self._check_obs_shape(obs).shape[:-1])

    def action_for(self, obs: np.ndarray, u: np.ndarray) -> np.ndarray:
        u = self._check_accel(self._check_obs_shape(obs), u)
        return np.clip(u / self.config.pair_accel_limit, -1.0, 1.0)

    def reward(self, reward, info, action, obs=None):
        return np.asarray(reward, dtype=np.float64)
