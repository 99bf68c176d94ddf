"""PairFlockCore: B swarms of N UAVs in one set of arrays, the engine behind every view.

One control step (:meth:`PairFlockCore.step`), stage by stage:

1. validate the pair actions (B, M, dim) (M = 2 x pairs; before any state changes):
   :func:`~pairflock_env.task.actions.check_pair_actions`;
2. decode: clip to [-1, 1], scale by ``pair_accel_limit`` to m/s^2, giving the pair command
   u = f^x of every paired UAV (:meth:`PairFlockCore.decode_actions`); with
   ``safety_filter="cbf"`` each paired UAV then filters its u from what it senses
   (:class:`~pairflock_env.safety.stage.CBFStage`, docs/safety.md), or, with
   ``safety_scope="swarm"``, every UAV filters its whole command f (+ u)
   (:class:`~pairflock_env.safety.stage.SwarmStage`, docs/swarm-safety.md);
3. a_des = flocking command of the current state (eqs. 11-19) + u on the paired UAVs
   (+ the random disturbance, when configured);
4. the vehicle model integrates ``substeps`` physics steps with a_des held;
5. the clock and the leader advance; one pass computes the flocking command of the new
   state together with separations, collisions and connectivity; observations
   (:mod:`~pairflock_env.task.observations`, through the partner delay and sensor noise),
   rewards and termination (:mod:`~pairflock_env.task.rewards`) and infos
   (:mod:`~pairflock_env.task.infos`) follow.

The flocking command of stage 3 was computed at the end of the previous step (or at reset),
so each step does exactly one pass: over all pairs (O(N^2)) or, with ``neighbor_search``
resolving to the grid, over a :class:`~pairflock_env.swarm.grid.NeighborGrid` rebuilt from
the positions first (O(N)); both give the same results. Initial states come from
:mod:`~pairflock_env.swarm.placement`. Views (PettingZoo, Gymnasium, SB3) only validate, reshape,
name agents and apply their auto-reset rule.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from pairflock_env.config import PairFlockConfig, make_config
from pairflock_env.config.arrays import real_array
from pairflock_env.dynamics import ParticleModel, QuadrotorModel, make_vehicle
from pairflock_env.kernels import jit_kernel
from pairflock_env.safety import make_safety_stage
from pairflock_env.safety.stage import NoFilterStage
from pairflock_env.seeding import swarm_generators
from pairflock_env.swarm.grid import NeighborGrid
from pairflock_env.swarm.leader import make_leader
from pairflock_env.swarm.passes import NeighborPass
from pairflock_env.swarm.placement import check_reset_options, initial_state, pinning_mask
from pairflock_env.task.actions import add_pair_command, check_pair_actions, decode_pair_actions
from pairflock_env.task.agent_pass import AGENT_ROWS, AgentPass
from pairflock_env.task.delay import PartnerDelayBuffer
from pairflock_env.task.infos import (
    AGENT_INFO_KEYS,
    SAFETY_SWARM_INFO_KEYS,
    SWARM_INFO_KEYS,
    StepResult,
    hold_last_finite,
    make_info,
)
from pairflock_env.task.observations import (
    OBSERVATIONS,
    ObservationContext,
    ObsLayout,
    add_sensor_noise,
)
from pairflock_env.task.rewards import DIVERGENCE_PENALTY, REWARD_TERMS, episode_end, may_overflow

__all__ = [
    "AGENT_INFO_KEYS",
    "SWARM_INFO_KEYS",
    "PairFlockCore",
    "SeedLike",
    "StepResult",
    "check_count",
    "real_array",
]

SeedLike = int | np.random.SeedSequence | None

#: a diverging swarm overflows on its way out; the step checks its results itself (a swarm
#: with non-finite values is flagged ``diverged``), so numpy's warnings would only be noise
_CHECKED_FP = dict(over="ignore", invalid="ignore", divide="ignore")


@jit_kernel
def _tick(steps, t, dt):
    """One control step more on every swarm's clock: t = steps dt."""
    for b in range(steps.shape[0]):
        steps[b] += 1
        t[b] = steps[b] * dt


