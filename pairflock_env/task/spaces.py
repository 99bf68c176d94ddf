"""Finite bounds of what the views emit, derived from the config, and the global state.

Everything a view emits comes from a state that is not *diverged*: every position and
velocity component lies within ``divergence_limit`` L (a diverged swarm keeps its last
finite observation and its episode ends). From that and the config follow finite bounds:

* offsets between two UAVs (partner, neighbours): 2 L per component; relative velocities 2 L;
* the virtual leader during an episode of T = ``episode_steps * dt`` seconds: its velocity
  component k is at most ``|v_k|`` (constant velocity) or the ground speed / climb rate
  (climb and turn), its position at most ``|q0_k| + vmax_k T``;
* the flocking command (eqs. 13-19): at most N - 1 neighbours within ``radius``, each
  contributing ``max(a, b_r - a) r + b 2 L``, plus the pinning term ``c1 (ql + L) + c2 (pl + L)``;
* observation noise: the noisy partner offset / velocity is bounded by the noiseless bound
  plus ``NOISE_SIGMAS`` standard deviations; the views clip the (vanishingly rare, about
  1e-15 per draw) values beyond it into the box.

:func:`physical_observation_bounds` gives the box of the physical observation
(:class:`~pairflock_env.task.observations.ObsLayout`), :class:`StateLayout` /
:func:`state_bounds` / :func:`global_state` the centralised-critic state of the PettingZoo
views. Bounds are float32 (rounded outward) and at most float32's largest finite value, as
the observations are float32 and finite. A leader type without a known bound gives infinite
bounds for the fields it enters.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.layout import Field as LayoutField
from pairflock_env.layout import FlatLayout
from pairflock_env.swarm.leader import LEADERS
from pairflock_env.task.observations import OBSERVATIONS, ObsLayout
from pairflock_env.task.rewards import DIVERGENCE_PENALTY

__all__ = [
    "NOISE_SIGMAS",
    "StateLayout",
    "core_reward_range",
    "global_state",
    "leader_bounds",
    "pair_error_bound",
    "physical_observation_bounds",
    "separation_bound",
    "state_bounds",
]

#: observation noise is bounded at this many standard deviations (and clipped there)
NOISE_SIGMAS = 8.0
# relative slack for the rounding of sums of many bounded terms
_SLACK = 1e-6
_F32_MAX = float(np.finfo(np.float32).max)


def _episode_time(cfg: PairFlockConfig) -> float:
    return cfg.episode_steps * cfg.dt


def leader_bounds(cfg: PairFlockConfig) -> tuple[np.ndarray, np.ndarray]:
    """Per-axis bounds (dim,) of |leader position| and |leader velocity| over an episode
    (the speed bound is the leader entry's, :class:`~pairflock_env.swarm.leader.Leader`)."""
    q0 = np.abs(cfg.vector("leader_position"))
    vmax = np.asarray(LEADERS[cfg.leader].speed_bound(cfg), dtype=np.float64)
    return q0 + vmax * _episode_time(cfg), vmax


def _flock_accel_bound(cfg: PairFlockConfig, lq: np.ndarray, lp: np.ndarray) -> np.ndarray:
    L = cfg.divergence_limit
    w = max(abs(cfg.attraction), abs(cfg.repulsion - cfg.attraction))
    neighbours = (cfg.n_uavs - 1) * (w * min(cfg.radius, 2 * L) + abs(cfg.consensus) * 2 * L)
    pin = abs(cfg.pin_position_gain) * (lq + L) + abs(cfg.pin_velocity_gain) * (lp + L)
    return (neighbours + pin) * (1 + _SLACK)


def _f32(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """float32 bounds rounded outward, capped at float32's largest finite value."""
    low = np.maximum(np.asarray(low, np.float64), -_F32_MAX)
    high = np.minimum(np.asarray(high, np.float64), _F32_MAX)
    lo, hi = low.astype(np.float32), high.astype(np.float32)
    lo = np.where(lo > low, np.nextafter(lo, np.float32(-np.inf)), lo)
    hi = np.where(hi < high, np.nextafter(hi, np.float32(np.inf)), hi)
    return lo.astype(np.float32), hi.astype(np.float32)


def physical_observation_bounds(cfg: PairFlockConfig) -> tuple[np.ndarray, np.ndarray]:
    """(low, high), each float32 (obs_size,), of every physical observation of ``cfg``."""
    layout = ObsLayout.for_config(cfg)
    L, D, K = cfg.divergence_limit, cfg.dim, cfg.obs_neighbors
    lq, lp = leader_bounds(cfg)
    acc = _flock_accel_bound(cfg, lq, lp)
    d_m = cfg.d_m_array
    high = {
        "partner_offset": np.full(D, 2 * L + NOISE_SIGMAS * cfg.obs_noise_position),
        "partner_velocity": np.full(D, 2 * L + NOISE_SIGMAS * cfg.obs_noise_velocity),
        "target_distance": np.array([d_m.max()]),
        "shared_neighbors": np.array([float(cfg.n_uavs)]),
        "leader_offset": lq + L,
        "leader_velocity": lp + L,
        "flock_accel": acc,
        "partner_flock_accel": acc,
        "neighbor_offsets": np.full(K * D, 2 * L),
        "neighbor_velocities": np.full(K * D, 2 * L),
        "neighbor_mask": np.ones(K),
    }
    low = {k: -v for k, v in high.items()}
    low["target_distance"] = np.zeros(1)  # not [d_m, d_m]: a degenerate box trips checkers
    low["shared_neighbors"] = np.zeros(1)
    low["neighbor_mask"] = np.zeros(K)
    for name in cfg.obs_extra:
        entry = OBSERVATIONS[name]
        b = np.full(entry.size(D, K), float(entry.bound(cfg)))
        high[name], low[name] = b, -b
    lo = np.empty(layout.size)
    hi = np.empty(layout.size)
    for name in layout.names:
        lo[layout.slice(name)] = low[name]
        hi[layout.slice(name)] = high[name]
    return _f32(lo, hi)


def pair_error_bound(cfg: PairFlockConfig) -> float:
    """Largest |pair error| (m) of a non-diverged state: ||y|| <= 2 L sqrt(dim)."""
    d_m = cfg.d_m_array
    reach = 2 * cfg.divergence_limit * np.sqrt(cfg.dim)
    return float(max(reach - d_m.min(), d_m.max()))


def separation_bound(cfg: PairFlockConfig) -> float:
    """Largest finite distance (m) between two UAVs of a non-diverged state."""
    return float(2 * cfg.divergence_limit * np.sqrt(cfg.dim))


def core_reward_range(cfg: PairFlockConfig) -> tuple[float, float]:
    """(low, 0): the range of the core's per-agent reward (:mod:`pairflock_env.task.rewards`).

    Per control step and agent the reward is ``-w_err |e|`` (|e| up to
    :func:`pair_error_bound`) minus effort (at most ``w_u dim``), separation (at most ``w_sep``)
    and collision (``w_col``) penalties, or ``-DIVERGENCE_PENALTY`` when the swarm diverges.
    """
    worst = (
        cfg.reward_error_weight * pair_error_bound(cfg)
        + cfg.reward_effort_weight * cfg.dim
        + cfg.reward_separation_weight
        + cfg.reward_collision_weight
    )
    return -max(worst * (1 + _SLACK), DIVERGENCE_PENALTY), 0.0


class StateLayout(FlatLayout):
    """Named fields of the global state of one swarm (``env.state()``), float32.

    Positions and velocities are relative to the virtual leader (the dynamics do not depend
    on where the swarm is, only on where it is relative to the leader); the leader's own
    velocity and the elapsed fraction of the episode complete it. The vehicle's attitude
    (quadrotor) is not part of it.
    """

    def __init__(self, n_uavs: int, dim: int) -> None:
        N, D = n_uavs, dim
        fields = (
            LayoutField("positions", (N, D), "m", "q_i - q_leader of every UAV i, row by row"),
            LayoutField("velocities", (N, D), "m/s", "p_i - p_leader of every UAV i"),
            LayoutField("leader_velocity", (D,), "m/s", "p_leader"),
            LayoutField("time_fraction", (1,), "1", "sim time / episode length, in [0, 1]"),
        )
        super().__init__(fields, "state")


def state_bounds(cfg: PairFlockConfig) -> tuple[np.ndarray, np.ndarray]:
    """(low, high), each float32 (state size,), of :func:`global_state` for ``cfg``."""
    layout = StateLayout(cfg.n_uavs, cfg.dim)
    L = cfg.divergence_limit
    lq, lp = leader_bounds(cfg)
    hi = np.empty(layout.size)
    hi[layout.slice("positions")] = np.tile(lq + L, cfg.n_uavs)
    hi[layout.slice("velocities")] = np.tile(lp + L, cfg.n_uavs)
    hi[layout.slice("leader_velocity")] = lp
    hi[layout.slice("time_fraction")] = 1.0
    lo = -hi
    lo[layout.slice("time_fraction")] = 0.0
    return _f32(lo, hi)


def global_state(
    cfg: PairFlockConfig,
    q: np.ndarray,
    p: np.ndarray,
    leader_q: np.ndarray,
    leader_p: np.ndarray,
    t: float,
) -> np.ndarray:
    """The :class:`StateLayout` vector of one swarm: q, p (N, dim), leader (dim,), time t (s)."""
    frac = min(max(float(t) / _episode_time(cfg), 0.0), 1.0)
    parts = [(q - leader_q).reshape(-1), (p - leader_p).reshape(-1), leader_p, [frac]]
    return np.concatenate(parts).astype(np.float32)
