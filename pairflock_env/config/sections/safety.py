"""Section ``safety``: the optional CBF safety filter on the paired UAVs' commands
(:mod:`pairflock_env.safety`, docs/safety.md)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

from pairflock_env.config.fields import Choice, Field, OrNone, Real
from pairflock_env.config.limits import MAX_DISTANCE, MAX_GAIN
from pairflock_env.config.schema import Rule, Section

__all__ = [
    "BRAKE_SHARE",
    "DECAY",
    "OTHER_SHARE",
    "QUAD_DECAY",
    "QUAD_OTHER_SHARE",
    "QUAD_REACTION_CYCLES",
    "RULES",
    "SECTIONS",
    "SENSING_RADIUS",
    "brake_accel",
    "decay",
    "other_accel",
    "quad_accel_bound",
    "reaction_time",
    "sensing_radius",
]

#: share of ``pair_accel_limit`` a paired UAV counts on for braking when unset
BRAKE_SHARE = 0.8
#: share of ``pair_accel_limit`` assumed for unpaired UAVs' acceleration when unset; the
#: barrier against an unpaired UAV brakes at (BRAKE_SHARE - OTHER_SHARE) pair_accel_limit
OTHER_SHARE = 0.4
#: barrier rate lambda when unset (particle model)
DECAY = 0.5
#: default sensing radius R_s (m): the smallest of 20-120 m with which no filtered tuning run
#: (seeds 2000-2019: the safe generalist at pair_accel_limit 50, sliding mode, the
#: proportional method and the generalist at 1000) had an infeasible step (docs/safety.md)
SENSING_RADIUS = 100.0

# Quadrotor defaults (``dynamics="quadrotor"``, docs/safety.md "Quadrotors"): the vehicle
# realises at most ``quad_accel_bound`` and realises it late (its attitude loop), so the unset
# parameters follow the vehicle. They reproduce the setting selected on the tuning
# seeds 60000-60099 of the paper-quadrotor scenario (alpha 6, A_o 2, tau 0.1 s, lambda 0.1).
#: A_o is at most this share of :func:`quad_accel_bound` (alpha at most all of it)
QUAD_OTHER_SHARE = 1.0 / 3.0
#: tau = QUAD_REACTION_CYCLES / quad_attitude_freq (the attitude loop's time scale 1/wn;
#: 0.1 s at the default 15 rad/s, the only frequency it was measured at)
QUAD_REACTION_CYCLES = 1.5
#: barrier rate lambda when unset on the quadrotor
QUAD_DECAY = 0.1
#: largest reaction time tau (s) the field accepts; the quadrotor's derived one must fit too
MAX_REACTION_TIME = 10.0


def _quadrotor(v: Any) -> bool:
    return getattr(v, "dynamics", "particle") == "quadrotor"


def quad_accel_bound(v: Any) -> float:
    """The horizontal acceleration (m/s^2) a hovering quadrotor can realise:
    min(``quad_accel_limit``, ``quad_gravity`` tan ``quad_tilt_limit``), the smaller of its
    command bound and its tilt cone (6 m/s^2 in the paper-quadrotor preset)."""
    tilt = math.radians(v.quad_tilt_limit)
    return min(v.quad_accel_limit, v.quad_gravity * math.tan(tilt))


def brake_accel(v: Any) -> float:
    """alpha (m/s^2): ``safety_brake_accel``, or ``BRAKE_SHARE x pair_accel_limit`` (on the
    quadrotor at most :func:`quad_accel_bound`)."""
    if v.safety_brake_accel is not None:
        return v.safety_brake_accel
    a = BRAKE_SHARE * v.pair_accel_limit
    return min(a, quad_accel_bound(v)) if _quadrotor(v) else a


def other_accel(v: Any) -> float:
    """A_o (m/s^2): ``safety_other_accel``, or ``OTHER_SHARE x pair_accel_limit`` (on the
    quadrotor at most ``QUAD_OTHER_SHARE x`` :func:`quad_accel_bound`)."""
    if v.safety_other_accel is not None:
        return v.safety_other_accel
    o = OTHER_SHARE * v.pair_accel_limit
    return min(o, QUAD_OTHER_SHARE * quad_accel_bound(v)) if _quadrotor(v) else o


def reaction_time(v: Any) -> float:
    """tau (s): ``safety_reaction_time``, or 0 (on the quadrotor QUAD_REACTION_CYCLES /
    ``quad_attitude_freq``)."""
    if v.safety_reaction_time is not None:
        return v.safety_reaction_time
    return QUAD_REACTION_CYCLES / v.quad_attitude_freq if _quadrotor(v) else 0.0


def sensing_radius(v: Any) -> float:
    """R_s (m): ``safety_sensing_radius``, or the deprecated ``safety_lookahead_range`` where
    that is set and larger."""
    r, reach = v.safety_sensing_radius, v.safety_lookahead_range
    return r if reach is None else max(r, reach)


def decay(v: Any) -> float:
    """lambda: ``safety_decay``, or DECAY (on the quadrotor QUAD_DECAY)."""
    if v.safety_decay is not None:
        return v.safety_decay
    return QUAD_DECAY if _quadrotor(v) else DECAY


@dataclasses.dataclass(frozen=True)
class FilterChoice(Choice):
    """``"none"`` or ``"cbf"``; None means ``"none"`` (what the CLIs' value parser makes of
    ``--set safety_filter=none``)."""

    def valid(self) -> str:
        return super().valid() + " (None: 'none')"

    def check(self, name: str, value: Any, ctx: Mapping[str, Any] | None = None) -> str:
        return "none" if value is None else super().check(name, value, ctx)


SAFETY = Section(
    "safety",
    "Safety filter",
    "A decentralised braking-distance CBF filter between the decoded pair command and the "
    "vehicle model (pairflock_env.safety, docs/safety.md): each paired UAV replaces its pair "
    "command u by the nearest one with ||u|| <= pair_accel_limit (a ball, not the action "
    "box) that keeps safety_distance from every UAV it senses. Off by default.",
    (
        Field(
            "safety_filter",
            FilterChoice(("none", "cbf")),
            "none",
            "",
            '"none": the pair command is applied as decoded; "cbf": every paired UAV filters '
            "it (infos safety_active, safety_correction, safety_infeasible).",
        ),
        Field(
            "safety_distance",
            Real(1e-3, MAX_DISTANCE),
            1.0,
            "m",
            "Distance D_s every paired UAV keeps from every other UAV with the filter on.",
        ),
        Field(
            "safety_margin",
            Real(0.0, MAX_DISTANCE),
            0.01,
            "m",
            "Buffer delta: the barrier keeps safety_distance + safety_margin, which absorbs "
            "small breaks of the filter's assumptions (docs/safety.md).",
        ),
        Field(
            "safety_brake_accel",
            OrNone(
                Real(0.0, MAX_GAIN, lo_open=True),
                "0.8 pair_accel_limit; quadrotor: at most the vehicle's bound",
            ),
            None,
            "m/s^2",
            "Line-of-sight deceleration alpha a paired UAV counts on from its own acceleration "
            "when it must brake; at most pair_accel_limit. The quadrotor's bound is "
            "min(quad_accel_limit, quad_gravity tan quad_tilt_limit).",
        ),
        Field(
            "safety_other_accel",
            OrNone(Real(0.0, MAX_GAIN), "0.4 pair_accel_limit; quadrotor: at most its bound / 3"),
            None,
            "m/s^2",
            "Assumed bound A_o on an unpaired UAV's acceleration towards a paired UAV; below "
            "the brake acceleration.",
        ),
        Field(
            "safety_sensing_radius",
            Real(1e-3, MAX_DISTANCE),
            SENSING_RADIUS,
            "m",
            "A paired UAV constrains its command against the UAVs closer than this (and "
            "against its partner at any distance); above safety_distance + safety_margin. "
            "A UAV closing at V m/s must first be sensed on the safe side, roughly "
            "safety_distance + V^2 / (2 (brake - other accel)) away (docs/safety.md).",
        ),
        Field(
            "safety_lookahead_range",
            OrNone(Real(1e-3, MAX_DISTANCE), "safety_sensing_radius"),
            None,
            "m",
            "Deprecated: the filter senses out to the larger of this and "
            "safety_sensing_radius; set safety_sensing_radius instead.",
            deprecated="it now only extends safety_sensing_radius to its value (its entry "
            "rule made the filtered command chatter); set safety_sensing_radius instead",
        ),
        Field(
            "safety_reaction_time",
            OrNone(Real(0.0, MAX_REACTION_TIME), "0; quadrotor: 1.5 / quad_attitude_freq"),
            None,
            "s",
            "Reaction time tau of the barrier: a paired UAV counts on braking only after "
            "coasting tau at the current closing speed (for a vehicle that realises its "
            "command with a lag, such as the quadrotor's attitude loop); 0: at once.",
        ),
        Field(
            "safety_decay",
            OrNone(Real(0.0, 1.0, lo_open=True), "0.5; quadrotor: 0.1"),
            None,
            "1",
            "Discrete barrier rate lambda: H(k+1) >= (1 - lambda) H(k); 1 lets the state "
            "reach the braking curve in one step.",
        ),
    ),
)

SECTIONS = (SAFETY,)


def _brake_within_limit(v: Any) -> str | None:
    if v.safety_brake_accel is not None and v.safety_brake_accel > v.pair_accel_limit:
        return f"must be <= pair_accel_limit = {v.pair_accel_limit:g} m/s^2"
    return None


def _other_below_brake(v: Any) -> str | None:
    a, o = brake_accel(v), other_accel(v)
    if not o < a:
        return (
            f"must keep the other UAVs' bound safety_other_accel ({o:g} m/s^2) below the brake "
            f"acceleration safety_brake_accel ({a:g} m/s^2; None: 0.8 pair_accel_limit, on the "
            "quadrotor at most min(quad_accel_limit, quad_gravity tan quad_tilt_limit))"
        )
    return None


def _radius_beyond_distance(v: Any) -> str | None:
    if not v.safety_sensing_radius > v.safety_distance + v.safety_margin:
        return (
            f"must keep safety_sensing_radius ({v.safety_sensing_radius:g} m) above "
            f"safety_distance + safety_margin ({v.safety_distance:g} + {v.safety_margin:g} m)"
        )
    return None


def _derived_reaction_time_in_range(v: Any) -> str | None:
    if v.safety_filter != "cbf" or v.safety_reaction_time is not None or not _quadrotor(v):
        return None
    tau = reaction_time(v)
    if not tau <= MAX_REACTION_TIME:
        return (
            f"makes the unset safety_reaction_time {QUAD_REACTION_CYCLES:g} / "
            f"quad_attitude_freq = {tau:g} s, above the {MAX_REACTION_TIME:g} s it may be; "
            "set safety_reaction_time"
        )
    return None


RULES = (
    Rule(
        ("safety_brake_accel", "pair_accel_limit"),
        _brake_within_limit,
        "safety_brake_accel <= pair_accel_limit",
    ),
    Rule(
        (
            "safety_other_accel",
            "safety_brake_accel",
            "pair_accel_limit",
            "dynamics",
            "quad_accel_limit",
            "quad_gravity",
            "quad_tilt_limit",
        ),
        _other_below_brake,
        "safety_other_accel < the brake acceleration (each default or set)",
    ),
    Rule(
        ("safety_sensing_radius", "safety_distance", "safety_margin"),
        _radius_beyond_distance,
        "safety_sensing_radius > safety_distance + safety_margin",
    ),
    Rule(
        ("quad_attitude_freq", "safety_reaction_time", "safety_filter", "dynamics"),
        _derived_reaction_time_in_range,
        "the quadrotor's derived safety_reaction_time (1.5 / quad_attitude_freq) <= 10 s",
    ),
)