def check_count(name: str, value: Any) -> None:
    """A count of swarms: ``TypeError`` unless an integer, ``ValueError`` unless >= 1."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}={value!r} is invalid: must be an integer >= 1")
    if value < 1:
        raise ValueError(f"{name}={value!r} is invalid: must be an integer >= 1")


class PairFlockCore:
    """Vectorised pair-flocking simulator.

    Args:
        config: a :class:`PairFlockConfig`, or ``None`` to build one from ``preset`` and
            ``overrides``.
        num_swarms: number of swarms B simulated side by side.
        seed: seed of the per-swarm generators (see :meth:`reset`).

    Attributes (read-only views of the state; use :meth:`reset` / :meth:`step` to change it):
        q, p: positions and velocities, (B, N, dim) float64.
        t: sim time of each swarm (B,), s.  steps: control steps since reset (B,).
    """

    def __init__(
        self,
        config: PairFlockConfig | None = None,
        num_swarms: int = 1,
        seed: SeedLike = None,
        *,
        preset: str | None = "paper",
        **overrides: Any,
    ) -> None:
        if config is None:
            config = make_config(preset, **overrides)
        elif not isinstance(config, PairFlockConfig):
            hint = f" (for a preset: preset={config!r})" if isinstance(config, str) else ""
            raise TypeError(
                f"config={config!r} is invalid: must be a PairFlockConfig or None{hint}"
            )
        elif overrides:
            config = config.replace(**overrides)
        check_count("num_swarms", num_swarms)
        self.config = cfg = config
        self.num_swarms = B = int(num_swarms)
        N, D = cfg.n_uavs, cfg.dim
        self.layout = ObsLayout.for_config(cfg)

        # the passes of the current state, and the agents' indexing (one definition, there)
        self._neighbors = sw = NeighborPass(cfg, B)
        self.agent_uavs, self.partner_uavs = sw.agent_uavs, sw.partner_uavs  # (M,) A0, B0, ...
        self.agent_pair, self.partner_of = sw.agent_pair, sw.partner_of  # (M,), (N,)
        self._agent_dm = sw.agent_dm  # (M,)
        self._agents = AgentPass(
            cfg, self.layout, self.agent_uavs, self.partner_uavs, self.agent_pair, sw.agent_dm
        )
        self._leader = make_leader(cfg)
        self.vehicle = make_vehicle(cfg, B)
        # stage 2b (safety_filter); the partner is constrained at any distance
        self.safety = make_safety_stage(cfg, self.agent_uavs, B, self.partner_uavs)
        self.q = np.zeros((B, N, D))
        self.p = np.zeros((B, N, D))
        self.t = np.zeros(B)
        self.steps = np.zeros(B, np.int64)
        self._pinned = np.zeros((B, N))
        #: the pair command (B, M, dim), m/s^2, the last step applied (after the safety stage)
        self.pair_command = np.zeros((B, len(self.agent_uavs), D))
        self._flock_out: dict[str, np.ndarray] | None = None
        M = len(self.agent_uavs)
        self._obs = np.zeros((B, M, self.layout.size), np.float32)
        self._info: dict[str, np.ndarray] | None = None  # the last step's infos
        self._noise: tuple[np.ndarray, ...] | None = None  # this step's sensor noise
        partner_col = np.arange(M) ^ 1  # agent column of each agent's partner
        self._delay = (
            PartnerDelayBuffer(cfg.partner_delay, B, M, D, partner_col)
            if cfg.partner_delay
            else None
        )
        self._is_reset = np.zeros(B, bool)
        self._all_reset = False
        self._check_finite = may_overflow(cfg)
        #: whether the agents perceive something other than the true state (delay, noise) or
        #: extra fields: those fields are then filled on top of the agents' pass
        noisy = cfg.obs_noise_position > 0 or cfg.obs_noise_velocity > 0
        self._perceived = bool(cfg.partner_delay or noisy or cfg.obs_extra)
        #: whether a step does no numpy arithmetic that could overflow (a diverging swarm's
        #: overflow would only raise warnings, which the step masks otherwise)
        self._no_filter = type(self.safety) is NoFilterStage
        numba_stages = type(self.vehicle) in (ParticleModel, QuadrotorModel)
        numba_stages &= cfg.safety_filter == "none" and cfg.disturbance_std == 0
        self._quiet = numba_stages and not (self._perceived or self._check_finite)
        self._rngs: list[np.random.Generator] = [
            g if g is not None else np.random.default_rng() for g in self._make_rngs(seed, B)
        ]

    # ------------------------------------------------------------------ properties
    @property
    def n_agents(self) -> int:
        """M: the number of paired UAVs (agents), two per pair."""
        return self.agent_uavs.shape[0]

    @property
    def obs_size(self) -> int:
        """Length of one agent's observation vector (``layout.size``)."""
        return self.layout.size

    @property
    def action_size(self) -> int:
        """Length of one agent's action vector (``dim``)."""
        return self.config.dim

    @property
    def rngs(self) -> tuple[np.random.Generator, ...]:
        """The per-swarm generators (initial states are drawn from these only)."""
        return tuple(self._rngs)

    def leader_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Virtual leader position and velocity now, each (B, dim)."""
        return self._leader.state(self.t)

    @property
    def flock_accel(self) -> np.ndarray:
        """Flocking command (eq. 11 without f^x) of the current state, (B, N, dim)."""
        self._require_reset()
        return self._flock_out["acc"]

    @property
    def closest_distance(self) -> np.ndarray:
        """Each UAV's distance to its nearest other UAV (its partner excluded) in the current
        state, (B, N), m (a new array; inf with no other UAV)."""
        self._require_reset()
        return np.sqrt(self._flock_out["min_d2"])

    @property
    def neighbor_grid(self) -> NeighborGrid | None:
        """The neighbour grid of the current state, built by the last pass (``None`` with
        all-pairs search): a stage that needs the neighbours of the current state (a safety
        filter between decoding and the desired acceleration) queries it."""
        return self._neighbors.grid

    @property
    def pinned(self) -> np.ndarray:
        """h_i of eq. 6 as 0/1 floats, (B, N)."""
        return self._pinned

    # ------------------------------------------------------------------ seeding
    @staticmethod
    def _make_rngs(seed: Any, n: int) -> list[np.random.Generator]:
        return swarm_generators(seed, n)

    # ------------------------------------------------------------------ reset
    def reset(self, seed: Any = None, options: Mapping[str, Any] | None = None) -> StepResult:
        """Reset every swarm.

        ``seed``: ``None`` continues each swarm's generator; an int or SeedSequence s gives
        swarm b the generator of ``SeedSequence(s).spawn(B)[b]``; a sequence of B entries
        (int, SeedSequence or None) seeds each swarm with its own entry, so swarm b of a
        batch equals a 1-swarm core reset with ``seed=[that entry]``.

        ``options``: ``positions`` / ``velocities`` arrays (N, dim) or (B, N, dim) override
        the random initial state.
        """
        return self.reset_rows(np.arange(self.num_swarms), seed=seed, options=options)

    def reset_rows(
        self,
        rows: Sequence[int] | np.ndarray,
        seed: Any = None,
        options: Mapping[str, Any] | None = None,
    ) -> StepResult:
        """Reset only the swarms in ``rows`` (the others keep their state).

        ``seed`` as in :meth:`reset`, with one entry per row when a sequence. Returns the
        full batch's current :class:`StepResult` (zero reward, no flags for reset rows).
        Everything is validated before any state changes.
        """
        rows = np.asarray(rows, dtype=np.int64).reshape(-1)
        B, D, cfg = self.num_swarms, self.config.dim, self.config
        if rows.size and (rows.min() < 0 or rows.max() >= B):
            raise ValueError(f"rows={rows.tolist()} is invalid: must be in [0, {B - 1}]")
        new_rngs = None if seed is None else self._make_rngs(seed, len(rows))
        q0, p0 = check_reset_options(options, len(rows), cfg.n_uavs, D)
        # --- apply --------------------------------------------------------------------
        if new_rngs is not None:
            for r, g in zip(rows, new_rngs, strict=False):
                if g is not None:
                    self._rngs[r] = g
        lq0, _ = self._leader.state(np.zeros(1))
        for k, r in enumerate(rows):
            q, p = initial_state(cfg, self._rngs[r], self.agent_uavs)
            if q0 is not None:
                q = q0[k]
            if p0 is not None:
                p = p0[k]
            self.q[r] = q
            self.p[r] = p
            self._pinned[r] = pinning_mask(cfg, q, lq0[0])
        self.t[rows] = 0.0
        self.steps[rows] = 0
        self.vehicle.reset_rows(rows, self.q, self.p)
        self._is_reset[rows] = True
        self._all_reset = bool(self._is_reset.all())
        zeros_u = np.zeros((B, self.n_agents, D))
        with np.errstate(**_CHECKED_FP):
            res = self._refresh(zeros_u, np.zeros((B, self.n_agents), bool), reset_rows=rows)
        res.reward[rows] = 0.0
        res.terminated[rows] = False
        res.truncated[rows] = False
        return res

    # ------------------------------------------------------------------ step
    def check_actions(self, actions: Any) -> np.ndarray:
        """Validate pair actions: shape (B, M, dim) (or (M, dim) when B = 1), real, finite.

        Returns them as float64 (B, M, dim); what is accepted is listed in
        :mod:`pairflock_env.task.actions`.
        """
        return check_pair_actions(
            actions, self.num_swarms, self.n_agents, self.config.dim, self.agent_uavs
        )

    def decode_actions(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Stage 2 of a step: checked actions (B, M, dim) to the pair command.

        Returns ``u`` (B, M, dim) in m/s^2 (clipped to [-1, 1], scaled by
        ``pair_accel_limit``) and ``clipped`` (B, M) bool. Changes nothing.
        """
        return decode_pair_actions(actions, self.config.pair_accel_limit)

    def step(self, actions: Any) -> StepResult:
        """Advance every swarm by one control period under the given pair actions.

        ``actions`` (B, M, dim): each paired UAV's pairwise acceleration f^x_i in units of
        ``pair_accel_limit``; components outside [-1, 1] are clipped (reported as
        ``action_clipped``). NaN/inf raise ``ValueError`` and leave the state unchanged.
        Swarms whose episode has ended keep integrating; views reset them.

        Decoding (stage 2) and the desired acceleration (stage 3) are separate on purpose:
        the safety filter (stage 2b, :attr:`safety`) adjusts the decoded pair command u
        from what each UAV senses, using the pass over the current state that the previous
        step (or the reset) made.
        """
        self._require_reset()
        a = self.check_actions(actions)  # 1. validate (raises before any state change)
        u, clipped = self.decode_actions(a)  # 2. decode: the pair command u, m/s^2
        grid = self.neighbor_grid  # of this state, from the last pass (None: all pairs)
        u = self.safety.apply(self.q, self.p, self._flock_out["acc"], u, grid)  # 2b. safety filter
        self.pair_command = u
        if self._quiet:  # every stage below runs in numba: no floating-point flags to mask
            return self._advance(u, clipped)
        with np.errstate(**_CHECKED_FP):
            return self._advance(u, clipped)

    def _advance(self, u: np.ndarray, clipped: np.ndarray) -> StepResult:
        """Stages 3-5 of a step, from the (filtered) pair command u."""
        a_des = self._desired_acceleration(u)  # 3. flocking + pair term (+ disturbance)
        self.vehicle.advance(self.q, self.p, a_des)  # 4. the vehicle model tracks a_des
        _tick(self.steps, self.t, self.config.dt)  # t = steps dt: no drift from repeated sums
        return self._refresh(u, clipped)

    def _desired_acceleration(self, u: np.ndarray) -> np.ndarray:
        """a_des (B, N, dim): the flocking command of the current state, plus the pair
        command u on the paired UAVs (or the safety stage's filtered whole command, when it
        filters every UAV's: ``safety_scope="swarm"``), plus the random disturbance (when
        configured)."""
        whole = getattr(self.safety, "whole_command", None)
        if whole is not None:
            a_des = whole.copy()
        else:
            a_des = add_pair_command(self._flock_out["acc"], self.agent_uavs, u)
        if self.config.disturbance_std > 0:
            a_des += self.config.disturbance_std * self._draw_normal(a_des.shape[1:])
        return a_des

    def _draw_normal(self, shape: tuple[int, ...]) -> np.ndarray:
        """Standard normal draws (B, *shape), swarm b from its own generator."""
        return np.stack([g.standard_normal(shape) for g in self._rngs])

    def _require_reset(self) -> None:
        if not self._all_reset:
            rows = np.flatnonzero(~self._is_reset).tolist()
            raise RuntimeError(f"call reset() before step(): swarms {rows} were never reset")

    # ------------------------------------------------------------------ observation etc.
    def _refresh(
        self, u: np.ndarray, clipped: np.ndarray, reset_rows: np.ndarray | None = None
    ) -> StepResult:
        """Run the neighbour pass over the new state and build the step's observation, reward,
        flags and infos."""
        cfg = self.config
        lq, lp = self._leader.state(self.t)
        fl, pp = self._neighbor_pass(lq, lp)
        obs, res, finite = self._observation(fl, pp, lq, lp, u, reset_rows)
        if self._noise is not None and not finite.all():
            finite = self._saturate_noise(obs)
        diverged = fl["diverged"] | ~finite
        rows = dict(zip(AGENT_ROWS, res, strict=True))
        reward = rows["reward"]
        if self._check_finite:  # an extreme config: what overflows still ends as a divergence
            finite = np.isfinite(reward) & np.isfinite(rows["sliding_surface"])
            diverged |= ~finite.all(axis=1)
        safety = self.safety.info(reset=reset_rows is not None)
        if self._no_filter:  # what make_info would count: no UAV's command was changed
            B = self.num_swarms
            safety |= {k: np.zeros(B, np.int64) for k in SAFETY_SWARM_INFO_KEYS}
        terms = {k: rows[f"reward_{k}"] for k in REWARD_TERMS}
        info = make_info(rows, fl, u, clipped, self.t, diverged, terms, safety, rows["pair_accel"])
        if np.count_nonzero(
            diverged
        ):  # a diverged swarm keeps its last finite observation and infos
            obs[diverged] = self._obs[diverged]
            hold_last_finite(info, self._info, diverged)
            reward[diverged] = -DIVERGENCE_PENALTY
        self._obs, self._info = obs, info
        vinfo = self.vehicle.info()
        terminated, truncated = episode_end(
            cfg, diverged, vinfo, info["min_separation"], self.steps
        )
        if vinfo:
            info.update(vinfo)
        return StepResult(obs, reward, terminated, truncated, info)

    def _neighbor_pass(self, lq: np.ndarray, lp: np.ndarray) -> tuple[dict, dict[str, np.ndarray]]:
        """The flocking and pair passes of the current state
        (:class:`~pairflock_env.swarm.passes.NeighborPass`)."""
        fl, pp = self._neighbors.run(self.q, self.p, lq, lp, self._pinned)
        self._flock_out = fl
        sense = getattr(self.safety, "sense", None)  # optional for a plug-in stage
        if sense is not None:
            sense(fl)
        return fl, pp

    def _perceived_partner(
        self, reset_rows: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Partner offset, velocity and flocking command as the agents perceive them:
        ``partner_delay`` steps old and with sensor noise (when configured)."""
        cfg = self.config
        self._noise = None
        acc = self._flock_out["acc"]
        qa, pa = self.q.take(self.agent_uavs, axis=1), self.p.take(self.agent_uavs, axis=1)
        off = self.q.take(self.partner_uavs, axis=1) - qa
        vel = self.p.take(self.partner_uavs, axis=1) - pa
        acc_partner = acc[:, self.partner_uavs]
        if self._delay is not None:
            now = np.stack([qa, pa, acc[:, self.agent_uavs]])  # (3, B, M, D)
            old = self._delay.push(now, reset_rows)
            off, vel, acc_partner = old[0] - qa, old[1] - pa, old[2]
        if cfg.obs_noise_position > 0 or cfg.obs_noise_velocity > 0:
            z = self._draw_normal((2, *off.shape[1:]))
            self._noise = noise = (
                off,
                cfg.obs_noise_position * z[:, 0],
                vel,
                cfg.obs_noise_velocity * z[:, 1],
            )
            off, vel = off + noise[1], vel + noise[3]
        return off, vel, acc_partner

    def _saturate_noise(self, obs: np.ndarray) -> np.ndarray:
        """Where noise overflowed an observation: the noisy fields again, saturated by
        :func:`~pairflock_env.task.observations.add_sensor_noise` (values that did not overflow
        stay as they were); returns which swarms' observations are finite now."""
        off, noise_off, vel, noise_vel = self._noise
        sl = self.layout.slice
        obs[..., sl("partner_offset")] = add_sensor_noise(off, noise_off)
        obs[..., sl("partner_velocity")] = add_sensor_noise(vel, noise_vel)
        return np.isfinite(obs).all(axis=(1, 2))

    def _observation(
        self,
        fl: Mapping[str, np.ndarray],
        pp: Mapping[str, np.ndarray],
        lq: np.ndarray,
        lp: np.ndarray,
        u: np.ndarray,
        reset_rows: np.ndarray | None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The agents' pass (:mod:`~pairflock_env.task.agent_pass`): the observation (B, M,
        obs_size) float32 of the current state (layout by name), the per-agent results
        ``AGENT_ROWS`` and whether each swarm's observation is finite. The partner delay,
        sensor noise and registered extra fields, when configured, replace their fields."""
        obs, res, finite, closest = self._agents.run(
            self.q, self.p, fl["acc"], fl["min_d2"], lq, lp, u, pp
        )
        fl["swarm_min_separation"] = closest
        if not self._perceived:
            return obs, res, finite
        cfg = self.config
        off, vel, acc_partner = self._perceived_partner(reset_rows)
        fields = {"partner_offset": off, "partner_velocity": vel}
        fields["partner_flock_accel"] = acc_partner
        if cfg.obs_extra:
            ctx = ObservationContext(
                cfg, self.q, self.p, self.t, lq, lp, self.agent_uavs, self.partner_uavs, fl["acc"]
            )  # fmt: skip
            for name in cfg.obs_extra:
                fields[name] = OBSERVATIONS[name].value(ctx)
        B, M = obs.shape[:2]
        for name, v in fields.items():
            obs[:, :, self.layout.slice(name)] = v.reshape(B, M, -1)
        return obs, res, np.isfinite(obs).all(axis=(1, 2))

    def observe(self) -> np.ndarray:
        """The current observation (B, M, obs_size), float32 (a copy)."""
        self._require_reset()
        return self._obs.copy()
