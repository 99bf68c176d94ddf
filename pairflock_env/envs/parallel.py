"""PettingZoo view of one swarm: the paired UAVs are the agents."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from pairflock_env.config import PairFlockConfig
from pairflock_env.core import AGENT_INFO_KEYS, SWARM_INFO_KEYS
from pairflock_env.envs._base import RENDER_MODES, SwarmView, check_policy_actions, held_step
from pairflock_env.seeding import check_seed
from pairflock_env.task.observations import ObsLayout
from pairflock_env.task.spaces import StateLayout, global_state, state_bounds

__all__ = ["PairFlockParallelEnv", "agent_name", "parallel_env"]


#: dtypes that real_array takes as they are (real, at most 64 bits): copied into float64 exactly
_PLAIN = dict.fromkeys(np.typecodes["Float"][:-1] + np.typecodes["AllInteger"], True)


def agent_name(uav_index: int) -> str:
    """The agent name of UAV ``uav_index``: ``"uav_<i>"``."""
    return f"uav_{uav_index}"


_DOC = """A UAV swarm flocking with the protocol of eqs. 11-19; each paired UAV is an agent
that chooses its own pairwise acceleration f^x_i (the pair term of eq. 11).

Every UAV flies the analytic flocking protocol (attraction/repulsion within the perception
radius, velocity consensus, pinning to a virtual leader). The paired UAVs additionally apply
the agents' actions. The paper's sliding-mode controller (eq. 28), its proportional
"normal method" (eq. 44) and learned policies all act through this same slot
(``baselines.make_pair_policy``).

## Agents
``uav_<i>`` for every UAV i of ``config.pairs`` (default ``uav_0`` and ``uav_1``);
``env.partners`` maps each agent to its partner's name.

## Interfaces
``interface="world"`` (default) is the physical env below. ``interface="pair"`` gives each
agent the learning interface of the Gymnasium view (:mod:`pairflock_env.interfaces`): the
normalised pair-frame observation in ``[-5, 5]``, a pair-frame action on top of a
feed-forward, the bounded pair-frame reward, and one ``step`` per policy decision (the action
is held for ``decision_period`` control steps, the reward is their mean).
``interface_params`` sets its parameters.

## Action space
``Box(-1, 1, (dim,), float32)``: the UAV's pairwise acceleration in the world frame, in units
of ``pair_accel_limit`` m/s^2 (action 1.0 = ``pair_accel_limit``; 1000 m/s^2 in the paper
preset, above the ~420 m/s^2 peak of sliding mode). Finite values outside [-1, 1] are clipped
per component and reported in ``infos[agent]["action_clipped"]``; NaN/inf, a wrong shape, a
non-numeric dtype, or a missing/unknown agent raise an exception and leave the env unchanged
(``docs/bad-input.md``).

## Observation space
``Box(low, high, (obs_size,), float32)``, physical units, relative to the observing UAV, with
finite bounds derived from the config (:mod:`pairflock_env.task.spaces`: positions within
``divergence_limit``, flocking commands bounded by the gains). The layout below is for
dim = 2 and ``obs_neighbors`` = 6; read fields by name with
``env.layout.get(obs, "partner_offset")``.

{table}

## State (centralised critics)
``env.state()`` is the swarm's global state, float32, in ``env.state_space`` (bounded like
the observation; a diverged swarm's state, at the end of its episode, is clipped into it);
``env.state_layout`` names its fields (shown for 3 UAVs in 2-D):

{state_table}

## Rewards
Per agent, a sum of penalties (see ``pairflock_env.task.rewards``):
``-w_err |pair error| - w_u (||u|| / limit)^2 - w_sep max(0, safe - sep)/safe
- w_col [sep < collision_distance]``; ``-100`` on the step a swarm diverges. The scale is
metres of pair error per control step: about -250 per agent-step at the paper's start and
episode returns of order -1e5. ``interface="pair"`` gives a normalised reward of order one
per step; ``env.reward_range`` is the guaranteed range of either.

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
All agents end together. ``step`` after the end, ``step``/``render``/``state`` before
``reset`` and ``reset``/``step`` after ``close`` raise ``RuntimeError``.

