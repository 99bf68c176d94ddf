"""The safety filter's parameters: a small frozen object built from scalars."""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any

from pairflock_env.config.sections import safety as _section
from pairflock_env.config.sections.safety import BRAKE_SHARE, DECAY, OTHER_SHARE, SENSING_RADIUS

__all__ = ["INTEGRATORS", "SafetyParams"]

#: particle integrators the discrete-time barrier is derived for (see docs/safety.md)
INTEGRATORS = ("semi_implicit", "exact")


def _real(name: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, numbers.Real):
        raise TypeError(f"{name}={v!r} is invalid: must be a real number")
    x = float(v)
    if not math.isfinite(x):
        raise ValueError(f"{name}={v!r} is invalid: must be finite")
    return x


@dataclasses.dataclass(frozen=True)
class SafetyParams:
    """Parameters of the braking-distance CBF filter (units in each field's doc).

    ``brake_accel`` and ``other_accel`` default to 0.8 and 0.4 of ``accel_limit``. Every
    field is validated on construction (``TypeError`` for a non-number, ``ValueError`` for a
    bad value); :meth:`from_config` takes ``accel_limit``, ``dt``, ``substeps`` and
    ``integrator`` from an env config.
    """

    accel_limit: float
    """U (m/s^2): bound on the magnitude ||u|| of the filtered pair command (a ball, not a
    box); the filter's output always satisfies it."""
    safety_distance: float = 1.0
    """D_s (m): the distance every paired UAV keeps from every other UAV."""
    margin: float = 0.01
    """delta (m): the barrier is built at :attr:`barrier_distance` = D_s + delta, a buffer
    against small breaks of the assumptions (an unpaired UAV pushed towards the agent
    harder than ``other_accel``, docs/safety.md); >= 0."""
    brake_accel: float | None = None
    """alpha (m/s^2): the line-of-sight deceleration a paired UAV counts on from its own
    acceleration f_i + u_i when it has to brake; 0 < alpha <= accel_limit. None: 0.8 U."""
    other_accel: float | None = None
    """A_o (m/s^2): assumed bound on an unpaired UAV's acceleration towards the agent
    (n . a_j <= A_o; for ``integrator="exact"`` or ``substeps > 1`` on its norm);
    0 <= A_o < alpha. None: 0.4 U."""
    sensing_radius: float = SENSING_RADIUS
    """R_s (m): an agent constrains itself against the UAVs closer than this (> D_s +
    delta), and against its partner (``SafetyFilter(partners=...)``) at any distance. A UAV
    closing at V is first sensed on the safe side if R_s >= :meth:`required_sensing_radius`
    (V), the radius condition (b) of docs/safety.md."""
    reaction_time: float = 0.0
    """tau (s): the barrier counts on braking only after coasting tau at the current range
    rate, E = d - D_s - delta + tau d' (a reaction-time braking distance, for a vehicle that
    realises its command with a lag, e.g. the quadrotor's attitude loop); >= 0. The
    distance itself is still constrained as with tau = 0."""
    decay: float = DECAY
    """lambda in (0, 1]: the discrete barrier condition is H(k+1) >= (1 - lambda) H(k);
    1 allows the state onto the braking curve in one step, smaller values approach it
    geometrically."""
    dt: float = 0.01
    """T (s): control period over which the command is held (zero-order hold)."""
    substeps: int = 1
    """Physics steps per control period of the semi-implicit Euler integrator."""
    integrator: str = "semi_implicit"
    """The env's particle integrator: ``"semi_implicit"`` or ``"exact"``."""

    def __post_init__(self) -> None:
        put = object.__setattr__
        U = _real("accel_limit", self.accel_limit)
        if U <= 0:
            raise ValueError(f"accel_limit={self.accel_limit!r} is invalid: must be > 0")
        put(self, "accel_limit", U)
        for name in ("safety_distance", "dt"):
            v = _real(name, getattr(self, name))
            if v <= 0:
                raise ValueError(f"{name}={getattr(self, name)!r} is invalid: must be > 0")
            put(self, name, v)
        a = BRAKE_SHARE * U if self.brake_accel is None else _real("brake_accel", self.brake_accel)
        if not 0 < a <= U:
            raise ValueError(
                f"brake_accel={self.brake_accel!r} is invalid: must be in (0, accel_limit={U}]"
            )
        put(self, "brake_accel", a)
        o = OTHER_SHARE * U if self.other_accel is None else _real("other_accel", self.other_accel)
        if not 0 <= o < a:
            raise ValueError(
                f"other_accel={self.other_accel!r} is invalid: must be in [0, brake_accel={a})"
            )
        put(self, "other_accel", o)
        m = _real("margin", self.margin)
        if m < 0:
            raise ValueError(f"margin={self.margin!r} is invalid: must be >= 0")
        put(self, "margin", m)
        r = _real("sensing_radius", self.sensing_radius)
        if not r > self.safety_distance + m:
            raise ValueError(
                f"sensing_radius={self.sensing_radius!r} is invalid: must exceed "
                f"safety_distance + margin = {self.safety_distance + m:g}"
            )
        put(self, "sensing_radius", r)
        tau = _real("reaction_time", self.reaction_time)
        if tau < 0:
            raise ValueError(f"reaction_time={self.reaction_time!r} is invalid: must be >= 0")
        put(self, "reaction_time", tau)
        lam = _real("decay", self.decay)
        if not 0 < lam <= 1:
            raise ValueError(f"decay={self.decay!r} is invalid: must be in (0, 1]")
        put(self, "decay", lam)
        s = self.substeps
        if isinstance(s, bool) or not isinstance(s, numbers.Integral):
            raise TypeError(f"substeps={s!r} is invalid: must be an integer >= 1")
        if int(s) < 1:
            raise ValueError(f"substeps={s!r} is invalid: must be an integer >= 1")
        put(self, "substeps", int(s))
        if not isinstance(self.integrator, str) or self.integrator not in INTEGRATORS:
            raise ValueError(
                f"integrator={self.integrator!r} is invalid: must be one of {INTEGRATORS}"
            )

    @classmethod
    def from_config(cls, config: Any, **overrides: Any) -> SafetyParams:
        """Parameters for an env config: ``accel_limit = pair_accel_limit``, the config's
        ``dt``, ``substeps``, ``integrator`` and its ``safety_*`` fields (section ``safety``:
        ``safety_distance``, ``safety_margin``, ``safety_brake_accel``,
        ``safety_other_accel``, ``safety_sensing_radius`` (or the deprecated
        ``safety_lookahead_range`` where that is larger), ``safety_reaction_time``,
        ``safety_decay``). The unset (None) ones follow the
        vehicle: the brake and other accelerations, the reaction time and the rate take the
        section's defaults for ``config.dynamics`` (:func:`~pairflock_env.config.sections.
        safety.brake_accel` and its siblings; on the quadrotor they depend on
        ``quad_accel_limit`` and ``quad_attitude_freq``). Keyword ``overrides`` replace any
        field."""
        kw: dict[str, Any] = dict(
            accel_limit=config.pair_accel_limit,
            dt=config.dt,
            substeps=config.substeps,
            integrator=config.integrator,
            safety_distance=config.safety_distance,
            margin=config.safety_margin,
            brake_accel=_section.brake_accel(config),
            other_accel=_section.other_accel(config),
            sensing_radius=_section.sensing_radius(config),
            reaction_time=_section.reaction_time(config),
            decay=_section.decay(config),
        )
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(overrides) - names)
        if unknown:
            raise TypeError(f"unknown safety parameter(s) {unknown}; valid: {sorted(names)}")
        kw.update(overrides)
        return cls(**kw)

    @property
    def barrier_distance(self) -> float:
        """D_s + delta (m): the distance the barrier keeps (``safety_distance + margin``)."""
        return self.safety_distance + self.margin

    @property
    def position_gain(self) -> float:
        """c of the held-command position update x+ = x + T w + c T^2 a: (S + 1) / (2 S)
        for S semi-implicit substeps, 1/2 for the exact integrator."""
        if self.integrator == "exact":
            return 0.5
        return (self.substeps + 1) / (2 * self.substeps)

    def barrier_accel(self, cooperative: bool) -> float:
        """alpha_ij (m/s^2) of the barrier against a UAV: 2 alpha for another filtered UAV
        (each brakes alpha), alpha - A_o for an unpaired one."""
        return 2 * self.brake_accel if cooperative else self.brake_accel - self.other_accel

    def required_sensing_radius(self, closing_speed: float, cooperative: bool = False) -> float:
        """Smallest R_s (m) such that a UAV closing at ``closing_speed`` (m/s) or less is
        first sensed on the safe side of the barrier: D_s + delta + V (T + tau) +
        max(0, V - beta)^2 / (2 alpha_ij), beta = (c - 1/2) alpha_ij T (docs/safety.md).
        It concerns the UAVs other than the agent's partner, which the filter senses at any
        distance."""
        v = _real("closing_speed", closing_speed)
        a = self.barrier_accel(cooperative)
        x = max(0.0, v - (self.position_gain - 0.5) * a * self.dt)
        return self.barrier_distance + v * (self.dt + self.reaction_time) + x * x / (2.0 * a)
