"""Section ``quadrotor``: the airframe, rotors and attitude loop of ``dynamics="quadrotor"``
(docs/quadrotor.md). The fields are checked whatever the vehicle, used by the quadrotor only.

Airframe: the paper's mass and inertia (Sec. VI-B); the rest from an F450-class frame as
identified by T. Luukkonen, "Modelling and control of quadcopter", Aalto University (2011),
Table 1 (m = 0.468 kg, close to the paper's 0.455 kg).
"""

from __future__ import annotations

import math
from typing import Any

from pairflock_env.config.fields import Choice, Field, OrNone, Real, Vector
from pairflock_env.config.limits import MAX_POSITION, MAX_REACTION_TIME, MAX_SUBSTEPS
from pairflock_env.config.schema import Derived, Rule, Section
from pairflock_env.config.sections.timing import physics_dt

__all__ = [
    "DERIVED",
    "QUADROTOR",
    "RULES",
    "SECTIONS",
    "accel_bound",
    "attitude_rate",
    "min_substeps",
    "reaction_time",
]

_FREQ = Real(1e-2, 1e4)

#: the safety filter counts on braking only after this many attitude-loop time constants
#: (1 / quad_attitude_freq): 0.1 s at the default 15 rad/s, the only frequency it was
#: measured at (docs/safety-results.md "Quadrotors")
REACTION_CYCLES = 1.5


def attitude_rate(v: Any) -> float:
    """Fastest rate of the quadrotor attitude loop (rad/s): the explicit integration needs a
    physics step of at most 0.1 / rate."""
    return max(v.quad_attitude_freq, v.quad_yaw_freq) * max(1.0, 2 * v.quad_attitude_damping)


def min_substeps(v: Any) -> int:
    """Fewest substeps that resolve the quadrotor attitude loop at ``dt`` (capped at the
    substeps limit; the rule then says what to change)."""
    need = math.ceil(v.dt / (0.1 / attitude_rate(v)) - 1e-9)
    return max(1, min(need, MAX_SUBSTEPS))


def accel_bound(v: Any) -> float:
    """The horizontal acceleration (m/s^2) a hovering quadrotor can realise:
    min(``quad_accel_limit``, ``quad_gravity`` tan ``quad_tilt_limit``), the smaller of its
    command bound and its tilt cone (6 m/s^2 in the paper-quadrotor preset)."""
    tilt = math.radians(v.quad_tilt_limit)
    return min(v.quad_accel_limit, v.quad_gravity * math.tan(tilt))


def reaction_time(v: Any) -> float:
    """How late the quadrotor realises a command (s): REACTION_CYCLES / quad_attitude_freq."""
    return REACTION_CYCLES / v.quad_attitude_freq


def _hover_out_of_range(v: Any) -> str | None:
    hover = v.quad_mass * v.quad_gravity / 4.0
    if v.quad_motor_thrust_min < hover < v.quad_motor_thrust_max:
        return None
    return (
        f"the hover thrust per rotor quad_mass quad_gravity / 4 = {hover:.4g} N must lie "
        "strictly between quad_motor_thrust_min and quad_motor_thrust_max"
    )


def _crash_below_tilt(v: Any) -> str | None:
    if v.quad_tilt_limit < v.quad_crash_tilt:
        return None
    return "must be in (quad_tilt_limit, 180] degrees"


def _attitude_unresolved(v: Any) -> str | None:
    """Explicit integration of the attitude loop needs h * (fastest rate) <= 0.1."""
    if v.dynamics != "quadrotor":
        return None
    rate = attitude_rate(v)
    h_max = 0.1 / rate
    if physics_dt(v) <= h_max * (1 + 1e-9):
        return None
    need = math.ceil(v.dt / h_max - 1e-9)
    fix = (
        f"use substeps >= {need} with dt={v.dt}"
        if need <= MAX_SUBSTEPS
        else f"that needs substeps >= {need}, above the limit {MAX_SUBSTEPS:_}: lower dt or "
        "the attitude frequencies"
    )
    return (
        f"the physics step dt / substeps = {physics_dt(v):.4g} s is too coarse for the "
        f"quadrotor attitude loop, which must have a step <= {h_max:.4g} s = 0.1 / "
        f"{rate:g} rad/s; {fix}"
    )


