"""Section ``crazyflie``: the airframe, firmware rates and setpoint feeding of
``dynamics="crazyflie"`` (docs/crazyflie.md), declared here and registered with the vehicle
(:mod:`pairflock_env.dynamics.crazyflie`). The fields are checked whatever the vehicle; the
rules that tie them to ``dt`` and ``substeps`` only hold with ``dynamics="crazyflie"``.
"""

from __future__ import annotations

import math
from typing import Any

from pairflock_env.config.fields import Choice, Field, OrNone, Real
from pairflock_env.config.limits import MAX_DISTANCE, MAX_POSITION, MAX_SPEED, MAX_SUBSTEPS
from pairflock_env.config.schema import Rule, Section
from pairflock_env.dynamics.crazyflie.data import (
    CRAZYFLIE_MODELS,
    FIRMWARE,
    FIRMWARE_RATE,
)
from pairflock_env.dynamics.crazyflie.params import hover_rpm

__all__ = [
    "CRAZYFLIE",
    "RULES",
    "accel_bound",
    "default_substeps",
    "hover_rotor_time_constant",
    "reaction_time",
    "ticks_per_period",
]

NAME = "crazyflie"

#: the filter counts on braking after this many rotor time constants (at hover, the slower of
#: spin-up and spin-down; the rotors, not the attitude loop, make a Crazyflie late): the
#: smallest multiple that covers the measured 63 % rise time of a 1-3 m/s^2 acceleration step
#: on all four sets (0.08-0.11 s; docs/crazyflie.md, "Safety filter")
REACTION_ROTOR_CONSTANTS = 1.4


def ticks_per_period(v: Any) -> float:
    """Firmware ticks (1/500 s) per control period: 500 dt (a whole number when valid)."""
    return v.dt * FIRMWARE_RATE


def default_substeps(v: Any) -> int:
    """One plant step per firmware tick (500 Hz, as crazyflow): round(500 dt), in
    [1, MAX_SUBSTEPS] (the rules below reject a dt that is no whole number of ticks)."""
    return max(1, min(round(ticks_per_period(v)), MAX_SUBSTEPS))


def hover_rotor_time_constant(model: str) -> float:
    """The slower of the rotors' spin-up and spin-down time constants (s) at the hover speed
    of the identified set ``model``: 1 / d(Omega')/d(Omega) of the rotor law at hover."""
    hover = hover_rpm(model)
    c1, c2, c3, c4 = CRAZYFLIE_MODELS[model]["rotor_dyn"]
    return max(1.0 / (c1 + 2.0 * c2 * hover), 1.0 / (c3 + 2.0 * c4 * hover))


def accel_bound(v: Any) -> float:
    """The horizontal acceleration (m/s^2) a hovering Crazyflie can realise: the smaller of
    ``crazyflie_accel_limit`` and g sqrt((4 f_max / m g)^2 - 1), its full-thrust bound."""
    a = CRAZYFLIE_MODELS[v.crazyflie_model]
    g = FIRMWARE["gravity"]
    ratio = 4.0 * a["thrust_max"] / (a["mass"] * g)
    return min(v.crazyflie_accel_limit, g * math.sqrt(max(ratio * ratio - 1.0, 0.0)))


def reaction_time(v: Any) -> float:
    """How late the Crazyflie realises a command (s): REACTION_ROTOR_CONSTANTS x the rotors'
    hover time constant (0.19 s for cf2x_L250)."""
    return REACTION_ROTOR_CONSTANTS * hover_rotor_time_constant(v.crazyflie_model)


def _whole(x: float) -> bool:
    return abs(x - round(x)) <= 1e-9 * max(1.0, abs(x))


def _dt_not_in_ticks(v: Any) -> str | None:
    if v.dynamics != NAME or _whole(ticks_per_period(v)):
        return None
    return (
        f"must be a whole number of firmware ticks (1/{FIRMWARE_RATE:g} s) with "
        f'dynamics="crazyflie", e.g. 0.02 (50 Hz, 10 ticks)'
    )


def _substeps_not_per_tick(v: Any) -> str | None:
    if v.dynamics != NAME:
        return None
    ticks = round(ticks_per_period(v))
    if v.substeps % ticks == 0:
        return None
    return (
        f'must be a multiple of the {ticks} firmware ticks per dt with dynamics="crazyflie" '
        f"(plant steps per tick: {ticks} = 500 Hz, {2 * ticks} = 1 kHz, ...)"
    )


def _rate_not_dividing(rate: float | None, v: Any) -> str | None:
    if v.dynamics != NAME or rate is None:
        return None
    k = FIRMWARE_RATE / rate
    ticks = round(ticks_per_period(v))
    if _whole(k) and ticks % round(k) == 0:
        return None
    return (
        f"must be {FIRMWARE_RATE:g} / k Hz with k a divisor of the {ticks} firmware ticks "
        f'per dt with dynamics="crazyflie" (e.g. 500, 250, 100)'
    )


