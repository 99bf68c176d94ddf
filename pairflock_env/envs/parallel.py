"""PettingZoo view of one swarm: the paired UAVs are the agents."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv
from pettingzoo.utils.conversions import parallel_to_aec

from ..config import PairFlockConfig, make_config
from ..core import AGENT_INFO_KEYS, SWARM_INFO_KEYS, PairFlockCore, real_array
from ..observations import ObsLayout
from ..render import SwarmRenderer

__all__ = ["PairFlockParallelEnv", "agent_name", "env", "parallel_env", "raw_env"]

RENDER_MODES = ("rgb_array", "human")


def agent_name(uav_index: int) -> str:
    return f"uav_{uav_index}"


_DOC = """A UAV swarm flocking with the protocol of eqs. 11-19; each paired UAV is an agent
that chooses its own pairwise acceleration f^x_i (the pair term of eq. 11).

Every UAV flies the analytic flocking protocol (attraction/repulsion within the perception
radius, velocity consensus, pinning to a virtual leader). The paired UAVs additionally apply
the agents' actions. The paper's sliding-mode controller (eq. 28), its proportional
"normal method" (eq. 44) and learned policies all act through this same slot
(``baselines.make_pair_policy``).

## Agents
``uav_<i>`` for every UAV i of ``config.pairs`` (default ``uav_0`` and ``uav_1``).

## Action space
``Box(-1, 1, (dim,), float32)``: the UAV's pairwise acceleration in the world frame, in units
of ``pair_accel_limit`` m/s^2 (action 1.0 = ``pair_accel_limit``; 1000 m/s^2 in the paper
preset, above the ~420 m/s^2 peak of sliding mode). Finite values outside [-1, 1] are clipped
per component and reported in ``infos[agent]["action_clipped"]``; NaN/inf, a wrong shape, a
non-numeric dtype, or a missing/unknown agent raise an exception and leave the env unchanged.

## Observation space
``Box(-inf, inf, (obs_size,), float32)``, physical units, relative to the observing UAV.
The layout below is for dim = 2 and ``obs_neighbors`` = 6; read fields by name with
``env.layout.get(obs, "partner_offset")``.

{table}

## Rewards
Per agent, a sum of penalties (see ``pairflock_env.rewards``):
``-w_err |pair error| - w_u (||u|| / limit)^2 - w_sep max(0, safe - sep)/safe
- w_col [sep < collision_distance]``; ``-100`` on the step a swarm diverges.

## Vehicle models
``dynamics="particle"`` (default): every UAV is a double integrator of the commanded
acceleration (eq. 1). ``dynamics="quadrotor"`` (3-D; preset ``"paper-quadrotor"``, Sec. VI-B):
every UAV is a 6-DOF rigid body with four rotors whose geometric SO(3) controller tracks
the same commanded acceleration (flocking + pair action) at ``dt / substeps`` (500 Hz),
within an acceleration limit and a tilt cone; observations, actions, rewards, seeds and
baselines are the same. Airframe parameters (``quad_*``), what the extra infos mean and the
crash semantics are in ``docs/quadrotor.md``.

