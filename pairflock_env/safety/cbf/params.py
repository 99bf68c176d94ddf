"""The safety filter's parameters, declared like the env config's fields (one record, one
validation, one table in docs/config.md)."""

from __future__ import annotations

import math
from typing import Any

from pairflock_env.config.fields import Auto, Choice, Field, Int, Real, fmt_num
from pairflock_env.config.limits import MAX_GAIN, MAX_REACTION_TIME, MAX_SUBSTEPS
from pairflock_env.config.schema import Record, Rule, Schema, Section, declare_record
from pairflock_env.config.sections import safety as _section
from pairflock_env.config.sections.safety import BRAKE_SHARE, DECAY, OTHER_SHARE, SENSING_RADIUS

__all__ = ["INTEGRATORS", "SAFETY_SCHEMA", "SafetyParams"]

#: particle integrators the discrete-time barrier is derived for (see docs/safety.md)
INTEGRATORS = ("semi_implicit", "exact")

_ACCEL = Real(0.0, MAX_GAIN, lo_open=True)
#: distances (m): any finite positive size a test or a large arena may need
_DISTANCE = Real(0.0, 1e12, lo_open=True)

_FIELDS = (
    Field(
        "accel_limit",
        _ACCEL,
        None,
        "m/s^2",
        "U: bound on the magnitude ||u|| of the filtered command (a ball, not a box); the "
        "filter's output always satisfies it.",
    ),
    Field(
        "safety_distance",
        _DISTANCE,
        1.0,
        "m",
        "D_s: the distance every filtering UAV keeps from every other UAV.",
    ),
    Field(
        "margin",
        Real(0.0, 1e12),
        0.01,
        "m",
        "delta: the barrier is built at barrier_distance = D_s + delta, a buffer against small "
        "breaks of the assumptions (an unpaired UAV pushed harder than other_accel).",
    ),
    Field(
        "brake_accel",
        _ACCEL,
        None,
        "m/s^2",
        "alpha: the line-of-sight deceleration a filtering UAV counts on from its own "
        "acceleration when it has to brake; 0 < alpha <= accel_limit.",
        auto=Auto(lambda v: BRAKE_SHARE * v.accel_limit, ("accel_limit",), "0.8 accel_limit"),
    ),
    Field(
        "other_accel",
        Real(0.0, MAX_GAIN),
        None,
        "m/s^2",
        "A_o: assumed bound on an unfiltered UAV's acceleration towards the agent (n . a_j <= "
        "A_o; for the exact integrator or substeps > 1 on its norm); 0 <= A_o < alpha.",
        auto=Auto(lambda v: OTHER_SHARE * v.accel_limit, ("accel_limit",), "0.4 accel_limit"),
    ),
    Field(
        "sensing_radius",
        _DISTANCE,
        SENSING_RADIUS,
        "m",
        "R_s: a UAV constrains itself against the UAVs closer than this (> D_s + delta) and "
        "against its partner at any distance; radius condition (b) of docs/safety.md.",
    ),
    Field(
        "reaction_time",
        Real(0.0, MAX_REACTION_TIME),
        0.0,
        "s",
        "tau: the barrier counts on braking only after coasting tau at the current range "
        "rate (a vehicle that realises its command with a lag); the distance itself is "
        "still constrained as with tau = 0.",
    ),
    Field(
        "decay",
        Real(0.0, 1.0, lo_open=True),
        DECAY,
        "1",
        "lambda: the discrete barrier condition is H(k+1) >= (1 - lambda) H(k); 1 allows the "
        "state onto the braking curve in one step.",
    ),
    Field("dt", Real(1e-6, 1.0), 0.01, "s", "T: control period the command is held over."),
    Field(
        "substeps",
        Int(1, MAX_SUBSTEPS),
        1,
        "steps",
        "Physics steps per control period of the semi-implicit Euler integrator.",
    ),
    Field("integrator", Choice(INTEGRATORS), "semi_implicit", "", "The particle integrator."),
)


def _brake_within(v: Any) -> str | None:
    if not v.brake_accel <= v.accel_limit:
        return f"must be in (0, accel_limit={fmt_num(v.accel_limit)}]"
    return None


def _other_below(v: Any) -> str | None:
    if not v.other_accel < v.brake_accel:
        return f"must be in [0, brake_accel={fmt_num(v.brake_accel)})"
    return None


def _radius_beyond(v: Any) -> str | None:
    if not v.sensing_radius > v.safety_distance + v.margin:
        return f"must exceed safety_distance + margin = {v.safety_distance + v.margin:g}"
    return None


#: the declared parameters of :class:`SafetyParams`
SAFETY_SCHEMA = Schema(
    "safety parameter",
    (Section("safety_params", "Safety filter parameters", "SafetyParams", _FIELDS),),
    (
        Rule(("brake_accel", "accel_limit"), _brake_within, "brake_accel <= accel_limit"),
        Rule(("other_accel", "brake_accel"), _other_below, "other_accel < brake_accel"),
        Rule(
            ("sensing_radius", "safety_distance", "margin"),
            _radius_beyond,
            "sensing_radius > safety_distance + margin",
        ),
    ),
)


class _SafetyParamsMethods(Record):
    """Derived quantities of :class:`SafetyParams`."""

    @classmethod
    def from_config(cls, config: Any, **overrides: Any) -> Any:
        """Parameters for an env config: ``accel_limit = pair_accel_limit``, the config's
        ``dt``, ``substeps``, ``integrator`` and its ``safety_*`` fields. The unset (None)
        ones follow the vehicle model (:func:`~pairflock_env.config.sections.safety.
        brake_accel` and its siblings). Keyword ``overrides`` replace any field."""
        kw: dict[str, Any] = dict(
            accel_limit=config.pair_accel_limit,
            dt=config.dt,
            substeps=config.substeps,
            integrator=config.integrator,
            safety_distance=config.safety_distance,
            margin=config.safety_margin,
            brake_accel=_section.brake_accel(config),
            other_accel=_section.other_accel(config),
            sensing_radius=config.safety_sensing_radius,
            reaction_time=_section.reaction_time(config),
            decay=_section.decay(config),
        )
        kw.update(cls.schema.resolve(overrides))
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
        v = Real(-math.inf, math.inf).check("closing_speed", closing_speed)
        a = self.barrier_accel(cooperative)
        x = max(0.0, v - (self.position_gain - 0.5) * a * self.dt)
        return self.barrier_distance + v * (self.dt + self.reaction_time) + x * x / (2.0 * a)


SafetyParams = declare_record(
    "SafetyParams",
    SAFETY_SCHEMA,
    _SafetyParamsMethods,
    "pairflock_env.safety",
    """Parameters of the braking-distance CBF filter (units and ranges: docs/config.md).

    A frozen record with keyword-only construction, declared like the env config:
    ``TypeError`` for an unknown name or a non-number, ``ValueError`` for a bad value, each
    naming the parameter. ``brake_accel`` and ``other_accel`` default to 0.8 and 0.4 of
    ``accel_limit``; :meth:`from_config` takes them, ``accel_limit``, ``dt``, ``substeps``
    and ``integrator`` from an env config.
    """,
)
