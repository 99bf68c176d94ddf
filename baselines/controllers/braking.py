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

**The detour** (``detour = H > 0``; off by default). The members' midpoint ``c`` is free:
the relative law above does not move it. A pair that starts far apart on opposite sides of
the flock would meet in the middle of it, where the protocol's consensus with every
neighbour holds back two UAVs that cross it, and the filter brakes them at its edge. With
the detour, both members add the same common-mode acceleration, which pushes ``c`` at least
``H`` away from the leader (the flock's pinning point), across the pair's axis:

    c_perp = component of (c - q_leader) across the axis,  n = c_perp / |c_perp|
    g = clip(k_c max(H s - |c_perp|, 0) - k_c s (dc/dt - p_leader) . n, +-G) n
    s = clip((||z|| - detour_near) / (detour_far - detour_near), 0, 1)

so the pair meets beside the flock and rejoins it together. Both members compute ``c``,
``n`` and ``g`` from their own observation (``c - q_leader = z/2 - leader_offset``), so they
agree; a midpoint already farther than ``H`` is left alone. When ``c`` is on the axis
(``c_perp = 0``, e.g. the paper's corner start, whose leader lies on the diagonal), the
member farther from the leader takes its ``+e_t`` (the pair frame's first tangent,
:func:`~pairflock_env.interfaces.pair_basis`) and the nearer one its ``-e_t``: the same world
direction for both, and one that a policy in the pair frame can observe (with the leader at
the midpoint, neither side is preferred and there is no detour). ``u_i`` is the
relative law scaled into the ball, plus ``g``, scaled into the ball again.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from baselines.controllers.base import PairPolicy, gain_value
from pairflock_env.interfaces import pair_basis, pair_feedforward

__all__ = ["BrakingCurveController"]

#: margin below the bound, so that float32 rounding of the action never exceeds it
_BALL_MARGIN = 1.0 - 1e-6
#: the detour's stiffness k_c (1/s^2, also its damping in 1/s) and its bound G (m/s^2)
_DETOUR_GAIN, _DETOUR_BOUND = 4.0, 40.0


class BrakingCurveController(PairPolicy):
    """Feed-forward + braking-curve closing law within a ball; see the module docstring."""

    GAINS = {
        "a_b": (None, "relative deceleration of the braking curve (m/s^2); None: 0.9 x the bound"),
        "k": (20.0, "tracking rate of the closing speed and the tangential damping (1/s)"),
        "k_e": (6.0, "slope of the closing-speed curve near the target, r* = -k_e e (1/s)"),
        "accel_limit": (None, "bound on ||u|| (m/s^2); None: the env's pair_accel_limit"),
        "detour": (0.0, "least distance of the midpoint from the leader across the axis (m)"),
        "detour_near": (40.0, "pair distance below which the detour is off (m)"),
        "detour_far": (100.0, "pair distance above which the detour is fully on (m)"),
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
        for name in ("detour", "detour_near"):
            self.gains[name] = gain_value(name, self.gains[name], minimum=0.0, allow_minimum=True)
        far = gain_value("detour_far", self.gains["detour_far"], minimum=0.0, allow_minimum=False)
        if far <= self.gains["detour_near"]:
            raise ValueError(
                f"detour_far={far!r} is invalid: must be > detour_near="
                f"{self.gains['detour_near']!r}"
            )
        self.gains["detour_far"] = far

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
        u = self._into_ball(pair_feedforward(self.layout, obs) + w)
        if g["detour"] > 0.0:
            u = self._into_ball(u + self._detour(obs, z, v, dist))
        return u

    def _into_ball(self, u: np.ndarray) -> np.ndarray:
        norm = np.linalg.norm(u, axis=-1, keepdims=True)
        return u / np.maximum(norm / self._limit, 1.0)

    def _detour(self, obs: np.ndarray, z, v, dist) -> np.ndarray:
        """The common-mode acceleration g of the module docstring (..., dim)."""
        get, g = self.layout.get, self.gains
        e_r, e_t = np.moveaxis(pair_basis(z)[..., :2, :], -2, 0)
        lead = get(obs, "leader_offset")
        c = 0.5 * z - lead  # midpoint minus leader
        c_perp = c - np.sum(c * e_r, axis=-1, keepdims=True) * e_r
        across = np.linalg.norm(c_perp, axis=-1, keepdims=True)
        # on the axis: the member farther from the leader takes +e_t, the nearer one -e_t
        # (neither when the leader is at the midpoint: no side is preferred)
        farther = np.sign(np.sum(lead * lead - (lead - z) ** 2, axis=-1, keepdims=True))
        n = np.where(across > 1e-9, c_perp / np.maximum(across, 1e-9), farther * e_t)
        ramp = np.clip((dist - g["detour_near"]) / (g["detour_far"] - g["detour_near"]), 0.0, 1.0)
        drift = np.sum((0.5 * v - get(obs, "leader_velocity")) * n, axis=-1, keepdims=True)
        push = _DETOUR_GAIN * (np.maximum(g["detour"] * ramp - across, 0.0) - ramp * drift)
        return np.clip(push, -_DETOUR_BOUND, _DETOUR_BOUND) * n
