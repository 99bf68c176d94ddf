"""Virtual-leader trajectories (q_gamma, p_gamma of eq. 19).

A trajectory is any object with ``state(t) -> (q, p)`` where ``t`` has shape (B,) (the sim
time of each swarm) and ``q``, ``p`` have shape (B, dim). Trajectories are pure functions of
time, so a batch of swarms at different times (after auto-resets) is handled naturally.
A trajectory type is a :class:`Leader` entry of :data:`LEADERS`, picked by ``config.leader``
(docs/extending.md).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from numba import njit

from pairflock_env.config import PairFlockConfig
from pairflock_env.config.registry import LEADERS, Plugin

__all__ = [
    "LEADERS",
    "ClimbAndTurnLeader",
    "ConstantVelocityLeader",
    "Leader",
    "LeaderTrajectory",
    "make_leader",
]


class LeaderTrajectory(Protocol):
    dim: int

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position and velocity, each (B, dim), at times ``t`` (B,)."""
        ...


class ConstantVelocityLeader:
    """q(t) = q0 + v t, p(t) = v (Sec. VI-A)."""

    def __init__(self, position: np.ndarray, velocity: np.ndarray) -> None:
        self.q0 = np.asarray(position, dtype=np.float64)
        self.v = np.asarray(velocity, dtype=np.float64)
        self.dim = self.q0.shape[0]

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if type(t) is not np.ndarray or t.dtype != np.float64 or t.ndim != 1:
            t = np.ascontiguousarray(t, dtype=np.float64).reshape(-1)
        q = np.empty((t.shape[0], self.dim))
        p = np.empty((t.shape[0], self.dim))
        _constant_velocity_state(t, self.q0, self.v, q, p)
        return q, p


@njit(cache=True)
def _constant_velocity_state(t, q0, v, q, p):
    """q = q0 + t v, p = v for each swarm's time (one call: a numpy expression costs a few
    microseconds at B = 1, this a fraction of one)."""
    for b in range(t.shape[0]):
        for k in range(q0.shape[0]):
            q[b, k] = q0[k] + t[b] * v[k]
            p[b, k] = v[k]


# Gauss-Legendre nodes and weights on [0, 1] for the position integral inside a turn; the
# integrand cos/sin(psi(t)) is smooth, so 24 nodes reach float64 rounding for any turn
# shorter than a few revolutions.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(24)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


@njit(cache=True)
def _heading(t, psi0, turns):
    """psi(t) = psi0 + sum_k A_k S((t - t_k) / T_k), turns rows (t_k, T_k, A_k [rad])."""
    psi = psi0
    for k in range(turns.shape[0]):
        u = (t - turns[k, 0]) / turns[k, 1]
        if u >= 1.0:
            psi += turns[k, 2]
        elif u > 0.0:
            psi += turns[k, 2] * 0.5 * (1.0 - math.cos(math.pi * u))
    return psi


@njit(cache=True)
def _turn_integral(t0, t, speed, psi0, turns, gx, gw):
    """integral_{t0}^{t} V (cos psi, sin psi) dt by Gauss-Legendre quadrature."""
    span = t - t0
    cx = 0.0
    cy = 0.0
    for g in range(gx.shape[0]):
        ps = _heading(t0 + span * gx[g], psi0, turns)
        cx += gw[g] * math.cos(ps)
        cy += gw[g] * math.sin(ps)
    return speed * span * cx, speed * span * cy


