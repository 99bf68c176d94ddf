"""The proportional "normal method" of eq. 44 (Sec. VI-A), the paper's comparison.

    f_i^x = k_p (d_m - ||q_i - q_j||) sign(q_i - q_j)      (element-wise sign; erratum 6)

From UAV i's own observation, q_i - q_j = -(partner offset).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from baselines.controllers.base import PairPolicy, gain_value

__all__ = ["ProportionalController"]


class ProportionalController(PairPolicy):
    """Eq. 44 (element-wise sign); see the module docstring."""

    GAINS = {"k_p": (1.0, "proportional gain k_p (1/s^2); the paper does not state it")}

    def __init__(self, env: Any, **gains: Any) -> None:
        super().__init__(env, **gains)
        self.gains["k_p"] = gain_value("k_p", self.gains["k_p"], minimum=0.0, allow_minimum=False)

    def accel(self, obs: np.ndarray) -> np.ndarray:
        L = self.layout
        y = L.get(obs, "partner_offset")
        dm = L.get(obs, "target_distance")
        dist = np.linalg.norm(y, axis=-1, keepdims=True)
        return self.gains["k_p"] * (dm - dist) * np.sign(-y)
