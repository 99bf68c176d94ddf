"""Section ``safety``: the optional CBF safety filter on the paired UAVs' commands
(:mod:`pairflock_env.safety`, docs/safety.md), and its swarm scope, where every UAV filters
its whole command (:mod:`pairflock_env.safety.cbf.swarm`, docs/swarm-safety.md)."""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import Choice, Field, Flag, OrNone, Real
from pairflock_env.config.limits import MAX_DISTANCE, MAX_GAIN, MAX_REACTION_TIME
from pairflock_env.config.registry import FILTERS, VEHICLES, Registered
from pairflock_env.config.schema import Rule, Section

__all__ = [
    "BOUND_OTHER_SHARE",
    "BRAKE_SHARE",
    "DECAY",
    "OTHER_SHARE",
    "RULES",
    "SCOPES",
    "SECTIONS",
    "SENSING_RADIUS",
    "SWARM_ACCEL_LIMIT",
    "brake_accel",
    "decay",
    "other_accel",
    "reaction_time",
    "swarm_accel_limit",
    "swarm_brake_accel",
    "swarm_sensing_radius",
]

#: share of ``pair_accel_limit`` a paired UAV counts on for braking when unset
BRAKE_SHARE = 0.8
#: share of ``pair_accel_limit`` assumed for unpaired UAVs' acceleration when unset; the
#: barrier against an unpaired UAV brakes at (BRAKE_SHARE - OTHER_SHARE) pair_accel_limit
OTHER_SHARE = 0.4
#: barrier rate lambda when unset (and the vehicle model gives none)
DECAY = 0.5
#: default sensing radius R_s (m): the smallest of 20-120 m with which no filtered tuning run
#: (seeds 2000-2019: the safe generalist at pair_accel_limit 50, sliding mode, the
#: proportional method and the generalist at 1000) had an infeasible step (docs/safety-results.md)
SENSING_RADIUS = 100.0
#: what the filter covers: the paired UAVs' pair commands, or every UAV's whole command
SCOPES = ("pairs", "swarm")
#: default bound U_s on an unpaired UAV's whole command under the swarm scope (m/s^2, 2 g):
#: the paper's flocking command peaks at 10-36 m/s^2 only in the first step of a start with
#: UAVs 2 m apart, and stays below 9.2 m/s^2 after 5 s at N = 20-100 (docs/swarm-safety.md)
SWARM_ACCEL_LIMIT = 20.0

# A vehicle model that realises at most some acceleration, and realises it late (the
# quadrotor's attitude loop), sets the unset parameters from its own physics
# (pairflock_env.dynamics.Vehicle: accel_bound, reaction_time, safety_decay). For the
# quadrotor they reproduce the setting selected on the tuning seeds 60000-60099 of the
# paper-quadrotor scenario (alpha 6, A_o 2, tau 0.1 s, lambda 0.1; docs/safety-results.md).
#: with a vehicle bound, A_o is at most this share of it (alpha at most all of it)
BOUND_OTHER_SHARE = 1.0 / 3.0
#: under the swarm scope every UAV's command is filtered and realised late, and the
#: vehicle's lag alone (0.1 s for the quadrotor) left one to three infeasible UAV-steps in
#: 50 runs of the 10-quadrotor experiment and, on seeds 73000-73049, two quadrotors 0.9935 m
#: apart: the unset reaction time is this multiple of the lag (selected on seed 72040 and
#: seeds 73000-73049; measured on 74000-74049: docs/swarm-safety-results.md)
SWARM_LAG_FACTOR = 1.5


def _bound(v: Any) -> float | None:
    """The acceleration the chosen vehicle model can realise (m/s^2), None if unbounded."""
    rule = VEHICLES[v.dynamics].accel_bound
    return None if rule is None else rule(v)


def brake_accel(v: Any) -> float:
    """alpha (m/s^2): ``safety_brake_accel``, or ``BRAKE_SHARE x pair_accel_limit`` (at most
    the vehicle's bound)."""
    if v.safety_brake_accel is not None:
        return v.safety_brake_accel
    a, bound = BRAKE_SHARE * v.pair_accel_limit, _bound(v)
    return a if bound is None else min(a, bound)