def _reaction_time_too_long(v: Any) -> str | None:
    """The filter's unset reaction time is this vehicle's lag, which must fit its field."""
    if v.dynamics != "quadrotor" or v.safety_filter == "none" or v.safety_reaction_time is not None:
        return None
    tau = reaction_time(v)
    if tau <= MAX_REACTION_TIME:
        return None
    return (
        f"makes the unset safety_reaction_time {REACTION_CYCLES:g} / quad_attitude_freq = "
        f"{tau:g} s, above the {MAX_REACTION_TIME:g} s it may be; set safety_reaction_time"
    )


QUADROTOR = Section(
    "quadrotor",
    "Quadrotor",
    'Used with dynamics="quadrotor" (docs/quadrotor.md); checked for every config.',
    (
        Field("quad_mass", Real(1e-3, 1e4), 0.455, "kg", "Mass m. Source: the paper, Sec. VI-B."),
        Field(
            "quad_inertia",
            Vector(Real(1e-9, 1e4), length=3),
            (0.43e-2, 0.43e-2, 1.02e-2),
            "kg m^2",
            "Principal moments of inertia (Jxx, Jyy, Jzz), body axes. Source: the paper, "
            "Sec. VI-B. (Jzz > Jxx + Jyy, which no rigid body has exactly; used as given.)",
        ),
        Field(
            "quad_arm_length",
            Real(1e-3, 100.0),
            0.225,
            "m",
            "Distance from the centre of mass to each rotor axis, L. Source: Luukkonen (2011).",
        ),
        Field(
            "quad_thrust_coeff",
            Real(1e-12, 1.0),
            2.98e-6,
            "N s^2/rad^2",
            "Rotor thrust coefficient k_f, T = k_f W^2. Source: Luukkonen (2011).",
        ),
        Field(
            "quad_torque_coeff",
            Real(1e-14, 1.0),
            1.14e-7,
            "N m s^2/rad^2",
            "Rotor drag-torque coefficient k_m, reaction torque k_m W^2. Source: Luukkonen (2011).",
        ),
        Field(
            "quad_motor_thrust_min",
            Real(0.0, 1e6),
            0.05,
            "N",
            "Smallest thrust of one rotor: motors idle, they do not stop or reverse (rotor "
            "speed sqrt(0.05 / k_f) = 130 rad/s). Assumed idle level.",
        ),
        Field(
            "quad_motor_thrust_max",
            Real(0.0, 1e6, lo_open=True),
            2.79,
            "N",
            "Largest thrust of one rotor: 4 x 2.79 N = 2.5 x the weight of 0.455 kg, a common "
            "thrust-to-weight margin for small multirotors (968 rad/s). Assumed.",
        ),
        Field(
            "quad_mixer",
            Choice(("desaturate", "clip")),
            "desaturate",
            "",
            'When a rotor would leave its thrust range: "desaturate" (keep the direction of the '
            'body moments, give up collective thrust first, as flight stacks do) or "clip" '
            "(clip each rotor on its own, which distorts the moments).",
        ),
        Field(
            "quad_motor_time_constant",
            Real(0.0, 1e9),
            0.03,
            "s",
            "Time constant tau of the first-order rotor-speed response; 0 = instantaneous. "
            "Assumed, in the range identified for brushless motors of this size (e.g. "
            "Eschmann et al. 2024, arXiv:2404.07837).",
        ),
        Field(
            "quad_drag",
            Real(0.0, 1e4),
            0.0,
            "kg/s",
            "Linear translational drag k_d, force -k_d p; the controller compensates it. 0 "
            "(the paper's rigid body); Luukkonen (2011) identifies 0.25.",
        ),
        Field("quad_gravity", Real(0.1, 100.0), 9.81, "m/s^2", "Gravitational acceleration g."),
        Field(
            "quad_attitude_freq",
            _FREQ,
            15.0,
            "rad/s",
            "Roll/pitch natural frequency wn of the attitude loop: K_R = J wn^2.",
        ),
        Field(
            "quad_attitude_damping",
            Real(1e-2, 100.0),
            0.9,
            "1",
            "Damping ratio zeta of the attitude loop (all axes): K_w = 2 zeta J wn.",
        ),
        Field("quad_yaw_freq", _FREQ, 5.0, "rad/s", "Yaw natural frequency of the attitude loop."),
        Field(
            "quad_accel_limit",
            Real(1e-3, 1e4),
            6.0,
            "m/s^2",
            "Largest norm of the desired acceleration the vehicle accepts; larger commands are "
            "scaled down (reported as accel_limited).",
        ),
        Field(
            "quad_tilt_limit",
            Real(0.0, 90.0, lo_open=True, hi_open=True),
            35.0,
            "deg",
            "Tilt cone: the desired thrust direction stays within this angle of vertical "
            "(horizontal command scaled down, reported as accel_limited).",
        ),
        Field("quad_yaw", Real(-360.0, 360.0), 0.0, "deg", "Fixed heading psi of every quadrotor."),
        Field(
            "quad_crash_tilt",
            Real(0.0, 180.0, lo_open=True),
            90.0,
            "deg",
            "A UAV tilted beyond this has flipped: it crashes (episode ends). In "
            "(quad_tilt_limit, 180]; 180 disables the check.",
        ),
        Field(
            "quad_ground_altitude",
            OrNone(Real(-MAX_POSITION, MAX_POSITION), "no ground"),
            None,
            "m",
            "A UAV below this altitude z has hit the ground and crashes.",
        ),
    ),
)