CRAZYFLIE = Section(
    NAME,
    "Crazyflie",
    'Used with dynamics="crazyflie" (docs/crazyflie.md): a Crazyflie 2.x (identified first-'
    "principles model of drone-models) flown by the firmware's Mellinger controller, fed with "
    "cmdFullState setpoints; checked for every config. dt must then be a whole number of "
    "firmware ticks (1/500 s) and substeps a multiple of them (plant steps per tick).",
    (
        Field(
            "crazyflie_model",
            Choice(tuple(CRAZYFLIE_MODELS)),
            "cf2x_L250",
            "",
            'Identified parameter set (drone-models): "cf2x_L250" (Crazyflie 2.1, stock L250 '
            'propellers, 31.9 g), "cf2x_P250" (P250 propellers), "cf2x_T350" (thrust upgrade '
            'kit, 37.9 g), "cf21B_500" (Crazyflie 2.1 Brushless, 43.4 g).',
        ),
        Field(
            "crazyflie_position_rate",
            Real(0.0, FIRMWARE_RATE, lo_open=True),
            FIRMWARE_RATE,
            "Hz",
            "Rate of the Mellinger position loop: 500 (the firmware) or 500 / k with k dividing "
            "the ticks per dt (100: crazyflow's default).",
        ),
        Field(
            "crazyflie_setpoint_rate",
            OrNone(Real(0.0, FIRMWARE_RATE, lo_open=True), "one setpoint per control period"),
            None,
            "Hz",
            "Rate at which the ground station streams the reference as cmdFullState: 500 / k "
            "with k dividing the ticks per dt; the firmware holds each setpoint until the next.",
        ),
        Field(
            "crazyflie_reference",
            Choice(("integrated", "anchored")),
            "integrated",
            "",
            'How a_des becomes a setpoint: "integrated" (a reference particle that follows the '
            "limited a_des, on a leash around the UAV; the firmware corrects its errors) or "
            '"anchored" (the UAV\'s own position and velocity with a_des; drifts, see the docs).',
        ),
        Field(
            "crazyflie_leash",
            Real(0.0, MAX_DISTANCE, lo_open=True),
            0.1,
            "m",
            "The integrated reference position is pulled back to within this distance of the "
            "UAV at each period start (reported as accel_limited).",
        ),
        Field(
            "crazyflie_leash_velocity",
            Real(0.0, MAX_SPEED, lo_open=True),
            0.3,
            "m/s",
            "The integrated reference velocity is pulled back to within this of the UAV's.",
        ),
        Field(
            "crazyflie_accel_limit",
            Real(0.0, 100.0, lo_open=True),
            5.0,
            "m/s^2",
            "Largest norm of a_des sent as the setpoint's feed-forward acceleration; larger "
            "commands are scaled down (accel_limited). Above about 3 m/s^2, commands that "
            "switch quickly flip a cf2x (rotor lag 0.14 s; docs/crazyflie.md).",
        ),
        Field("crazyflie_yaw", Real(-180.0, 180.0), 0.0, "deg", "Fixed yaw setpoint psi."),
        Field(
            "crazyflie_crash_tilt",
            Real(0.0, 180.0, lo_open=True),
            90.0,
            "deg",
            "A Crazyflie tilted beyond this has flipped: it crashes (episode ends); 180 "
            "disables the check.",
        ),
        Field(
            "crazyflie_ground_altitude",
            OrNone(Real(-MAX_POSITION, MAX_POSITION), "no ground"),
            None,
            "m",
            "A Crazyflie below this altitude z has hit the ground and crashes.",
        ),
    ),
)

RULES = (
    Rule(("dt", "dynamics"), _dt_not_in_ticks, 'dynamics="crazyflie": 500 dt is a whole number'),
    Rule(
        ("substeps", "dt", "dynamics"),
        _substeps_not_per_tick,
        'dynamics="crazyflie": substeps is a multiple of 500 dt',
    ),
    Rule(
        ("crazyflie_position_rate", "dt", "dynamics"),
        lambda v: _rate_not_dividing(v.crazyflie_position_rate, v),
        'dynamics="crazyflie": 500 / crazyflie_position_rate divides 500 dt',
    ),
    Rule(
        ("crazyflie_setpoint_rate", "dt", "dynamics"),
        lambda v: _rate_not_dividing(v.crazyflie_setpoint_rate, v),
        'dynamics="crazyflie": 500 / crazyflie_setpoint_rate divides 500 dt',
    ),
)
