"""The learning interface's base class: what every interface between the env and a learned
policy provides (see :mod:`pairflock_env.interfaces`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.interfaces.pair_params import PAIR_INTERFACE_SCHEMA
from pairflock_env.kernels import all_finite
from pairflock_env.task.observations import ObsLayout

__all__ = ["LearningInterface", "check_period", "symlog"]


def symlog(x: np.ndarray) -> np.ndarray:
    """sign(x) log(1 + |x|): linear near 0, logarithmic far out."""
    return np.sign(x) * np.log1p(np.abs(x))


def check_period(v: Any) -> int:
    return PAIR_INTERFACE_SCHEMA.fields["decision_period"].kind.check("decision_period", v, {})


class LearningInterface:
    """Maps the env's observation/action/reward to what a learned policy sees and outputs.

    Subclasses are stateless apart from their frozen parameters, so the same object serves
    every row of a batch and can be rebuilt from :meth:`to_dict`.
    """

    name: str = ""
    #: control steps a policy action is held (the policy period is decision_period * dt)
    decision_period: int = 1
    #: True when :meth:`decode` returns a checked action unchanged and :meth:`reward` the
    #: core's reward (the views then skip both)
    passes_through: bool = False

    def __init__(self, config: PairFlockConfig) -> None:
        if not isinstance(config, PairFlockConfig):
            raise TypeError(f"config={config!r} is invalid: must be a PairFlockConfig")
        self.config = config
        self.layout = ObsLayout.for_config(config)

    #: every entry of an encoded observation lies in [-observation_bound, observation_bound]
    observation_bound: float = np.inf

    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high), each float32 (observation_size,): the box every encoded observation
        lies in (what the views' observation spaces are)."""
        b = np.full(self.observation_size, self.observation_bound, np.float32)
        return -b, b

    @property
    def reward_range(self) -> tuple[float, float]:  # pragma: no cover - abstract
        """(low, high): every per-agent reward of :meth:`reward` lies in this range."""
        raise NotImplementedError

    @property
    def observation_size(self) -> int:  # pragma: no cover - abstract
        raise NotImplementedError

    def encode(self, obs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        """Policy observation (..., observation_size) float32 from env observations
        (..., obs_size)."""
        raise NotImplementedError

    def decode(self, obs: np.ndarray, action: np.ndarray) -> np.ndarray:  # pragma: no cover
        """Env actions (..., dim) (units of pair_accel_limit) from policy actions (..., dim)."""
        raise NotImplementedError

    def action_for(self, obs: np.ndarray, u: np.ndarray) -> np.ndarray:  # pragma: no cover
        """Policy actions (..., dim) that decode to the world-frame pair accelerations ``u``
        (..., dim, m/s^2) where the action box allows, clipped to it elsewhere: the inverse of
        :meth:`decode`, to label an analytic controller's commands (:mod:`train.imitate`)."""
        raise NotImplementedError

    def _check_accel(self, obs: np.ndarray, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=np.float64)
        if u.shape != (*obs.shape[:-1], self.config.dim):
            raise ValueError(
                f"u has shape {u.shape}; expected {(*obs.shape[:-1], self.config.dim)} "
                "(one world-frame acceleration per observation)"
            )
        return u

    def reward(
        self,
        reward: np.ndarray,
        info: Mapping[str, np.ndarray],
        action: np.ndarray,
        obs: np.ndarray | None = None,
    ) -> np.ndarray:  # pragma: no cover - abstract
        """Per-agent learning reward (B, M) from the core's reward and infos of a control step,
        the policy actions (B, M, dim) and the physical observation (B, M, obs_size) after it."""
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "decision_period": self.decision_period}

    def _check_obs_shape(self, obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs)
        if obs.shape[-1:] != (self.layout.size,):
            raise ValueError(
                f"observation has shape {obs.shape}; expected (..., {self.layout.size}) "
                f"(dim={self.config.dim}, obs_neighbors={self.config.obs_neighbors})"
            )
        return obs

    def _check_obs(self, obs: np.ndarray) -> np.ndarray:
        return self._check_obs_shape(obs).astype(np.float64, copy=False)

    def _check_action(self, action: np.ndarray, lead: tuple[int, ...]) -> np.ndarray:
        a = np.asarray(action, dtype=np.float64)
        D = self.config.dim
        if a.shape != (*lead, D):
            raise ValueError(f"action has shape {a.shape}; expected {(*lead, D)}")
        if not all_finite(a):
            raise ValueError("action contains NaN or inf; actions must be finite")
        return a
