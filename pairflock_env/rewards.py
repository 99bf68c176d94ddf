"""Per-agent reward: a sum of weighted penalties, each documented with its unit.

    r_i = - w_err * |e_i|                                   e_i = ||y|| - d_m  (m)
          - w_u   * (||u_i|| / pair_accel_limit)^2           applied pair acceleration
          - w_sep * max(0, D - sep_i) / D                    sep_i: nearest non-partner (m)
          - w_col * [sep_i < collision_distance]             D = reward_separation_distance

Both members of a pair share the distance term; effort and separation are individual.
A swarm whose state diverged gets ``-divergence_penalty`` instead (a finite number).
"""

from __future__ import annotations

import numpy as np

from .config import PairFlockConfig

__all__ = ["DIVERGENCE_PENALTY", "REWARD_TERMS", "reward_terms"]

REWARD_TERMS = ("error", "effort", "separation", "collision")
DIVERGENCE_PENALTY = 100.0


def reward_terms(
    cfg: PairFlockConfig,
    pair_error: np.ndarray,
    u: np.ndarray,
    min_separation: np.ndarray,
) -> dict[str, np.ndarray]:
    """The weighted penalty terms (each <= 0), shapes (B, M); their sum is the reward."""
    effort = np.einsum("...k,...k->...", u, u) / cfg.pair_accel_limit**2
    sep = cfg.reward_separation_distance
    short = np.maximum(0.0, sep - min_separation) / sep
    return {
        "error": -cfg.reward_error_weight * np.abs(pair_error),
        "effort": -cfg.reward_effort_weight * effort,
        "separation": -cfg.reward_separation_weight * short,
        "collision": -cfg.reward_collision_weight * (min_separation < cfg.collision_distance),
    }
