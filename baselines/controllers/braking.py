"""A braking-curve pair law within an acceleration ball (not in the paper): the analytic
reference for a pair controller with a small budget, and the teacher of the imitation
warm start (:mod:`train.imitate`).

With the feed-forward of eq. 23, ``u_i = 1/2 (f_j - f_i) + w_i``, the pair's relative motion
is a double integrator driven by ``w_j - w_i`` alone. Each member then asks for the closing
speed of a bang-bang approach that brakes at ``a_b`` (relative), and damps the tangential
relative velocity:

    r* = -sign(e) min(sqrt(2 a_b |e|), k_e |e|)   desired d||z||/dt     (e = ||z|| - d_m)
    w_i = k/2 (r - r*) e_r + k/2 v_t               r = v . e_r, v_t = v - r e_r

(``z``: partner offset, ``v``: partner velocity relative to the UAV, ``e_r = z / ||z||``).
Both members run the same law, so the relative acceleration along ``e_r`` is
``-k (r - r*)``: the closing speed tracks the braking curve at rate ``k``. Within
``2 a_b / k_e^2`` of the target the curve is linear, so the last metres are a damped linear
loop (stiffness ``k k_e``, damping ``k``) that a policy acting every 0.05 s can hold without
a limit cycle; no sliding surface, no sign function, no chattering. The default
``a_b = 0.9 accel_limit`` leaves each member a tenth of its budget beyond braking for the
flocking feed-forward (at ``pair_accel_limit = 50``: 45 m/s^2). ``u_i`` is scaled down
as a whole, direction kept, to ``||u_i|| <= accel_limit`` (default: the env's
``pair_accel_limit``), so it never leaves the ball the safety filter and the learning
interface use.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.learning import pair_feedforward

from .base import PairPolicy, gain_value

__all__ = ["BrakingCurveController"]

#: margin below the bound, so that float32 rounding of the action never exceeds it
_BALL_MARGIN = 1.0 - 1e-6


class BrakingCurveController(PairPolicy):
    """Feed-forward + braking-curve closing law within a ball; see the module docstring."""

    GAINS = {
        "a_b": (None, "relative deceleration of the braking curve (m/s^2); None: 0.9 x the bound"),
        "k": (20.0, "tracking rate of the closing speed and the tangential damping (1/s)"),
        "k_e": (6.0, "slope of the closing-speed curve near the target, r* = -k_e e (1/s)"),
        "accel_limit": (None, "bound on ||u|| (m/s^2); None: the env's pair_accel_limit"),
    }

    def __init__(self, env: Any, **gains: Any) -> None:
        super().__init__(env, **gains)
        limit = self.config.pair_accel_limit
        if self.gains["accel_limit"] is not None:
            self.gains["accel_limit"] = self._positive("accel_limit")
            limit = min(limit, self.gains["accel_limit"])
        self._limit = limit * _BALL_MARGIN
        if self.gains["a_b"] is None:
            self.gains["a_b"] = 0.9 * limit
        for name in ("a_b", "k", "k_e"):
            self.gains[name] = self._positive(name)

    def _positive(self, name: str) -> float:
        return gain_value(name, self.gains[name], minimum=0.0, allow_minimum=False)

    def accel(self, obs: np.ndarray) -> np.ndarray:
        get = self.layout.get
        z, v = get(obs, "partner_offset"), get(obs, "partner_velocity")
        dist = np.linalg.norm(z, axis=-1, keepdims=True)
        e_r = np.divide(z, dist, out=np.zeros_like(z), where=dist > 0)
        e = dist - get(obs, "target_distance")
        rate = np.sum(v * e_r, axis=-1, keepdims=True)
        g = self.gains
        target = -np.sign(e) * np.minimum(np.sqrt(2.0 * g["a_b"] * np.abs(e)), g["k_e"] * np.abs(e))
        half_k = 0.5 * g["k"]
        w = half_k * (rate - target) * e_r + half_k * (v - rate * e_r)
        u = pair_feedforward(self.layout, obs) + w
        norm = np.linalg.norm(u, axis=-1, keepdims=True)
        return u / np.maximum(norm / self._limit, 1.0)