## Starting state
``init="corners"``: pair members at ``swarm_center`` -/+ ``pair_corner`` on every axis (the
paper's (-90, -90) and (90, 90)), other UAVs uniform in ``swarm_center`` +- ``swarm_half_width``
([-50, 50]^dim in the paper preset), no two closer than ``min_init_spacing``, everyone at
rest (quadrotors level, rotors at hover speed).
``reset(options={{"positions": ..., "velocities": ...}})`` sets the state explicitly.

## Episode end
Truncation after ``config.episode_steps`` control steps (50 s in the paper preset; override
with ``max_cycles`` or ``horizon``). Termination when the state diverges (non-finite or
beyond ``divergence_limit``; ``infos[agent]["diverged"]``), on a collision when
``terminate_on_collision=True``, or when a quadrotor crashes (flipped beyond
``quad_crash_tilt`` or below ``quad_ground_altitude``; ``infos[agent]["vehicle_terminated"]``).
All agents end together.

## Infos (per agent)
{info_keys}, plus ``reward_<term>`` for each reward term. With ``dynamics="quadrotor"`` also
``crashed``, ``motor_saturated``, ``accel_limited``, ``tilt`` (deg) of the agent and the swarm
counts ``vehicle_terminated``, ``crashed_uavs``, ``motor_saturated_uavs``,
``accel_limited_uavs``.

## Arguments
``preset`` (default ``"paper"``), ``config`` (a ``PairFlockConfig``), ``render_mode``
(``"rgb_array"`` or ``"human"``) and any ``PairFlockConfig`` field as a keyword
(``n_uavs=100``, ``d_m=4.0``, ``max_cycles=500``, ...).

## Example
>>> from pairflock_env import parallel_env
>>> env = parallel_env(preset="paper", n_uavs=20)
>>> obs, infos = env.reset(seed=0)
>>> actions = {{a: env.action_space(a).sample() for a in env.agents}}
>>> obs, rewards, terms, truncs, infos = env.step(actions)
>>> round(infos["uav_0"]["sim_time"], 2)
0.01

## Version history
* v0: initial release.
"""


class PairFlockParallelEnv(ParallelEnv):
    __doc__ = _DOC.format(
        table=ObsLayout(2, 6).markdown_table(),
        info_keys=", ".join(f"``{k}``" for k in AGENT_INFO_KEYS + SWARM_INFO_KEYS),
    )

    metadata = {
        "name": "pairflock_v0",
        "render_modes": list(RENDER_MODES),
        "render_fps": 25,
        "is_parallelizable": True,
    }

    def __init__(
        self,
        preset: str | None = "paper",
        *,
        config: PairFlockConfig | None = None,
        render_mode: str | None = None,
        seed: int | None = None,
        **overrides: Any,
    ) -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(
                f"render_mode={render_mode!r} is invalid: must be None or one of {RENDER_MODES}"
            )
        if config is None:
            config = make_config(preset, **overrides)
        elif overrides:
            config = config.replace(**overrides)
        self.core = PairFlockCore(config, num_envs=1, seed=seed)
        self.config = self.core.config
        self.layout = self.core.layout
        self.render_mode = render_mode
        self.possible_agents = [agent_name(i) for i in self.core.agent_uavs]
        self.agents: list[str] = []
        self._agent_index = {a: m for m, a in enumerate(self.possible_agents)}
        obs_space = spaces.Box(-np.inf, np.inf, (self.layout.size,), np.float32)
        act_space = spaces.Box(-1.0, 1.0, (self.config.dim,), np.float32)
        self.observation_spaces = dict.fromkeys(self.possible_agents, obs_space)
        self.action_spaces = dict.fromkeys(self.possible_agents, act_space)
        # distinct objects per agent so that seeding one agent's space does not seed another's
        for a in self.possible_agents[1:]:
            self.observation_spaces[a] = spaces.Box(
                -np.inf, np.inf, (self.layout.size,), np.float32
            )
            self.action_spaces[a] = spaces.Box(-1.0, 1.0, (self.config.dim,), np.float32)
        self._renderer: SwarmRenderer | None = None
        self._last_info: list[dict[str, Any]] | None = None

    # PettingZoo requires the same object on every call
    def observation_space(self, agent: str) -> spaces.Box:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Box:
        return self.action_spaces[agent]

    @property
    def num_envs(self) -> int:
        return 1

    # ------------------------------------------------------------------ API
    def reset(self, seed: int | None = None, options: Mapping[str, Any] | None = None):
        res = self.core.reset(seed=None if seed is None else [seed], options=options)
        self.agents = list(self.possible_agents)
        if self._renderer is not None:
            self._renderer.reset()
        obs = {a: res.obs[0, m] for m, a in enumerate(self.possible_agents)}
        infos = self._infos(res.info)
        if self.render_mode == "human":
            self.render()
        return obs, infos

    def _check_action_dict(self, actions: Any) -> np.ndarray:
        if not isinstance(actions, Mapping):
            raise TypeError(
                f"actions must be a dict {{agent: action}}, got {type(actions).__name__}"
            )
        unknown = [k for k in actions if k not in self._agent_index]
        if unknown:
            raise ValueError(
                f"unknown agent(s) {unknown} in actions; agents are {self.possible_agents}"
            )
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"missing action for agent(s) {missing}; every live agent must act")
        D = self.config.dim
        out = np.empty((1, len(self.possible_agents), D))
        for a, m in self._agent_index.items():
            act = real_array(actions[a], f"action of {a}", (D,))
            out[0, m] = act
        return out

    def step(self, actions: Mapping[str, Any]):
        if not self.agents:
            raise RuntimeError("the episode has ended (or reset() was never called); call reset()")
        a = self._check_action_dict(actions)
        res = self.core.step(a)
        agents = self.possible_agents
        obs = {ag: res.obs[0, m] for m, ag in enumerate(agents)}
        r = res.reward[0].tolist()
        rewards = dict(zip(agents, r, strict=False))
        term = bool(res.terminated[0])
        trunc = bool(res.truncated[0])
        terminations = dict.fromkeys(agents, term)
        truncations = dict.fromkeys(agents, trunc)
        infos = self._infos(res.info)
        if term or trunc:
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terminations, truncations, infos

    def _infos(self, info: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
        # (B,) arrays are swarm-level, (B, M) arrays per agent, (B, ...) anything else
        swarm = {k: v[0].item() for k, v in info.items() if v.ndim == 1}
        per_agent = {k: v[0].tolist() for k, v in info.items() if v.ndim == 2}
        out = {}
        for m, a in enumerate(self.possible_agents):
            d = {k: v[m] for k, v in per_agent.items()}
            d.update(swarm)
            d["uav_index"] = int(self.core.agent_uavs[m])
            d["partner"] = agent_name(int(self.core.partner_uavs[m]))
            out[a] = d
        self._last_info = list(out.values())
        return out

    def render(self):
        if self.render_mode is None:
            import warnings

            warnings.warn(
                "render() called without a render_mode; pass render_mode=...", stacklevel=2
            )
            return None
        if self._renderer is None:
            self._renderer = SwarmRenderer(self.config.pairs, self.config.d_m, self.render_mode)
        core = self.core
        lq, _ = core.leader_state()
        info = self._last_info[0] if self._last_info else None
        title = None
        if info is not None:
            title = f"t = {info['sim_time']:.2f} s   pair distance = {info['pair_distance']:.2f} m"
        if self.render_mode == "rgb_array":
            return self._renderer.rgb_array(core.q[0], core.p[0], lq[0], title)
        self._renderer.human(core.q[0], core.p[0], lq[0], title)
        return None

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


def parallel_env(**kwargs: Any) -> PairFlockParallelEnv:
    """The PettingZoo ParallelEnv (see :class:`PairFlockParallelEnv` for arguments)."""
    return PairFlockParallelEnv(**kwargs)


def raw_env(**kwargs: Any):
    """The AEC env built from the parallel env by PettingZoo's converter (order enforced)."""
    return parallel_to_aec(parallel_env(**kwargs))


def env(**kwargs: Any):
    """The AEC env (PettingZoo's standard entry point)."""
    return raw_env(**kwargs)