@njit(cache=True)
def _climb_turn_state(t, q0, speed, psi0, climb, tc, tl, turns, psi_after, xy_end, gx, gw, q, p):
    D = q0.shape[0]
    K = turns.shape[0]
    for b in range(t.shape[0]):
        ti = t[b]
        psi = _heading(ti, psi0, turns)
        p[b, 0] = speed * math.cos(psi)
        p[b, 1] = speed * math.sin(psi)
        # from the end of the last completed turn (or t = 0), straight at its final heading,
        # then the quadrature of the turn in progress (if any)
        x = 0.0
        y = 0.0
        base_t = 0.0
        base_psi = psi0
        current = -1
        for k in range(K):
            end = turns[k, 0] + turns[k, 1]
            if ti >= end:
                x, y = xy_end[k, 0], xy_end[k, 1]
                base_t, base_psi = end, psi_after[k]
            else:
                if ti > turns[k, 0]:
                    current = k
                break
        straight_to = ti if current < 0 else turns[current, 0]
        x += speed * (straight_to - base_t) * math.cos(base_psi)
        y += speed * (straight_to - base_t) * math.sin(base_psi)
        if current >= 0:
            dx, dy = _turn_integral(turns[current, 0], ti, speed, psi0, turns, gx, gw)
            x += dx
            y += dy
        q[b, 0] = q0[0] + x
        q[b, 1] = q0[1] + y
        if D == 3:
            # climb at c until tc, fade to 0 along a half-cosine over tl, then level
            if ti <= tc:
                z, vz = climb * ti, climb
            else:
                tau = min(ti - tc, tl)
                z = climb * tc
                vz = 0.0
                if tl > 0.0:
                    z += climb * 0.5 * (tau + tl / math.pi * math.sin(math.pi * tau / tl))
                    if ti < tc + tl:
                        vz = climb * 0.5 * (1.0 + math.cos(math.pi * tau / tl))
            q[b, 2] = q0[2] + z
            p[b, 2] = vz


class ClimbAndTurnLeader:
    """Constant ground speed with a climb phase and smooth heading turns (Sec. VI-B).

    With horizontal speed V and initial heading psi0 (from the horizontal part of ``velocity``)
    and climb rate c (its vertical part, 3-D only):

        psi(t)  = psi0 + sum_k A_k S((t - t_k) / T_k),  S(u) = (1 - cos(pi u)) / 2 on [0, 1],
                  0 before, 1 after                         (turn k: start t_k, length T_k)
        p_xy(t) = V (cos psi(t), sin psi(t))
        p_z(t)  = c for t <= t_c; c (1 + cos(pi (t - t_c) / T_l)) / 2 for t_c < t < t_c + T_l;
                  0 afterwards                             (climb time t_c, level-off T_l)
        q(t)    = q0 + integral_0^t p

    The integral is exact (closed form) on straight segments and for z; inside a turn it uses
    24-point Gauss-Legendre quadrature from the turn's start. Everything is a pure function of
    t (a numba loop over the swarms' times), so swarms at different times are evaluated
    together. In 2-D there is no climb.

    Args:
        position, velocity: q(0) and p(0), each (dim,).
        turns: ((start s, duration s, angle rad), ...) in time order, not overlapping.
        climb_time: t_c in s (None: the vertical velocity is kept forever).
        level_time: T_l in s (0: the climb stops at once).
    """

    def __init__(
        self,
        position: np.ndarray,
        velocity: np.ndarray,
        turns=(),
        climb_time: float | None = None,
        level_time: float = 0.0,
    ) -> None:
        self.q0 = np.asarray(position, dtype=np.float64)
        v0 = np.asarray(velocity, dtype=np.float64)
        self.dim = self.q0.shape[0]
        if v0.shape != (self.dim,) or self.dim not in (2, 3):
            raise ValueError(
                f"velocity has shape {v0.shape}; expected ({self.dim},) like position (dim 2 or 3)"
            )
        self.speed = float(np.hypot(v0[0], v0[1]))
        self.psi0 = float(np.arctan2(v0[1], v0[0]))
        self.climb_rate = float(v0[2]) if self.dim == 3 else 0.0
        self.climb_time = np.inf if climb_time is None else float(climb_time)
        self.level_time = float(level_time)
        if self.level_time < 0:
            raise ValueError(f"level_time={level_time!r} is invalid: must be >= 0")
        turns = [(float(a), float(b), float(c)) for a, b, c in turns]
        for k, (t0, dur, _) in enumerate(turns):
            if dur <= 0 or t0 < 0 or (k and t0 < turns[k - 1][0] + turns[k - 1][1]):
                raise ValueError(
                    f"turns={turns!r} is invalid: need start >= 0, duration > 0, in time order "
                    "without overlap"
                )
        if turns and self.speed == 0:
            raise ValueError(f"velocity={v0.tolist()} is invalid: turns need a horizontal speed")
        self.turns = np.asarray(turns, dtype=np.float64).reshape(-1, 3)
        # heading after each turn and horizontal position (from q0) at each turn's end
        self._psi_after = self.psi0 + np.cumsum(self.turns[:, 2])
        self._xy_end = np.zeros((len(turns), 2))
        xy, t_prev, psi_prev = np.zeros(2), 0.0, self.psi0
        for k, (t0, dur, _) in enumerate(self.turns):
            xy = xy + self.speed * (t0 - t_prev) * np.array([np.cos(psi_prev), np.sin(psi_prev)])
            xy = xy + np.array(
                _turn_integral(t0, t0 + dur, self.speed, self.psi0, self.turns, _GL_X, _GL_W)
            )
            self._xy_end[k] = xy
            t_prev, psi_prev = t0 + dur, self._psi_after[k]

    def heading(self, t: np.ndarray) -> np.ndarray:
        """psi(t) in rad, shape of t."""
        t = np.asarray(t, dtype=np.float64)
        return np.array([_heading(x, self.psi0, self.turns) for x in t.reshape(-1)]).reshape(
            t.shape
        )

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.ascontiguousarray(t, dtype=np.float64).reshape(-1)
        q = np.empty((t.shape[0], self.dim))
        p = np.empty((t.shape[0], self.dim))
        _climb_turn_state(
            t,
            self.q0,
            self.speed,
            self.psi0,
            self.climb_rate,
            self.climb_time,
            self.level_time,
            self.turns,
            self._psi_after,
            self._xy_end,
            _GL_X,
            _GL_W,
            q,
            p,
        )
        return q, p


