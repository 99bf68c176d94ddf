"""Gymnasium VectorEnv of B swarms in one batched core (the ``vector_entry_point``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..config import PairFlockConfig
from ._learning_view import (
    RENDER_MODES,
    SwarmFrames,
    build_core_and_interface,
    check_policy_actions,
    held_step,
)

__all__ = ["PairFlockVectorEnv"]


class PairFlockVectorEnv(VectorEnv):
    """B independent swarms, each exactly :class:`~pairflock_env.envs.single.PairFlockGymEnv`,
    simulated side by side in one :class:`~pairflock_env.core.PairFlockCore`.

    ``gymnasium.make_vec("pairflock/PairFlock-v0", num_envs=B,
    vectorization_mode="vector_entry_point", **kwargs)`` builds it; ``kwargs`` are those of
    the single env. Sub-env b equals a single env reset with the same seed: ``reset(seed=s)``
    seeds sub-env b with ``s + b`` (as ``SyncVectorEnv``), a list gives one seed each.

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
        frame: str = "pair",
        frame_params: Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        seed: int | None = None,
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
        self.core, self.interface = build_core_and_interface(
            preset, config, overrides, num_envs, seed, frame, frame_params, render_mode
        )
        self.num_envs = self.core.num_envs
        self.config = self.core.config
        self.layout = self.core.layout
        self.frame = frame
        self.render_mode = render_mode
        self.autoreset_mode = mode
        self.metadata = {
            "render_modes": list(RENDER_MODES),
            "render_fps": 25,
            "autoreset_mode": mode,
        }
        M, D = self.core.n_agents, self.config.dim
        n = self.interface.observation_size
        bound = self.interface.observation_bound
        self.single_observation_space = spaces.Box(-bound, bound, (M * n,), np.float32)
        self.single_action_space = spaces.Box(-1.0, 1.0, (M * D,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.physical_obs: np.ndarray | None = None
        self._needs_reset = np.zeros(self.num_envs, bool)
        self._was_reset = False
        self._frames = SwarmFrames(self.core, render_mode)

    # ------------------------------------------------------------------ reset
    def _swarm_seeds(self, seed: Any, n: int) -> list[int | None] | None:
        if seed is None:
            return None
        if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            if seed < 0:
                raise ValueError(f"seed={seed!r} is invalid: must be >= 0")
            return [int(seed) + i for i in range(n)]
        if isinstance(seed, Sequence) and not isinstance(seed, str):
            if len(seed) != n:
                raise ValueError(f"seed has {len(seed)} entries, expected {n} (one per sub-env)")
            return list(seed)
        raise TypeError(
            f"seed={seed!r} is invalid: must be None, an int >= 0 or a list of {n} seeds"
        )

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None):
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
        seeds = self._swarm_seeds(seed, self.num_envs)
        if seeds is not None and len(rows) < self.num_envs:
            seeds = [seeds[r] for r in rows]
        res = self.core.reset_rows(rows, seed=seeds, options=opts or None)
        if seeds is not None:
            self._np_random_seed = seeds[0] if isinstance(seeds[0], int) else -1
        self._needs_reset[rows] = False
        self._was_reset = True
        self._frames.reset(set(rows.tolist()))
        self.physical_obs = res.obs.copy()
        obs = self.interface.encode(res.obs).reshape(self.num_envs, -1)
        return obs, self._infos(res.info, rows)

    # ------------------------------------------------------------------ step
    def step(self, actions: Any):
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
            self._frames.reset(set(rows.tolist()))
            extra = {
                "final_obs": final_obs,
                "_final_obs": ended.copy(),
                "final_info": final_info,
                "_final_info": ended.copy(),
            }
        elif self.autoreset_mode != AutoresetMode.SAME_STEP:
            self._needs_reset = ended.copy()
            if pending.size:
                self._frames.reset(set(pending.tolist()))
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
        out: dict[str, Any] = {}
        for k, v in info.items():
            arr = np.zeros_like(v)
            arr[rows] = v[rows]
            out[k] = arr
            out["_" + k] = mask.copy()
        return out

    # ------------------------------------------------------------------ misc
    def render(self) -> tuple[Any, ...] | None:
        if self.render_mode is None:
            return self._frames.render(0)  # warns
        frames = tuple(self._frames.render(b) for b in range(self.num_envs))
        return frames if self.render_mode == "rgb_array" else None

    def close_extras(self, **kwargs: Any) -> None:
        self._frames.close()