def other_accel(v: Any) -> float:
    """A_o (m/s^2): ``safety_other_accel``, or ``OTHER_SHARE x pair_accel_limit`` (at most
    ``BOUND_OTHER_SHARE x`` the vehicle's bound)."""
    if v.safety_other_accel is not None:
        return v.safety_other_accel
    o, bound = OTHER_SHARE * v.pair_accel_limit, _bound(v)
    return o if bound is None else min(o, BOUND_OTHER_SHARE * bound)


def swarm_accel_limit(v: Any) -> float:
    """U_s (m/s^2): ``swarm_accel_limit``, or ``SWARM_ACCEL_LIMIT`` (at most the vehicle's
    bound)."""
    if v.swarm_accel_limit is not None:
        return v.swarm_accel_limit
    bound = _bound(v)
    return SWARM_ACCEL_LIMIT if bound is None else min(SWARM_ACCEL_LIMIT, bound)


def swarm_brake_accel(v: Any) -> float:
    """alpha_s (m/s^2): ``swarm_brake_accel``, or ``BRAKE_SHARE x`` :func:`swarm_accel_limit`."""
    if v.swarm_brake_accel is not None:
        return v.swarm_brake_accel
    return BRAKE_SHARE * swarm_accel_limit(v)


def swarm_sensing_radius(v: Any) -> float:
    """The radius (m) within which two unpaired UAVs constrain each other: the field, or the
    paired UAVs' ``safety_sensing_radius`` (one radius for every row)."""
    if v.swarm_sensing_radius is None:
        return v.safety_sensing_radius
    return v.swarm_sensing_radius


def reaction_time(v: Any) -> float:
    """tau (s): ``safety_reaction_time``, or the vehicle's lag (0 for the particle), times
    ``SWARM_LAG_FACTOR`` under the swarm scope (at most ``MAX_REACTION_TIME``)."""
    if v.safety_reaction_time is not None:
        return v.safety_reaction_time
    rule = VEHICLES[v.dynamics].reaction_time
    if rule is None:
        return 0.0
    lag = rule(v)
    return min(SWARM_LAG_FACTOR * lag, MAX_REACTION_TIME) if v.safety_scope == "swarm" else lag


def decay(v: Any) -> float:
    """lambda: ``safety_decay``, or the vehicle's default, or DECAY."""
    if v.safety_decay is not None:
        return v.safety_decay
    d = VEHICLES[v.dynamics].safety_decay
    return DECAY if d is None else d