@dataclasses.dataclass(frozen=True, kw_only=True)
class Leader(Plugin):
    """A registered leader trajectory.

    Attributes (besides :class:`~pairflock_env.config.registry.Plugin`'s):
        trajectory: builds it for a config, ``trajectory(config) -> LeaderTrajectory``.
        speed_bound: per-axis bound (dim,) of |leader velocity| over any episode of a
            config; the views' observation bounds follow from it.
    """

    trajectory: Callable[[Any], LeaderTrajectory]
    speed_bound: Callable[[Any], np.ndarray]


def _climb_turn_speed(cfg: Any) -> np.ndarray:
    """The horizontal speed on every horizontal axis (turns rotate it), the climb rate up."""
    v0 = cfg.vector("leader_velocity")
    vmax = np.full(cfg.dim, float(np.hypot(v0[0], v0[1])))
    if cfg.dim == 3:
        vmax[2] = abs(v0[2])
    return vmax


def make_leader(config: PairFlockConfig) -> LeaderTrajectory:
    """The leader trajectory ``config.leader``."""
    return LEADERS[config.leader].trajectory(config)


LEADERS.register(
    Leader(
        name="constant_velocity",
        doc="q(t) = q0 + v t (Sec. VI-A)",
        trajectory=lambda cfg: ConstantVelocityLeader(
            cfg.vector("leader_position"), cfg.vector("leader_velocity")
        ),
        speed_bound=lambda cfg: np.abs(cfg.vector("leader_velocity")),
    )
)
LEADERS.register(
    Leader(
        name="climb_and_turn",
        doc="climb, level off, turn at constant ground speed (Sec. VI-B)",
        trajectory=lambda cfg: ClimbAndTurnLeader(
            cfg.vector("leader_position"),
            cfg.vector("leader_velocity"),
            turns=[(t0, dur, np.radians(ang)) for t0, dur, ang in cfg.leader_turns],
            climb_time=cfg.leader_climb_time,
            level_time=cfg.leader_level_time,
        ),
        speed_bound=_climb_turn_speed,
    )
)
