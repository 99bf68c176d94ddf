"""Gymnasium view of one swarm: one agent choosing the joint action of every paired UAV."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from pairflock_env.config import PairFlockConfig
from pairflock_env.envs._base import (
    RENDER_MODES,
    SwarmView,
    check_policy_actions,
    held_step,
)
from pairflock_env.seeding import check_seed

__all__ = ["ENV_ID", "PairFlockGymEnv"]

ENV_ID = "pairflock/PairFlock-v0"


class PairFlockGymEnv(SwarmView, gym.Env):
    """One UAV swarm flocking with the protocol of eqs. 11-19; the agent controls the pair.

    ``gymnasium.make("pairflock/PairFlock-v0", n_uavs=20, pair_accel_limit=50.0)``. Every UAV
    flies the analytic flocking protocol; the agent sets the pairwise acceleration of the
    paired UAVs (for the default config: one pair, UAVs 0 and 1), the slot the paper's
    sliding-mode controller fills. ``gymnasium.make_vec(ENV_ID, num_envs=B,
    vectorization_mode="vector_entry_point")`` runs B swarms in one batched core
    (:class:`~pairflock_env.envs.vector.PairFlockGymVectorEnv`); the SB3 VecEnv with one row
    per paired UAV is :class:`~pairflock_env.envs.sb3.PairFlockSB3VecEnv`.

    ## Action space
    ``Box(-1, 1, (M * dim,), float32)``, M = 2 x pairs: the concatenated actions of the paired
    UAVs A0, B0, A1, B1, ... (``action.reshape(M, dim)`` gives one row per UAV; flat so that
    SB3's MLP policies take it as is). What a row means depends on ``interface`` (see
    :mod:`pairflock_env.interfaces`):

    * ``interface="pair"`` (default): the UAV's acceleration in its pair frame (radial toward the
      partner, tangential), ``accel_scale`` m/s^2 per unit, on top of a feed-forward that
      cancels the observed flocking difference on the pair; the sum never exceeds
      ``pair_accel_limit`` per component.
    * ``interface="world"``: the raw env action, world frame, units of ``pair_accel_limit``
      (clipped per component by the core).

    NaN/inf, a wrong shape or a non-numeric dtype raise and leave the env unchanged. One
    ``step`` is one policy decision: the action is held for the interface's
    ``decision_period`` control steps (5 x 0.01 s for ``"pair"``, 1 for ``"world"``; set it
    with ``interface_params={"decision_period": k}``) and the reward is their mean.

    ## Observation space
    ``Box(low, high, (M * n,), float32)``: ``obs.reshape(M, n)[m]`` is what UAV m sees.
    ``interface="pair"``: the normalised pair-frame features in [-5, 5] of
    :class:`~pairflock_env.interfaces.PairInterface`
    (``env.unwrapped.interface.fields``); ``interface="world"``: the physical observation of
    :class:`~pairflock_env.task.observations.ObsLayout` (``env.unwrapped.layout``), with finite
    bounds derived from the config (:mod:`pairflock_env.task.spaces`). The physical observation
    (M, obs_size) is always available as ``env.unwrapped.physical_obs``.

    ## Rewards
    The mean over the M paired UAVs of the interface's per-UAV reward: the core's penalty sum
    (``interface="world"``; metres of pair error per control step, about -250 at the paper's
    start) or the pair frame's normalised log-accuracy / effort / separation reward (of order
    one per step). ``env.unwrapped.reward_range`` is its guaranteed range.

    ## Starting state, episode end
    As the PettingZoo env (``pairflock_env.parallel_env``): pair members in opposite corners,
    the others uniform in [-50, 50]^dim at rest; truncation after ``config.episode_steps``
    control steps (50 s in the paper preset; ``max_cycles`` / ``horizon`` override it);
    termination on divergence (or on a collision with ``terminate_on_collision=True``).
    ``step`` after the end or before ``reset``, ``render`` before ``reset`` and
    ``reset``/``step`` after ``close`` raise ``RuntimeError``.

    ## Infos
    Per-agent quantities (``pair_error``, ``min_separation``, ...) as arrays (M,), swarm
    quantities (``sim_time``, ``collisions``, ...) as floats, plus ``reward_<term>``.

    ## Arguments
    ``preset`` (default ``"paper"``), ``config`` (a ``PairFlockConfig``), ``interface``
    (``"pair"`` or ``"world"``), ``interface_params`` (dict of
    :class:`~pairflock_env.interfaces.PairInterfaceParams` fields), ``render_mode``
    (``"rgb_array"`` / ``"human"``), ``seed`` (of the swarm generator when ``reset`` gets
    none) and any ``PairFlockConfig`` field as a keyword.

    ## Example
    >>> import gymnasium as gym, pairflock_env
    >>> env = gym.make("pairflock/PairFlock-v0", n_uavs=20, pair_accel_limit=50.0)
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, env.action_space.shape
    ((104,), (4,))
    >>> obs, r, terminated, truncated, info = env.step(env.action_space.sample())
    >>> round(info["sim_time"], 2)  # one decision = 5 control steps of 0.01 s
    0.05

    ## Version history
    * v0: initial release.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 25}

    def __init__(
        self,
        preset: str | None = "paper",
        *,
        config: PairFlockConfig | None = None,
        interface: str | None = None,
        interface_params: Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        seed: Any = None,
        **overrides: Any,
    ) -> None:
        self._open(
            preset=preset,
            config=config,
            overrides=overrides,
            num_swarms=1,
            seed=seed,
            interface=interface,
            interface_params=interface_params,
            render_mode=render_mode,
        )
        M, D = self.core.n_agents, self.config.dim
        low, high = self.interface.observation_bounds()
        self.observation_space = spaces.Box(np.tile(low, M), np.tile(high, M), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, (M * D,), np.float32)
        self._live = False

    @property
    def reward_range(self) -> tuple[float, float]:
        """The reward (the mean over the paired UAVs) lies in the interface's range."""
        return self.interface.reward_range

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None):
        """Start an episode; ``seed``: None, an int >= 0 or a SeedSequence."""
        self._check_open("reset")
        seed = check_seed(seed)
        res = self.core.reset(seed=None if seed is None else [seed], options=options)
        # the swarm's own generator is the env's np_random (one source of randomness)
        self._np_random = self.core.rngs[0]
        self._np_random_seed = seed if isinstance(seed, int) else -1
        self._live = True
        self._renderers.reset()
        self.physical_obs = res.obs[0]
        obs = self.interface.encode(res.obs[0]).reshape(-1)
        if self.render_mode == "human":
            self.render()
        return obs, self._info(res.info)

    def step(self, action: Any):
        """One policy decision (``decision_period`` control steps)."""
        self._check_open("step")
        if not self._live:
            raise RuntimeError("the episode has ended (or reset() was never called); call reset()")
        M, D = self.core.n_agents, self.config.dim
        a = check_policy_actions(action, (M * D,), "action").reshape(M, D)
        res = held_step(self.core, self.interface, self.physical_obs[None], a[None])
        reward = float(np.mean(res.reward[0]))
        terminated = bool(res.terminated[0])
        truncated = bool(res.truncated[0])
        self._live = not (terminated or truncated)
        self.physical_obs = res.obs[0]
        obs = self.interface.encode(res.obs[0]).reshape(-1)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, self._info(res.info)

    @staticmethod
    def _info(info: Mapping[str, np.ndarray]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in info.items():
            out[k] = v.item(0) if v.ndim == 1 else v[0].copy()
        return out

    def render(self):
        """The swarm as an RGB array (``render_mode="rgb_array"``) or in a window."""
        return self._renderers.render(0)

    def close(self) -> None:
        """Release the renderer; the env cannot be reset or stepped afterwards."""
        self._renderers.close()
        self._mark_closed()
