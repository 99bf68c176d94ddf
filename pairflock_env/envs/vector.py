"""Gymnasium VectorEnv of B swarms in one batched core (the ``vector_entry_point``)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pairflock_env.config import PairFlockConfig
from pairflock_env.core import check_count
from pairflock_env.envs._base import (
    RENDER_MODES,
    SwarmView,
    check_policy_actions,
    held_step,
)
from pairflock_env.seeding import offset_seeds

__all__ = ["PairFlockGymVectorEnv"]


class PairFlockGymVectorEnv(SwarmView, VectorEnv):
    """Gymnasium ``VectorEnv`` with one row per swarm: B independent swarms, each exactly
    :class:`~pairflock_env.envs.single.PairFlockGymEnv`, simulated side by side in one
    :class:`~pairflock_env.core.PairFlockCore`. ``num_envs`` (Gymnasium's name) =
    ``num_swarms`` = ``num_rows`` = B.

    ``gymnasium.make_vec("pairflock/PairFlock-v0", num_envs=B,
    vectorization_mode="vector_entry_point", **kwargs)`` builds it; ``kwargs`` are those of
    the single env. Sub-env b equals a single env reset with the same seed: ``reset(seed=s)``
    seeds sub-env b with ``s + b`` (as ``SyncVectorEnv``), a SeedSequence with its child b,
    a list gives one seed each (:mod:`pairflock_env.seeding`).

    Observations ``(B, M * n)``, actions ``(B, M * dim)`` (row b is sub-env b's flat
    observation / action, as in the single env), rewards / terminations /
    truncations ``(B,)``. Infos are Gymnasium's dict of arrays: per-agent quantities
    ``(B, M)``, swarm quantities ``(B,)``, each with its ``_<key>`` mask.

    Auto-reset (``autoreset_mode``, default ``AutoresetMode.NEXT_STEP`` like Gymnasium's own
    vector envs): with ``NEXT_STEP`` a sub-env that ended is reset on the following
    ``step`` (its action is ignored, its reward is 0 and its flags are False); with
    ``SAME_STEP`` it is reset within the step that ended it and the last observation and info
    are in ``infos["final_obs"]`` / ``infos["final_info"]``; ``DISABLED`` leaves resets to the
    caller (``reset(options={"reset_mask": mask})``). Equality with sequential single envs
    holds exactly when no per-step randomness is drawn (no observation noise, no
    disturbance), since the core draws such noise for all swarms at once.
    """

    def __init__(
        self,
        num_envs: int = 1,
        preset: str | None = "paper",
        *,
        config: PairFlockConfig | None = None,
        interface: str | None = None,
        interface_params: Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        seed: Any = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **overrides: Any,
    ) -> None:
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            raise ValueError(
                f"autoreset_mode={autoreset_mode!r} is invalid: must be one of "
                f"{[m.value for m in AutoresetMode]}"
            ) from None
        check_count("num_envs", num_envs)
        self._open(
            preset=preset,
            config=config,
            overrides=overrides,
            num_swarms=num_envs,
            seed=seed,
            interface=interface,
            interface_params=interface_params,
            render_mode=render_mode,
        )
        self.num_envs = self.core.num_swarms
        self.num_swarms = self.num_rows = self.num_envs
        self.autoreset_mode = mode
        self.metadata = {
            "render_modes": list(RENDER_MODES),
            "render_fps": 25,
            "autoreset_mode": mode,
        }
        M, D = self.core.n_agents, self.config.dim
        low, high = self.interface.observation_bounds()
        self.single_observation_space = spaces.Box(
            np.tile(low, M), np.tile(high, M), dtype=np.float32
        )
        self.single_action_space = spaces.Box(-1.0, 1.0, (M * D,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._needs_reset = np.zeros(self.num_envs, bool)
        self._was_reset = False

    @property
    def reward_range(self) -> tuple[float, float]:
        """Every reward (the mean over a swarm's paired UAVs) lies in this range."""
        return self.interface.reward_range

    # ------------------------------------------------------------------ reset
    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None):
        """Reset every sub-env, or those of ``options["reset_mask"]``; ``seed`` as in the
        class docstring, ``options`` may also set ``positions`` / ``velocities``."""
        self._check_open("reset")
        if options is not None and not isinstance(options, Mapping):
            raise TypeError(f"options={options!r} is invalid: must be a dict or None")
        rows = np.arange(self.num_envs)
        opts = dict(options) if options else {}
        if "reset_mask" in opts:
            mask = opts.pop("reset_mask")
            if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_:
                raise TypeError(f"options['reset_mask'] must be a bool numpy array, got {mask!r}")
            if mask.shape != (self.num_envs,) or not mask.any():
                raise ValueError(
                    f"options['reset_mask'] must have shape ({self.num_envs},) and at least one "
                    f"True entry, got {mask.tolist()}"
                )
            rows = np.flatnonzero(mask)
        seeds = offset_seeds(seed, self.num_envs)
        if seeds is not None and len(rows) < self.num_envs:
            seeds = [seeds[r] for r in rows]
        res = self.core.reset_rows(rows, seed=seeds, options=opts or None)
        if seeds is not None:
            self._np_random_seed = seeds[0] if isinstance(seeds[0], int) else -1
        self._needs_reset[rows] = False
        self._was_reset = True
        self._renderers.reset(set(rows.tolist()))
        self.physical_obs = res.obs.copy()
        obs = self.interface.encode(res.obs).reshape(self.num_envs, -1)
        return obs, self._infos(res.info, rows)

    # ------------------------------------------------------------------ step
    def step(self, actions: Any):
        """One policy decision of every sub-env, with the auto-reset of ``autoreset_mode``."""
        self._check_open("step")
        if not self._was_reset:
            raise RuntimeError("call reset() before step()")
        B, M, D = self.num_envs, self.core.n_agents, self.config.dim
        a = check_policy_actions(actions, (B, M * D)).reshape(B, M, D)
        if self.autoreset_mode == AutoresetMode.DISABLED and self._needs_reset.any():
            raise RuntimeError(
                f"sub-envs {np.flatnonzero(self._needs_reset).tolist()} have ended; with "
                "autoreset_mode=DISABLED reset them with reset(options={'reset_mask': mask})"
            )
        pending = np.flatnonzero(self._needs_reset)
        res = held_step(self.core, self.interface, self.physical_obs, a)
        reward = res.reward.mean(axis=1)
        terminated = res.terminated.copy()
        truncated = res.truncated.copy()
        obs_phys = res.obs
        info = res.info
        extra: dict[str, Any] = {}
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and pending.size:
            # the ended swarms start a new episode instead of taking this step
            rr = self.core.reset_rows(pending)
            obs_phys, info = self._merge(res, rr, pending)
            reward[pending] = 0.0
            terminated[pending] = False
            truncated[pending] = False
        ended = terminated | truncated
        if self.autoreset_mode == AutoresetMode.SAME_STEP and ended.any():
            rows = np.flatnonzero(ended)
            final_obs = np.full(B, None, dtype=object)
            enc = self.interface.encode(obs_phys).reshape(B, -1)
            final_info = self._infos(info, rows)
            for r in rows:
                final_obs[r] = enc[r]
            rr = self.core.reset_rows(rows)
            obs_phys, info = self._merge(res, rr, rows)
            self._renderers.reset(set(rows.tolist()))
            extra = {
                "final_obs": final_obs,
                "_final_obs": ended.copy(),
                "final_info": final_info,
                "_final_info": ended.copy(),
            }
        elif self.autoreset_mode != AutoresetMode.SAME_STEP:
            self._needs_reset = ended.copy()
            if pending.size:
                self._renderers.reset(set(pending.tolist()))
        self.physical_obs = obs_phys.copy()
        obs = self.interface.encode(obs_phys).reshape(B, -1)
        infos = self._infos(info, np.arange(B))
        infos.update(extra)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, infos

    @staticmethod
    def _merge(step_res, reset_res, rows: np.ndarray):
        obs = step_res.obs.copy()
        obs[rows] = reset_res.obs[rows]
        info = {}
        for k, v in step_res.info.items():
            w = v.copy()
            w[rows] = reset_res.info[k][rows]
            info[k] = w
        return obs, info

    def _infos(self, info: Mapping[str, np.ndarray], rows: np.ndarray) -> dict[str, Any]:
        mask = np.zeros(self.num_envs, bool)
        mask[rows] = True
        every = bool(mask.all())  # (each step) a copy of every row, zeros nowhere
        out: dict[str, Any] = {}
        for k, v in info.items():
            if every:
                arr = v.copy(order="K")  # the layout of zeros_like
            else:
                arr = np.zeros_like(v)
                arr[rows] = v[rows]
            out[k] = arr
            out["_" + k] = mask.copy()
        return out

    # ------------------------------------------------------------------ misc
    def render(self) -> tuple[Any, ...] | None:
        """One frame per sub-env (``render_mode="rgb_array"``), or the windows (``"human"``)."""
        if self.render_mode is None:
            return self._renderers.render(0)  # warns
        frames = tuple(self._renderers.render(b) for b in range(self.num_envs))
        return frames if self.render_mode == "rgb_array" else None

    def close_extras(self, **kwargs: Any) -> None:
        """Release the renderers; the env cannot be reset or stepped afterwards."""
        self._renderers.close()
        self._mark_closed()