SAFETY = Section(
    "safety",
    "Safety filter",
    "A decentralised braking-distance CBF filter between the decoded pair command and the "
    "vehicle model (pairflock_env.safety, docs/safety.md): each paired UAV replaces its pair "
    "command u by the nearest one with ||u|| <= pair_accel_limit (a ball, not the action "
    'box) that keeps safety_distance from every UAV it senses; with safety_scope="swarm" '
    "every UAV filters its whole command (docs/swarm-safety.md). Off by default.",
    (
        Field(
            "safety_filter",
            Registered(FILTERS, none_means="none", after_sections=True),
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
            "safety_reaction_time",
            OrNone(
                Real(0.0, MAX_REACTION_TIME),
                "0; quadrotor: 1.5 / quad_attitude_freq, 1.5 times that under the swarm scope",
            ),
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
        Field(
            "safety_scope",
            Choice(SCOPES),
            "pairs",
            "",
            '"pairs": the filter changes the paired UAVs\' pair commands; "swarm": every UAV, '
            "paired or not, replaces its whole command (flocking + pair term) by the nearest "
            "one that keeps safety_distance from every UAV it senses, the responsibility for "
            "each pair shared by brake capacity, and the flocking repulsion gets its floor "
            '(docs/swarm-safety.md). Needs safety_filter="cbf".',
        ),
        Field(
            "swarm_accel_limit",
            OrNone(Real(0.0, MAX_GAIN, lo_open=True), "20; at most the vehicle's bound"),
            None,
            "m/s^2",
            "U_s: the bound on an unpaired UAV's whole command under the swarm scope (a ball); "
            "the layer's output always satisfies it. Paired UAVs keep ||a - f|| <= "
            "pair_accel_limit. The quadrotor's bound is min(quad_accel_limit, quad_gravity "
            "tan quad_tilt_limit).",
        ),
        Field(
            "swarm_brake_accel",
            OrNone(Real(0.0, MAX_GAIN, lo_open=True), "0.8 swarm_accel_limit"),
            None,
            "m/s^2",
            "alpha_s: the line-of-sight deceleration an unpaired UAV counts on when it must "
            "brake (swarm scope); at most swarm_accel_limit. Two UAVs split each constraint "
            "in proportion to their brake accelerations.",
        ),
        Field(
            "swarm_sensing_radius",
            OrNone(Real(1e-3, MAX_DISTANCE), "safety_sensing_radius"),
            None,
            "m",
            "Two unpaired UAVs constrain each other closer than this (swarm scope; rows with "
            "a paired UAV use safety_sensing_radius); above safety_distance + safety_margin. "
            "Two unpaired UAVs closing at V m/s must first be sensed roughly "
            "safety_distance + V^2 / (4 swarm_brake_accel) apart (docs/swarm-safety.md).",
        ),
        Field(
            "swarm_repulsion_floor",
            Flag(),
            True,
            "",
            "Swarm scope: below the distance rho* where the flocking repulsion peaks, it grows "
            "as F* rho* / rho instead of fading (a change to eqs. 13-16, docs/swarm-safety.md); "
            "without it a pressed flock jams against the barrier. No effect under pairs.",
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


def _scope_supported(v: Any) -> str | None:
    scopes = FILTERS[v.safety_filter].scopes
    if v.safety_scope not in scopes:
        able = [name for name in FILTERS if v.safety_scope in FILTERS[name].scopes]
        return (
            f"must be one that safety_filter={v.safety_filter!r} supports ({', '.join(scopes)}); "
            f"safety_scope={v.safety_scope!r} needs safety_filter in {able}"
        )
    return None


def _swarm_brake_within(v: Any) -> str | None:
    a, U = swarm_brake_accel(v), swarm_accel_limit(v)
    if not a <= U:
        return f"must be <= swarm_accel_limit ({U:g} m/s^2; None: 20, at most the vehicle's bound)"
    return None


def _swarm_radius_beyond(v: Any) -> str | None:
    r, D = swarm_sensing_radius(v), v.safety_distance + v.safety_margin
    if not r > D:
        return (
            f"must keep the swarm sensing radius ({r:g} m; None: safety_sensing_radius) above "
            f"safety_distance + safety_margin ({D:g} m)"
        )
    return None


def _sphere_holds_ellipsoid(v: Any) -> str | None:
    h = v.collision_height
    if v.safety_filter == "cbf" and h is not None and not v.safety_distance >= h:
        return (
            f"must keep safety_distance ({v.safety_distance:g} m) >= collision_height "
            f'({h:g} m) with safety_filter="cbf": the filter keeps a sphere of radius '
            "safety_distance, which holds the collision ellipsoid only when it is at least "
            "as tall (docs/crazyflie.md); unset collision_height for a smaller sphere"
        )
    return None


RULES = (
    Rule(
        ("safety_distance", "collision_height", "safety_filter"),
        _sphere_holds_ellipsoid,
        'safety_distance >= collision_height (when set) with safety_filter="cbf"',
    ),
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
        ("safety_scope", "safety_filter"),
        _scope_supported,
        "safety_scope is one the filter supports (swarm: cbf)",
    ),
    Rule(
        ("swarm_brake_accel", "swarm_accel_limit", "dynamics"),
        _swarm_brake_within,
        "swarm_brake_accel <= swarm_accel_limit (each default or set)",
    ),
    Rule(
        ("swarm_sensing_radius", "safety_sensing_radius", "safety_distance", "safety_margin"),
        _swarm_radius_beyond,
        "swarm_sensing_radius (default safety_sensing_radius) > safety_distance + safety_margin",
    ),
)
