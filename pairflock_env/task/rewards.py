"""Per-agent reward: a sum of weighted penalties, each documented with its unit; and the
termination and truncation rules of an episode.

    r_i = - w_err * |e_i|                                   e_i = ||y|| - d_m  (m)
          - w_u   * (||u_i|| / pair_accel_limit)^2           applied pair acceleration
          - w_sep * max(0, D - sep_i) / D                    sep_i: nearest non-partner (m)
          - w_col * [sep_i < collision_distance]             D = reward_separation_distance

Both members of a pair share the distance term; effort and separation are individual.
A swarm whose state diverged gets ``-divergence_penalty`` instead (a finite number).

An episode is *terminated* when its swarm diverged, when the vehicle model reports it ended
(e.g. a crashed quadrotor) or, with ``terminate_on_collision``, when a paired UAV is closer
than ``collision_distance`` to another UAV; it is *truncated* when it reached
``episode_steps`` control steps without being terminated.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.kernels import KernelParams, jit_inline, jit_kernel
from pairflock_env.task.pairing import dot_axes

__all__ = [
    "DIVERGENCE_PENALTY",
    "REWARD",
    "REWARD_TERMS",
    "agent_reward",
    "episode_end",
    "may_overflow",
    "reward_params",
    "reward_terms",
    "total_reward",
]

REWARD_TERMS = ("error", "effort", "separation", "collision")
DIVERGENCE_PENALTY = 100.0


#: the reward's parameters, as the kernels receive them
REWARD = KernelParams(
    "Reward",
    (
        "pair_accel_limit2",
        "error_weight",
        "effort_weight",
        "separation_weight",
        "collision_weight",
        "separation_distance",
        "collision_distance",
    ),
)
_R = REWARD.index


def reward_params(cfg: PairFlockConfig) -> np.ndarray:
    """The reward's parameter vector (:data:`REWARD`) of a config."""
    return REWARD.pack(
        pair_accel_limit2=cfg.pair_accel_limit**2,
        error_weight=cfg.reward_error_weight,
        effort_weight=cfg.reward_effort_weight,
        separation_weight=cfg.reward_separation_weight,
        collision_weight=cfg.reward_collision_weight,
        separation_distance=cfg.reward_separation_distance,
        collision_distance=cfg.collision_distance,
    )


@jit_inline
def agent_reward(prm, pair_error, uu, min_separation):
    """The weighted terms of one agent (error, effort, separation, collision; each <= 0) and
    their sum, from its pair error (m), u.u of its pair command ((m/s^2)^2) and its
    separation (m): the equations of the module docstring, the only place they are written.
    A term's weight is negated before it multiplies (``-w * x``), a collision counts as 1.0
    or 0.0, and the terms add in the order of ``REWARD_TERMS``."""
    sep = prm[_R.separation_distance]
    short = sep - min_separation
    short = (0.0 if short <= 0.0 else short) / sep  # np.maximum(0, x): NaN stays NaN
    collision = 1.0 if min_separation < prm[_R.collision_distance] else 0.0
    error = -prm[_R.error_weight] * abs(pair_error)
    effort = -prm[_R.effort_weight] * (uu / prm[_R.pair_accel_limit2])
    separation = -prm[_R.separation_weight] * short
    collision = -prm[_R.collision_weight] * collision
    return error, effort, separation, collision, error + effort + separation + collision


@jit_kernel
def _reward_kernel(prm, pair_error, u, min_separation, dims, out):
    three = len(dims) == 3
    for b in range(u.shape[0]):
        for m in range(u.shape[1]):
            v = u[b, m]
            v2 = v[2] if three else 0.0
            uu = dot_axes(v[0], v[1], v2, v[0], v[1], v2, three)
            terms = agent_reward(prm, pair_error[b, m], uu, min_separation[b, m])
            for k in range(5):
                out[k, b, m] = terms[k]


def reward_terms(
    cfg: PairFlockConfig,
    pair_error: np.ndarray,
    u: np.ndarray,
    min_separation: np.ndarray,
) -> dict[str, np.ndarray]:
    """The weighted penalty terms (each <= 0), shapes (B, M); their sum is the reward
    (:func:`agent_reward` per agent)."""
    u = np.asarray(u, dtype=np.float64)
    B, M, D = u.shape
    err = np.broadcast_to(np.asarray(pair_error, dtype=np.float64), (B, M))
    sep = np.broadcast_to(np.asarray(min_separation, dtype=np.float64), (B, M))
    out = np.empty((5, B, M))
    _reward_kernel(reward_params(cfg), err, u, sep, (0,) * D, out)
    return dict(zip(REWARD_TERMS, out[:4], strict=True))


def total_reward(terms: Mapping[str, np.ndarray]) -> np.ndarray:
    """The reward (B, M): the sum of the terms, in the order of ``REWARD_TERMS``."""
    return terms["error"] + terms["effort"] + terms["separation"] + terms["collision"]


def episode_end(
    cfg: PairFlockConfig,
    diverged: np.ndarray,
    vehicle_info: Mapping[str, np.ndarray],
    min_separation: np.ndarray,
    steps: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``terminated`` and ``truncated`` (B,) bool, by the rules of the module docstring.

    Args:
        diverged: (B,) bool; vehicle_info: the vehicle model's ``info()`` (its optional
        ``vehicle_terminated`` (B,) ends episodes); min_separation: (B, M) m; steps: control
        steps since reset (B,).
    """
    terminated = diverged.copy()
    if "vehicle_terminated" in vehicle_info:  # e.g. a crashed quadrotor
        terminated |= vehicle_info["vehicle_terminated"]
    if cfg.terminate_on_collision:
        terminated |= np.any(min_separation < cfg.collision_distance, axis=1)
    truncated = (steps >= cfg.episode_steps) & ~terminated
    return terminated, truncated


def may_overflow(cfg: PairFlockConfig) -> bool:
    """Whether a swarm inside ``divergence_limit`` could still get a non-finite reward or
    sliding surface under ``cfg`` (only extreme configs can).

    Every |position| and |velocity| component of a swarm not flagged diverged is at most
    L = ``divergence_limit``, so |y| and |y'| are at most 2 L sqrt(dim); the bounds of the
    reward terms and of s = c e + e' follow. When they are far from the float64 range the
    core skips the per-step check of rewards and surfaces.
    """
    span = 2.0 * cfg.divergence_limit * math.sqrt(cfg.dim)
    d_m = float(cfg.d_m_array.max())
    surface = cfg.surface_slope * (span * span + d_m * d_m) + 2.0 * span * span
    limit2 = cfg.pair_accel_limit * cfg.pair_accel_limit
    reward = (
        cfg.reward_error_weight * (span + d_m)
        + cfg.reward_effort_weight * cfg.dim * max(limit2, 1.0 / limit2 if limit2 else math.inf)
        + cfg.reward_separation_weight
        + cfg.reward_collision_weight
    )
    return not (surface < 1e300 and reward < 1e300)