## Infos (per agent)
Numbers only: {info_keys}, plus ``reward_<term>`` for each reward term, ``uav_index`` and
``partner_index`` (UAV indices). With ``dynamics="quadrotor"`` also ``crashed``,
``motor_saturated``, ``accel_limited``, ``tilt`` (deg) of the agent and the swarm counts
``vehicle_terminated``, ``crashed_uavs``, ``motor_saturated_uavs``, ``accel_limited_uavs``.

## Arguments
``preset`` (default ``"paper"``), ``config`` (a ``PairFlockConfig``), ``interface``
(``"world"`` or ``"pair"``), ``interface_params`` (dict), ``render_mode`` (``"rgb_array"`` or
``"human"``), ``seed`` (of the swarm generator when ``reset`` gets none) and any
``PairFlockConfig`` field as a keyword (``n_uavs=100``, ``d_m=4.0``, ``max_cycles=500``,
...).

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


class PairFlockParallelEnv(SwarmView, ParallelEnv):
    __doc__ = _DOC.format(
        table=ObsLayout(2, 6).markdown_table(),
        state_table=StateLayout(3, 2).markdown_table(),
        info_keys=", ".join(f"``{k}``" for k in AGENT_INFO_KEYS + SWARM_INFO_KEYS),
    )

    metadata = {
        "name": "pairflock_v0",
        "render_modes": list(RENDER_MODES),
        "render_fps": 25,
        "is_parallelizable": True,
    }

    default_interface = "world"

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
        cfg = self.config
        self.state_layout = StateLayout(cfg.n_uavs, cfg.dim)
        self.render_mode = render_mode
        self.possible_agents = [agent_name(i) for i in self.core.agent_uavs]
        self.agents: list[str] = []
        self._agent_index = {a: m for m, a in enumerate(self.possible_agents)}
        self._action_names = {a: f"action of {a}" for a in self.possible_agents}
        self._action_shape = (cfg.dim,)
        # the infos every step adds to each agent's own
        self._agent_consts = [
            {"uav_index": int(a), "partner_index": int(b)}
            for a, b in zip(self.core.agent_uavs, self.core.partner_uavs, strict=True)
        ]
        self.partners = {
            agent_name(int(a)): agent_name(int(b))
            for a, b in zip(self.core.agent_uavs, self.core.partner_uavs, strict=True)
        }
        low, high = self.interface.observation_bounds()
        # distinct objects per agent so that seeding one agent's space does not seed another's
        self.observation_spaces = {
            a: spaces.Box(low, high, dtype=np.float32) for a in self.possible_agents
        }
        self.action_spaces = {
            a: spaces.Box(-1.0, 1.0, (cfg.dim,), np.float32) for a in self.possible_agents
        }
        self.state_space = spaces.Box(*state_bounds(cfg), dtype=np.float32)
        self._title_values: tuple[float, float] | None = None  # of the render title

    # PettingZoo requires the same object on every call
    def observation_space(self, agent: str) -> spaces.Box:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Box:
        return self.action_spaces[agent]

    @property
    def num_swarms(self) -> int:
        """1: one swarm (the batched views are the Gymnasium vector and SB3 envs)."""
        return 1

    @property
    def reward_range(self) -> tuple[float, float]:
        """Every per-agent reward lies in this range (the interface's)."""
        return self.interface.reward_range

    # ------------------------------------------------------------------ API
    def reset(self, seed: Any = None, options: Mapping[str, Any] | None = None):
        """Start an episode; ``seed`` (None, an int >= 0 or a SeedSequence) reseeds the swarm's
        generator, ``options`` may set ``positions`` / ``velocities`` (n_uavs, dim)."""
        self._check_open("reset")
        seed = check_seed(seed)
        res = self.core.reset(seed=None if seed is None else [seed], options=options)
        self.agents = list(self.possible_agents)
        self._renderers.reset()
        return self._emit(res.obs), self._infos(res.info)

    def check_action(self, agent: Any, action: Any) -> np.ndarray:
        """``action`` of the live agent ``agent`` as float64 (dim,); ValueError/TypeError
        naming the agent otherwise (nothing changes)."""
        if agent not in self._agent_index:
            raise ValueError(f"unknown agent {agent!r}; agents are {self.possible_agents}")
        if agent not in self.agents:
            raise RuntimeError(f"agent {agent!r} is done; call reset()")
        shape = self._action_shape
        x = action  # the usual case inline (what real_array does with it); anything else below
        plain = type(x) is np.ndarray and x.shape == shape and _PLAIN.get(x.dtype.char)
        if plain and np.isfinite(x).all():
            return x.astype(np.float64, copy=False)
        return check_policy_actions(action, shape, self._action_names[agent])

    def _check_action_dict(self, actions: Any) -> np.ndarray:
        if type(actions) is not dict and not isinstance(actions, Mapping):
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
        live, shape = self.agents, self._action_shape
        out = np.empty((1, len(self.possible_agents), *shape))
        for a, m in self._agent_index.items():  # the usual case: real ndarrays, one check
            x = actions[a] if a in live else None
            if not (type(x) is np.ndarray and x.shape == shape and _PLAIN.get(x.dtype.char)):
                break
            out[0, m] = x
        else:
            if np.isfinite(out).all():
                return out
        # anything else: check_action's per-agent conversion and first error, in agent order
        for a, m in self._agent_index.items():
            if a not in live:
                raise RuntimeError(f"agent {a!r} is done; call reset()")
            out[0, m] = check_policy_actions(actions[a], shape, self._action_names[a])
        return out

    def step(self, actions: Mapping[str, Any]):
        """One step (one policy decision of ``decision_period`` control steps with
        ``interface="pair"``) of every agent; returns PettingZoo's five dicts."""
        self._check_open("step")
        if not self.agents:
            raise RuntimeError("the episode has ended (or reset() was never called); call reset()")
        a = self._check_action_dict(actions)
        res = held_step(self.core, self.interface, self.physical_obs[None], a)
        agents = self.possible_agents
        obs = self._emit(res.obs)
        rewards = dict(zip(agents, res.reward.tolist()[0], strict=True))
        term = res.terminated.item(0)  # a Python bool
        trunc = res.truncated.item(0)
        terminations = dict.fromkeys(agents, term)
        truncations = dict.fromkeys(agents, trunc)
        infos = self._infos(res.info)
        if term or trunc:
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terminations, truncations, infos

    def _emit(self, phys: np.ndarray):
        """Observations of swarm 0 by agent; keeps the physical observation."""
        self.physical_obs = phys[0]
        return dict(zip(self.possible_agents, self.interface.encode(phys[0]), strict=True))

    def _infos(self, info: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
        # (B,) arrays are swarm-level, (B, M) arrays per agent, (B, ...) anything else; each
        # agent's dict: its per-agent values, then the swarm's, then its UAV indices
        keys, columns, swarm = [], [], {}
        for k, v in info.items():
            if v.ndim == 2:
                keys.append(k)
                columns.append(v.tolist()[0])
            elif v.ndim == 1:
                swarm[k] = v.item(0)
        out = {}
        rows = zip(*columns, strict=True) if columns else ((),) * len(self.possible_agents)
        for a, row, consts in zip(self.possible_agents, rows, self._agent_consts, strict=True):
            d = dict(zip(keys, row, strict=True))
            d.update(swarm)
            d.update(consts)
            out[a] = d
        first = out[self.possible_agents[0]]
        self._title_values = (first["sim_time"], first["pair_distance"])
        return out

    def state(self) -> np.ndarray:
        """The global state now (``state_layout``), float32 in ``state_space`` (the state of a
        diverged swarm, whose episode has ended, is clipped into it)."""
        if self.physical_obs is None:
            raise RuntimeError("call reset() before state()")
        c = self.core
        lq, lp = c.leader_state()
        s = global_state(self.config, c.q[0], c.p[0], lq[0], lp[0], c.t[0])
        return np.clip(np.nan_to_num(s), self.state_space.low, self.state_space.high)

    def render(self):
        """The swarm as an RGB array (``render_mode="rgb_array"``) or in a window."""
        title = None
        if self._title_values is not None:
            t, dist = self._title_values
            title = f"t = {t:.2f} s   pair distance = {dist:.2f} m"
        return self._renderers.render(0, title)

    def close(self) -> None:
        """Release the renderer; the env cannot be reset or stepped afterwards."""
        self._renderers.close()
        self._mark_closed()


def parallel_env(**kwargs: Any) -> PairFlockParallelEnv:
    """The PettingZoo ParallelEnv (see :class:`PairFlockParallelEnv` for arguments)."""
    return PairFlockParallelEnv(**kwargs)
