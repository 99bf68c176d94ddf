"""Virtual-leader trajectories (q_gamma, p_gamma of eq. 19).

A trajectory is any object with ``state(t) -> (q, p)`` where ``t`` has shape (B,) (the sim
time of each swarm) and ``q``, ``p`` have shape (B, dim). Trajectories are pure functions of
time, so a batch of swarms at different times (after auto-resets) is handled naturally.
New trajectory types register in :data:`LEADERS` and are picked by ``config.leader``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from .config import PairFlockConfig

__all__ = [
    "LeaderTrajectory",
    "ConstantVelocityLeader",
    "ClimbAndTurnLeader",
    "LEADERS",
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
        t = np.asarray(t, dtype=np.float64)[:, None]
        q = self.q0 + t * self.v
        p = np.broadcast_to(self.v, q.shape).copy()
        return q, p


# Gauss-Legendre nodes and weights on [0, 1] for the position integral inside a turn; the
# integrand cos/sin(psi(t)) is smooth, so 24 nodes reach float64 rounding for any turn
# shorter than a few revolutions.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(24)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


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
    Gauss-Legendre quadrature from the turn's start. Everything is a pure function of t, so
    swarms at different times are evaluated together. In 2-D there is no climb.

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
        # heading after each turn and horizontal position at each turn's end
        self._psi_after = self.psi0 + np.cumsum(self.turns[:, 2])
        ends = self.turns[:, 0] + self.turns[:, 1]
        self._xy_end = np.zeros((len(turns), 2))
        xy, t_prev, psi_prev = np.zeros(2), 0.0, self.psi0
        for k in range(len(turns)):
            t0 = self.turns[k, 0]
            xy = xy + self.speed * (t0 - t_prev) * np.array([np.cos(psi_prev), np.sin(psi_prev)])
            xy = xy + self._turn_integral(k, np.array([ends[k]]))[0]
            self._xy_end[k] = xy
            t_prev, psi_prev = ends[k], self._psi_after[k]

    def heading(self, t: np.ndarray) -> np.ndarray:
        """psi(t) in rad, shape of t."""
        t = np.asarray(t, dtype=np.float64)
        psi = np.full(t.shape, self.psi0)
        for t0, dur, ang in self.turns:
            u = np.clip((t - t0) / dur, 0.0, 1.0)
            psi += ang * 0.5 * (1.0 - np.cos(np.pi * u))
        return psi

    def _turn_integral(self, k: int, t: np.ndarray) -> np.ndarray:
        """integral of V (cos psi, sin psi) from turn k's start to t (inside the turn), (n, 2)."""
        t0 = self.turns[k, 0]
        span = t - t0
        nodes = t0 + span[:, None] * _GL_X  # (n, G)
        psi = self.heading(nodes)
        c = (np.cos(psi) * _GL_W).sum(axis=1)
        s = (np.sin(psi) * _GL_W).sum(axis=1)
        return self.speed * span[:, None] * np.stack([c, s], axis=1)

    def _vertical(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c, tc, tl = self.climb_rate, self.climb_time, self.level_time
        tau = np.clip(t - tc, 0.0, tl) if np.isfinite(tc) else np.zeros_like(t)
        climbing = t <= tc
        z = np.where(climbing, c * t, c * tc)
        vz = np.where(climbing, c, 0.0)
        if tl > 0 and np.isfinite(tc):
            fading = (t > tc) & (t < tc + tl)
            vz = np.where(fading, c * 0.5 * (1.0 + np.cos(np.pi * tau / tl)), vz)
            z = z + np.where(t > tc, c * 0.5 * (tau + tl / np.pi * np.sin(np.pi * tau / tl)), 0.0)
        return z, vz

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=np.float64).reshape(-1)
        psi = self.heading(t)
        p = np.zeros((t.shape[0], self.dim))
        p[:, 0] = self.speed * np.cos(psi)
        p[:, 1] = self.speed * np.sin(psi)
        # horizontal position: from the end of the last completed turn (or from t = 0), straight
        # at that turn's final heading, then the quadrature of the turn in progress (if any)
        xy = np.zeros((t.shape[0], 2))
        base_t = np.zeros(t.shape[0])
        base_psi = np.full(t.shape[0], self.psi0)
        straight_until = t
        n_turns = len(self.turns)
        if n_turns:
            starts = self.turns[:, 0]
            ends = starts + self.turns[:, 1]
            k = np.searchsorted(starts, t, side="right") - 1  # last turn started by t (-1: none)
            kc = np.maximum(k, 0)
            in_turn = (k >= 0) & (t < ends[kc])
            done = np.where(in_turn, k - 1, k)  # last turn completed by t
            dc = np.maximum(done, 0)
            has = done >= 0
            xy = np.where(has[:, None], self._xy_end[dc], 0.0)
            base_t = np.where(has, ends[dc], 0.0)
            base_psi = np.where(has, self._psi_after[dc], self.psi0)
            straight_until = np.where(in_turn, starts[kc], t)
        xy = xy + self.speed * (straight_until - base_t)[:, None] * np.stack(
            [np.cos(base_psi), np.sin(base_psi)], axis=1
        )
        if n_turns:
            for kk in np.unique(k[in_turn]):
                sel = in_turn & (k == kk)
                xy[sel] += self._turn_integral(int(kk), t[sel])
        q = np.empty((t.shape[0], self.dim))
        q[:, :2] = self.q0[:2] + xy
        if self.dim == 3:
            z, vz = self._vertical(t)
            q[:, 2] = self.q0[2] + z
            p[:, 2] = vz
        return q, p


LEADERS: dict[str, Callable[[PairFlockConfig], LeaderTrajectory]] = {
    "constant_velocity": lambda cfg: ConstantVelocityLeader(
        cfg.vector("leader_position"), cfg.vector("leader_velocity")
    ),
    "climb_and_turn": lambda cfg: ClimbAndTurnLeader(
        cfg.vector("leader_position"),
        cfg.vector("leader_velocity"),
        turns=[(t0, dur, np.radians(ang)) for t0, dur, ang in cfg.leader_turns],
        climb_time=cfg.leader_climb_time,
        level_time=cfg.leader_level_time,
    ),
}


def make_leader(config: PairFlockConfig) -> LeaderTrajectory:
    return LEADERS[config.leader](config)
