"""Batched episode rollouts of any pair policy, with recorded time series and metrics.

One rollout runs every seed of a (config, policy) combination as one batched core (swarm b
seeded with ``seeds[b]``, identical to a PettingZoo env reset with that seed), asks the
policy for all agents' actions at once through ``predict``, and records what the metrics and
figures need. The reproduction, the benchmark and the training evaluation all call this.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from pairflock_env import PairFlockConfig, PairFlockCore
from pairflock_env.task.metrics import (
    FLOCK_STATE_NAMES,
    flock_quality_metrics,
    flock_state,
    pair_episode_metrics,
    pair_safety_metrics,
    swarm_safety_metrics,
)

__all__ = ["Trace", "rollout", "trace_metrics"]


@dataclasses.dataclass
class Trace:
    """Time series of a batched rollout (B swarms, P pairs, M = 2P agents, T control steps)."""

    config: PairFlockConfig
    seeds: list[int]
    t: np.ndarray  # (T+1,)
    pair_error: np.ndarray  # (B, P, T+1)
    pair_distance: np.ndarray  # (B, P, T+1)
    surface: np.ndarray  # (B, P, T+1)
    min_separation: np.ndarray  # (B, M, T+1)
    speed: np.ndarray  # (B, M, T+1)
    u: np.ndarray  # (B, M, T, dim) applied pair acceleration, m/s^2
    largest_component: np.ndarray  # (B, T+1)
    velocity_mismatch: np.ndarray  # (B, T+1)
    collisions: np.ndarray  # (B, T+1)
    clipped_steps: np.ndarray  # (B, M)
    safety_active_steps: np.ndarray  # (B, M) steps the safety filter changed the command
    safety_infeasible_steps: np.ndarray  # (B, M)
    peak_correction: np.ndarray  # (B, M) largest ||u - u_nom||, m/s^2
    ended: np.ndarray  # (B,) control steps actually run (early termination < T)
    swarm_separation: np.ndarray  # (B, T+1) the closest two UAVs (swarm_min_separation)
    swarm_active: np.ndarray  # (B, T) UAVs whose command the safety stage changed
    swarm_infeasible: np.ndarray  # (B, T) UAVs with no command meeting every constraint
    flock_t: np.ndarray  # (S,) times of the flock samples (every FLOCK_EVERY s)
    flock: np.ndarray  # (B, S, 3) flock_state (FLOCK_STATE_NAMES) at those times
    positions: dict[int, np.ndarray]  # row -> (T+1, N, dim), only for recorded rows
    velocities: dict[int, np.ndarray]
    leader_positions: dict[int, np.ndarray]  # row -> (T+1, dim)

    @property
    def num_swarms(self) -> int:
        return self.pair_error.shape[0]


#: the flock's state (radius of gyration, tracking, lattice deviation) is sampled this often (s)
FLOCK_EVERY = 1.0


def _flock_stride(config: PairFlockConfig) -> int:
    return max(1, round(FLOCK_EVERY / config.dt))


def _empty_trace(config: PairFlockConfig, seeds: list[int], M: int, T: int, record_rows) -> Trace:
    B, P, D = len(seeds), M // 2, config.dim
    S = T // _flock_stride(config) + 1
    return Trace(
        config=config,
        seeds=seeds,
        t=np.arange(T + 1) * config.dt,
        pair_error=np.empty((B, P, T + 1)),
        pair_distance=np.empty((B, P, T + 1)),
        surface=np.empty((B, P, T + 1)),
        min_separation=np.empty((B, M, T + 1)),
        speed=np.empty((B, M, T + 1)),
        u=np.zeros((B, M, T, D)),
        largest_component=np.empty((B, T + 1), np.int64),
        velocity_mismatch=np.empty((B, T + 1)),
        collisions=np.empty((B, T + 1), np.int64),
        clipped_steps=np.zeros((B, M), np.int64),
        safety_active_steps=np.zeros((B, M), np.int64),
        safety_infeasible_steps=np.zeros((B, M), np.int64),
        peak_correction=np.zeros((B, M)),
        ended=np.full(B, T, np.int64),
        swarm_separation=np.empty((B, T + 1)),
        swarm_active=np.zeros((B, T), np.int64),
        swarm_infeasible=np.zeros((B, T), np.int64),
        flock_t=np.arange(S) * _flock_stride(config) * config.dt,
        flock=np.empty((B, S, len(FLOCK_STATE_NAMES))),
        positions={int(r): np.empty((T + 1, config.n_uavs, D)) for r in record_rows},
        velocities={int(r): np.empty((T + 1, config.n_uavs, D)) for r in record_rows},
        leader_positions={int(r): np.empty((T + 1, D)) for r in record_rows},
    )


def _record(tr: Trace, core: PairFlockCore, k: int, res, live: np.ndarray) -> None:
    """Store step ``k`` of the swarms still running (``live``)."""
    info = res.info
    pair_rows = np.arange(0, core.n_agents, 2)
    for name, key in (
        ("pair_error", "pair_error"),
        ("pair_distance", "pair_distance"),
        ("surface", "sliding_surface"),
    ):
        getattr(tr, name)[live, :, k] = info[key][live][:, pair_rows]
    tr.min_separation[live, :, k] = info["min_separation"][live]
    tr.speed[live, :, k] = np.linalg.norm(core.p[live][:, core.agent_uavs], axis=-1)
    tr.largest_component[live, k] = info["largest_component"][live]
    tr.velocity_mismatch[live, k] = info["velocity_mismatch"][live]
    tr.collisions[live, k] = info["collisions"][live]
    tr.swarm_separation[live, k] = info["swarm_min_separation"][live]
    stride = _flock_stride(tr.config)
    if k % stride == 0:
        _record_flock(tr, core, k // stride, live)
    if tr.positions:
        lq, _ = core.leader_state()
        for r in tr.positions:
            if live[r]:
                tr.positions[r][k] = core.q[r]
                tr.velocities[r][k] = core.p[r]
                tr.leader_positions[r][k] = lq[r]


def _record_flock(tr: Trace, core: PairFlockCore, s: int, live: np.ndarray) -> None:
    """Flock sample ``s`` of the live swarms (the others hold their last one)."""
    cfg = tr.config
    unpaired = np.ones(cfg.n_uavs, bool)
    unpaired[core.agent_uavs] = False
    lq, _ = core.leader_state()
    grid = core.neighbor_grid
    for b in range(tr.num_swarms):
        if live[b]:
            tr.flock[b, s] = flock_state(core.q, b, lq[b], unpaired, cfg.radius, cfg.spacing, grid)
        else:
            tr.flock[b, s] = tr.flock[b, s - 1]


def _record_safety(tr: Trace, info, live: np.ndarray) -> None:
    tr.safety_active_steps[live] += info["safety_active"][live]
    tr.safety_infeasible_steps[live] += info["safety_infeasible"][live]
    np.maximum(
        tr.peak_correction,
        np.where(live[:, None], info["safety_correction"], 0.0),
        out=tr.peak_correction,
    )


def _record_step(tr: Trace, core: PairFlockCore, k: int, res, live, filtered: bool) -> None:
    """What step ``k`` adds to the trace of the swarms still running (``live``)."""
    tr.u[live, :, k - 1] = core.pair_command[live]  # the applied (filtered) command
    if filtered:
        _record_safety(tr, res.info, live)
    tr.clipped_steps[live] += res.info["action_clipped"][live]
    tr.swarm_active[live, k - 1] = res.info["swarm_filter_active"][live]
    tr.swarm_infeasible[live, k - 1] = res.info["swarm_filter_infeasible"][live]
    _record(tr, core, k, res, live)


def _freeze_finished(tr: Trace, T: int) -> None:
    """Hold the series of swarms that ended early at their last value."""
    for b in np.flatnonzero(tr.ended < T):
        e = tr.ended[b]
        for arr in (tr.pair_error, tr.pair_distance, tr.surface, tr.min_separation, tr.speed):
            arr[b, ..., e + 1 :] = arr[b, ..., e : e + 1]
        for arr in (tr.largest_component, tr.velocity_mismatch, tr.collisions):
            arr[b, e + 1 :] = arr[b, e]
        tr.swarm_separation[b, e + 1 :] = tr.swarm_separation[b, e]


class _Progress:
    """Calls ``progress(n steps)`` about 50 times per episode."""

    def __init__(self, progress: Callable[[int], None] | None, T: int) -> None:
        self.progress, self.T, self.every, self.last = progress, T, max(1, T // 50), 0

    def step(self, k: int) -> None:
        if self.progress is not None and (k - self.last >= self.every or k == self.T):
            self.progress(k - self.last)
            self.last = k

    def finish(self) -> None:
        if self.progress is not None and self.last < self.T:
            self.progress(self.T - self.last)


def rollout(
    config: PairFlockConfig,
    policy: Any,
    seeds: Sequence[int],
    *,
    record_rows: Sequence[int] = (),
    steps: int | None = None,
    progress: Callable[[int], None] | None = None,
    on_step: Callable[[int, PairFlockCore, Any, np.ndarray], None] | None = None,
) -> Trace:
    """Run one episode per seed, all swarms in one batched core.

    Args:
        config: the task.  policy: anything with SB3's ``predict`` (analytic or learned).
        seeds: one seed per swarm.  record_rows: swarms whose full state is kept for figures.
        steps: control steps (default: the episode length).  progress: called with the number
            of steps done since the last call.
        on_step: optional recorder ``on_step(k, core, result, live)`` called after the reset
            (k = 0) and after every step k with the core, its :class:`StepResult` and the
            (B,) mask of swarms still running; for series the trace does not keep (e.g. the
            quadrotor attitude). It must not change the core.
    """
    seeds = [int(s) for s in seeds]
    core = PairFlockCore(config, num_swarms=len(seeds))
    B, M, D = len(seeds), core.n_agents, config.dim
    T = config.episode_steps if steps is None else int(steps)
    res = core.reset(seed=seeds)
    tr = _empty_trace(config, seeds, M, T, record_rows)
    done = np.zeros(B, bool)
    _record(tr, core, 0, res, ~done)
    if on_step is not None:
        on_step(0, core, res, ~done)
    report = _Progress(progress, T)
    # SB3's predict protocol: a policy with memory (a recurrent net, or a learned policy that
    # holds its action over several control steps) gets its state back and the episode starts
    state = None
    episode_start = np.ones(B * M, dtype=bool)
    filtered = core.config.safety_filter != "none"
    for k in range(1, T + 1):
        obs = res.obs.reshape(B * M, -1)
        actions, state = policy.predict(
            obs, state=state, episode_start=episode_start, deterministic=True
        )
        episode_start = np.zeros(B * M, dtype=bool)
        actions = np.asarray(actions, dtype=np.float64).reshape(B, M, D)
        res = core.step(actions)
        live = ~done
        _record_step(tr, core, k, res, live, filtered)
        if on_step is not None:
            on_step(k, core, res, live)
        ended_now = live & (res.terminated | res.truncated)
        if k < T and ended_now.any():  # freeze the finished swarms' series at their last value
            tr.ended[ended_now] = k
            done |= ended_now
        report.step(k)
        if done.all():
            break
    _freeze_finished(tr, T)
    report.finish()
    return tr


def _swarm_metrics(tr: Trace, b: int, steady_window: float) -> dict[str, Any]:
    """Swarm b's separation and flock quality (the same on each of its pairs' rows)."""
    e = tr.ended[b]
    m = swarm_safety_metrics(
        tr.swarm_separation[b],
        tr.swarm_active[b, :e],
        tr.swarm_infeasible[b, :e],
        tr.config.safety_distance,
    )
    m.update(
        flock_quality_metrics(
            tr.flock_t,
            tr.flock[b],
            tr.t,
            tr.velocity_mismatch[b],
            tr.largest_component[b],
            steady_window=steady_window,
        )
    )
    return m


def trace_metrics(
    tr: Trace,
    *,
    safety_metrics: bool | None = None,
    swarm_metrics: bool | None = None,
    **kwargs: Any,
):
    """Metrics of every (swarm, pair) of a trace, one dict each (with ``seed`` and ``pair``).

    ``safety_metrics`` adds the columns of :data:`~pairflock_env.task.metrics.SAFETY_METRIC_DOCS`
    (default: when the trace's config has ``safety_filter`` on; pass True for the same columns
    in every run of a comparison with the filter off and on). ``swarm_metrics`` adds the
    whole swarm's separation and the flock's quality (:data:`~pairflock_env.task.metrics.
    SWARM_SAFETY_METRIC_DOCS`, :data:`~pairflock_env.task.metrics.FLOCK_METRIC_DOCS`;
    default: with ``safety_scope="swarm"``). ``kwargs`` go to
    :func:`~pairflock_env.task.metrics.pair_episode_metrics`."""
    cfg = tr.config
    if safety_metrics is None:
        safety_metrics = cfg.safety_filter != "none"
    if swarm_metrics is None:
        swarm_metrics = cfg.safety_scope == "swarm"
    out = []
    for b in range(tr.num_swarms):
        swarm = _swarm_metrics(tr, b, kwargs.get("steady_window", 10.0)) if swarm_metrics else {}
        for k in range(tr.pair_error.shape[1]):
            ms = slice(2 * k, 2 * k + 2)
            m = pair_episode_metrics(
                tr.t,
                tr.pair_error[b, k],
                tr.surface[b, k],
                tr.min_separation[b, ms],
                tr.u[b, ms],
                tr.speed[b, ms],
                tr.largest_component[b],
                tr.velocity_mismatch[b],
                tr.collisions[b],
                cfg.dt,
                cfg.collision_distance,
                **kwargs,
            )
            if safety_metrics:
                m.update(
                    pair_safety_metrics(
                        tr.min_separation[b, ms],
                        tr.pair_distance[b, k],
                        tr.safety_active_steps[b, ms],
                        tr.safety_infeasible_steps[b, ms],
                        tr.peak_correction[b, ms],
                        cfg.safety_distance,
                    )
                )
            m = {
                "seed": tr.seeds[b],
                "pair": k,
                **m,
                **swarm,
                "clipped_steps": int(tr.clipped_steps[b, ms].sum()),
                "steps_run": int(tr.ended[b]),
            }
            out.append(m)
    return out
