"""Native stable-baselines3 VecEnv: one row per paired UAV of B swarms, one batched core.

Imports stable-baselines3, so it is loaded lazily (``pairflock_env.envs.PairFlockSB3VecEnv`` or
``from pairflock_env.envs.sb3 import PairFlockSB3VecEnv``); ``import pairflock_env`` stays light.
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces

try:
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv
except ImportError as e:  # pragma: no cover - depends on the install
    raise ImportError(
        "pairflock_env.envs.sb3 needs stable-baselines3: pip install 'pairflock-env[train]'"
    ) from e

from pairflock_env.config import PairFlockConfig
from pairflock_env.core import AGENT_INFO_KEYS, SWARM_INFO_KEYS
from pairflock_env.envs._base import (
    RENDER_MODES,
    SwarmRenderers,
    SwarmView,
    check_policy_actions,
    held_step,
)
from pairflock_env.envs.parallel import agent_name
from pairflock_env.seeding import offset_seeds
from pairflock_env.swarm.placement import check_reset_options

__all__ = ["AgentRow", "PairFlockSB3VecEnv"]


class AgentRow:
    """What ``get_attr`` / ``set_attr`` / ``env_method`` address: one row (one paired UAV).

    Read-only properties describe the row (``swarm``, ``agent``, ``uav_index``, ``partner``,
    ``config``, ``observation_space``, ``np_random`` (its swarm's generator), ...); other
    attributes can be set per row with ``set_attr`` and read back with ``get_attr`` (as on the
    sub-envs of a ``DummyVecEnv``). Methods: ``render()``, ``swarm_state()``,
    ``get_wrapper_attr(name)``.
    """

    _READ_ONLY = frozenset(
        {
            "index",
            "swarm",
            "agent_index",
            "agent",
            "uav_index",
            "partner",
            "config",
            "layout",
            "interface",
            "observation_space",
            "action_space",
            "render_mode",
            "metadata",
            "np_random",
            "unwrapped",
        }
    )

    def __init__(self, venv: PairFlockSB3VecEnv, index: int) -> None:
        object.__setattr__(self, "_venv", venv)
        object.__setattr__(self, "index", index)

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self._READ_ONLY:
            raise AttributeError(
                f"attribute {name!r} of a PairFlockSB3VecEnv row is read-only; settable are any "
                f"other names (stored per row), read-only are {sorted(self._READ_ONLY)}"
            )
        object.__setattr__(self, name, value)

    # --- description -----------------------------------------------------------------
    @property
    def swarm(self) -> int:
        return self.index // self._venv.agents_per_swarm

    @property
    def agent_index(self) -> int:
        return self.index % self._venv.agents_per_swarm

    @property
    def uav_index(self) -> int:
        return int(self._venv.core.agent_uavs[self.agent_index])

    @property
    def agent(self) -> str:
        return agent_name(self.uav_index)

    @property
    def partner(self) -> str:
        return agent_name(int(self._venv.core.partner_uavs[self.agent_index]))

    @property
    def config(self) -> PairFlockConfig:
        return self._venv.config

    @property
    def layout(self):
        return self._venv.layout

    @property
    def interface(self):
        return self._venv.interface

    @property
    def observation_space(self) -> spaces.Box:
        return self._venv.observation_space

    @property
    def action_space(self) -> spaces.Box:
        return self._venv.action_space

    @property
    def render_mode(self) -> str | None:
        return self._venv.render_mode

    @property
    def metadata(self) -> dict[str, Any]:
        return {"render_modes": list(RENDER_MODES), "render_fps": 25}

    @property
    def np_random(self) -> np.random.Generator:
        return self._venv.core.rngs[self.swarm]

    @property
    def unwrapped(self) -> AgentRow:
        return self

    # --- methods ----------------------------------------------------------------------
    def render(self):
        """The row's swarm as an RGB frame (``render_mode="rgb_array"``) or in a window."""
        return self._venv._renderers.render(self.swarm)

    def swarm_state(self) -> dict[str, Any]:
        """Copies of the row's swarm state: positions, velocities (N, dim), sim time, steps."""
        core, b = self._venv.core, self.swarm
        return {
            "positions": core.q[b].copy(),
            "velocities": core.p[b].copy(),
            "sim_time": float(core.t[b]),
            "steps": int(core.steps[b]),
        }

    def get_wrapper_attr(self, name: str) -> Any:
        return getattr(self, name)

    def __repr__(self) -> str:
        return f"AgentRow(index={self.index}, swarm={self.swarm}, agent={self.agent!r})"


class PairFlockSB3VecEnv(SwarmView, VecEnv):
    """SB3 ``VecEnv`` with one row per paired UAV, over one
    :class:`~pairflock_env.core.PairFlockCore` of ``num_swarms`` swarms, with parameter
    sharing: row ``b * M + m`` is paired UAV m of swarm b (M = 2 x pairs, ``agents_per_swarm``),
    so one policy drives every paired UAV. ``num_envs`` (SB3's name) = ``num_rows`` =
    ``num_swarms * M``.

    Observation/action/reward of a row are those of the learning interface ``interface``
    (:mod:`pairflock_env.interfaces`; ``"pair"`` by default, ``"world"`` for the raw env;
    parameters in ``interface_params``). One
    step is one policy decision: the action is held for the interface's ``decision_period``
    control steps and the reward is their mean.

    The SB3 contract, as ``DummyVecEnv`` implements it:

    * ``step_wait`` returns ``(obs (num_envs, n) float32, rewards (num_envs,) float32,
      dones (num_envs,) bool, infos list of dicts)``; every info has ``TimeLimit.truncated``
      (truncated and not terminated). A swarm whose episode ends marks all its rows done,
      stores each row's last observation in ``infos[i]["terminal_observation"]`` and is reset
      at once (without a seed: its generator continues); the returned observation is the
      first of the new episode.
    * ``seed(s)`` gives swarm b the seed ``s + b`` (a SeedSequence: its child b) at the next
      ``reset()`` (its rows all report that seed), so swarm b equals
      ``parallel_env().reset(seed=s + b)``; ``seed()`` with no argument draws a fresh seed
      from OS entropy (no global RNG). ``set_options({"positions": ..., "velocities": ...})``
      likewise applies at the next reset; every swarm's options are checked before any swarm
      is reset.
    * ``get_attr`` / ``set_attr`` / ``env_method`` address :class:`AgentRow` objects.
    * ``info_keys``: per-step core quantities copied into every row's info (names from
      ``AGENT_INFO_KEYS`` / ``SWARM_INFO_KEYS`` or ``"all"``); none by default, for speed.

    Invalid actions (wrong shape, non-numeric, NaN/inf) raise and leave the env unchanged;
    ``reset``/``step`` after ``close`` raise ``RuntimeError`` (``docs/bad-input.md``).
    """

    def __init__(
        self,
        preset: str | None = "paper",
        *,
        config: PairFlockConfig | None = None,
        num_swarms: int = 1,
        seed: Any = None,
        interface: str | None = None,
        interface_params: Mapping[str, Any] | None = None,
        render_mode: str | None = None,
        info_keys: Iterable[str] | str = (),
        **overrides: Any,
    ) -> None:
        self._open(
            preset=preset,
            config=config,
            overrides=overrides,
            num_swarms=num_swarms,
            seed=seed,
            interface=interface,
            interface_params=interface_params,
            render_mode=render_mode,
        )
        self.num_swarms = self.core.num_swarms
        self.agents_per_swarm = M = self.core.n_agents
        valid = AGENT_INFO_KEYS + SWARM_INFO_KEYS
        if isinstance(info_keys, str):
            if info_keys != "all":
                raise ValueError(f"info_keys={info_keys!r} is invalid: 'all' or a list of {valid}")
            info_keys = valid
        info_keys = tuple(info_keys)
        bad = [k for k in info_keys if k not in valid]
        if bad:
            raise ValueError(f"info_keys {bad} are invalid: valid keys are {list(valid)}")
        self.info_keys = info_keys
        self.num_rows = n_rows = self.num_swarms * M
        self._rows = [AgentRow(self, i) for i in range(n_rows)]
        obs_space = spaces.Box(*self.interface.observation_bounds(), dtype=np.float32)
        act_space = spaces.Box(-1.0, 1.0, (self.config.dim,), np.float32)
        super().__init__(n_rows, obs_space, act_space)
        self._actions: np.ndarray | None = None
        self._was_reset = False

    @property
    def reward_range(self) -> tuple[float, float]:
        """Every row's reward lies in this range (the interface's)."""
        return self.interface.reward_range

    # ------------------------------------------------------------------ seeding/reset
    def seed(self, seed: Any = None) -> Sequence[Any]:
        """Seeds for the next ``reset()``: swarm b gets ``seed + b`` (a SeedSequence: its
        child b; a list: one seed per swarm); ``None`` draws a fresh int seed from OS entropy.
        Returns one seed per row."""
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        per_swarm = offset_seeds(seed, self.num_swarms)
        M = self.agents_per_swarm
        self._seeds = [per_swarm[i // M] for i in range(self.num_envs)]
        return list(self._seeds)

    def set_options(self, options: dict | list[dict | None] | None = None) -> None:
        """Options for the next ``reset()``: one dict for every row or a list of ``num_envs``
        (SB3's convention); checked now (TypeError/ValueError naming the row)."""
        rows = options if isinstance(options, list) else [options] * self.num_envs
        if len(rows) != self.num_envs:
            raise ValueError(f"options has {len(rows)} entries, expected {self.num_envs} (rows)")
        N, D = self.config.n_uavs, self.config.dim
        for i, o in enumerate(rows):
            check_reset_options(o, 1, N, D, f"options of row {i}")
        super().set_options(options)

    def _per_swarm(self, values: list[Any], what: str) -> list[Any]:
        M = self.agents_per_swarm
        out = []
        for b in range(self.num_swarms):
            block = values[b * M : (b + 1) * M]
            first = block[0]
            for v in block[1:]:
                same = v is first or (
                    (v == first) if not isinstance(v, dict) else _same_options(v, first)
                )
                if not same:
                    raise ValueError(
                        f"{what} of rows {b * M}-{(b + 1) * M - 1} differ ({block!r}); the rows of "
                        "one swarm share its reset, so they must be equal"
                    )
            out.append(first)
        return out

    def reset(self):
        """Reset every swarm with the pending seeds and options; returns the observations."""
        self._check_open("reset")
        seeds = self._per_swarm(list(self._seeds), "seeds")
        options = self._per_swarm(list(self._options), "options")
        N, D = self.config.n_uavs, self.config.dim
        for b, o in enumerate(options):  # every swarm's options before the first reset
            check_reset_options(o or None, 1, N, D, f"options of swarm {b}")
        all_rows = np.arange(self.num_swarms)
        if all(not o for o in options):
            res = self.core.reset_rows(
                all_rows, seed=None if all(s is None for s in seeds) else seeds
            )
        else:
            res = None
            for b in all_rows:
                res = self.core.reset_rows([b], seed=[seeds[b]], options=options[b] or None)
        self._reset_seeds()
        self._reset_options()
        self._was_reset = True
        self._renderers.reset()
        self.physical_obs = res.obs.copy()
        self.reset_infos = [{} for _ in range(self.num_envs)]
        self._fill_infos(self.reset_infos, res.info, np.arange(self.num_swarms))
        return self.interface.encode(res.obs).reshape(self.num_envs, -1)

    # ------------------------------------------------------------------ step
    def step_async(self, actions: np.ndarray) -> None:
        """Validate and store the actions (num_envs, dim) of the next ``step_wait``."""
        self._check_open("step")
        self._actions = check_policy_actions(actions, (self.num_envs, self.config.dim))

    def step_wait(self):
        """One policy decision of every row, with SB3's auto-reset of ended swarms."""
        self._check_open("step")
        if not self._was_reset:
            raise RuntimeError("call reset() before step()")
        if self._actions is None:
            raise RuntimeError("step_wait() called without a pending step_async()")
        B, M, D = self.num_swarms, self.agents_per_swarm, self.config.dim
        a = self._actions.reshape(B, M, D)
        self._actions = None
        res = held_step(self.core, self.interface, self.physical_obs, a)
        rewards = res.reward.reshape(-1).astype(np.float32)
        term, trunc = res.terminated, res.truncated
        done_sw = term | trunc
        obs = self.interface.encode(res.obs)  # (B, M, n)
        infos: list[dict[str, Any]] = [{"TimeLimit.truncated": False} for _ in range(self.num_envs)]
        self._fill_infos(infos, res.info, np.arange(B))
        physical = res.obs
        if done_sw.any():
            ended = np.flatnonzero(done_sw)
            for b in ended:
                tl = bool(trunc[b] and not term[b])
                for m in range(M):
                    i = b * M + m
                    infos[i]["TimeLimit.truncated"] = tl
                    infos[i]["terminal_observation"] = obs[b, m].copy()
            rr = self.core.reset_rows(ended)
            physical = res.obs.copy()
            physical[ended] = rr.obs[ended]
            obs[ended] = self.interface.encode(rr.obs[ended])
            for b in ended:
                for m in range(M):
                    self.reset_infos[b * M + m] = {}
            self._fill_infos(self.reset_infos, rr.info, ended)
            self._renderers.reset(set(ended.tolist()))
        self.physical_obs = physical.copy()
        dones = np.repeat(done_sw, M)
        if self.render_mode == "human":
            self.render()
        return obs.reshape(self.num_envs, -1), rewards, dones, infos

    def _fill_infos(
        self, infos: list[dict[str, Any]], info: Mapping[str, np.ndarray], swarms
    ) -> None:
        if not self.info_keys:
            return
        M = self.agents_per_swarm
        vals = {k: info[k].tolist() for k in self.info_keys}
        for b in swarms:
            for m in range(M):
                d = infos[b * M + m]
                for k, v in vals.items():
                    d[k] = v[b][m] if isinstance(v[b], list) else v[b]

    # ------------------------------------------------------------------ state
    def get_state(self) -> dict[str, Any]:
        """A deep copy of everything that determines the following steps (the core's state and
        per-swarm generators, the last physical observation, pending seeds/options); with
        :meth:`set_state` it makes a checkpointed run continue exactly."""
        return {
            "config": self.config.to_dict(),
            "core": copy.deepcopy(self.core),
            "physical_obs": None if self.physical_obs is None else self.physical_obs.copy(),
            "seeds": list(self._seeds),
            "options": copy.deepcopy(self._options),
            "was_reset": self._was_reset,
        }

    def set_state(self, state: Mapping[str, Any]) -> None:
        """Restore a :meth:`get_state` snapshot taken from an env with the same config and size."""
        if not isinstance(state, Mapping) or "core" not in state:
            raise TypeError("state must be a dict returned by PairFlockSB3VecEnv.get_state()")
        if state["config"] != self.config.to_dict():
            raise ValueError("state was taken from an env with a different config")
        core = state["core"]
        if core.num_swarms != self.num_swarms:
            raise ValueError(
                f"state has {core.num_swarms} swarms, this env has num_swarms={self.num_swarms}"
            )
        self._renderers.close()
        self.core = copy.deepcopy(core)
        self._renderers = SwarmRenderers(self.core, self.render_mode)
        po = state["physical_obs"]
        self.physical_obs = None if po is None else po.copy()
        self._seeds = list(state["seeds"])
        self._options = copy.deepcopy(state["options"])
        self._was_reset = bool(state["was_reset"])
        self._actions = None

    # ------------------------------------------------------------------ attributes
    def _target_rows(self, indices) -> list[AgentRow]:
        return [self._rows[i] for i in self._get_indices(indices)]

    def _get_indices(self, indices) -> Iterable[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, (int, np.integer)):
            idx = [int(indices)]
        else:
            idx = [int(i) for i in indices]
        for i in idx:
            if not -self.num_envs <= i < self.num_envs:
                raise IndexError(f"indices={indices!r} is invalid: rows are 0..{self.num_envs - 1}")
        return idx

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [getattr(r, attr_name) for r in self._target_rows(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        for r in self._target_rows(indices):
            setattr(r, attr_name, value)

    def env_method(
        self, method_name: str, *method_args, indices=None, **method_kwargs
    ) -> list[Any]:
        return [
            getattr(r, method_name)(*method_args, **method_kwargs)
            for r in self._target_rows(indices)
        ]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        """One frame per row (its swarm's), with ``render_mode="rgb_array"``."""
        if self.render_mode != "rgb_array":
            warnings.warn(
                f"The render mode is {self.render_mode}, but get_images() needs 'rgb_array'",
                stacklevel=2,
            )
            return [None] * self.num_envs
        frames = [self._renderers.render(b) for b in range(self.num_swarms)]
        return [frames[i // self.agents_per_swarm] for i in range(self.num_envs)]

    def close(self) -> None:
        """Release the renderers; the env cannot be reset or stepped afterwards."""
        self._renderers.close()
        self._mark_closed()


def _same_options(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    if a.keys() != b.keys():
        return False
    return all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in a)