SECTIONS = (QUADROTOR,)

RULES = (
    Rule(
        ("quad_mass", "quad_gravity", "quad_motor_thrust_max", "quad_motor_thrust_min"),
        _hover_out_of_range,
        "quad_motor_thrust_min < quad_mass quad_gravity / 4 < quad_motor_thrust_max",
    ),
    Rule(
        ("quad_crash_tilt", "quad_tilt_limit"),
        _crash_below_tilt,
        "quad_tilt_limit < quad_crash_tilt",
    ),
    Rule(
        (
            "substeps",
            "dt",
            "dynamics",
            "quad_attitude_freq",
            "quad_yaw_freq",
            "quad_attitude_damping",
        ),
        _attitude_unresolved,
        'dynamics="quadrotor": dt / substeps <= 0.1 / (max(wn, wn_yaw) max(1, 2 zeta))',
    ),
    Rule(
        ("quad_attitude_freq", "safety_reaction_time", "safety_filter", "dynamics"),
        _reaction_time_too_long,
        "the quadrotor's derived safety_reaction_time (1.5 / quad_attitude_freq) <= 10 s",
    ),
)

DERIVED = (
    Derived(
        "kappa",
        ("quad_torque_coeff", "quad_thrust_coeff"),
        lambda v: v.quad_torque_coeff / v.quad_thrust_coeff,
        1e-12,
        1e12,
        "m",
        "k_m / k_f, the yaw-moment arm of the mixer",
    ),
    Derived(
        "hover rotor speed",
        ("quad_mass", "quad_gravity", "quad_thrust_coeff"),
        lambda v: math.sqrt(v.quad_mass * v.quad_gravity / 4.0 / v.quad_thrust_coeff),
        0.0,
        1e12,
        "rad/s",
        "sqrt(m g / 4 / k_f)",
    ),
)
