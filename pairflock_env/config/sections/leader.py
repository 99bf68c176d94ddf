"""Section ``leader``: the virtual leader's trajectory (q_gamma, p_gamma of eq. 19)."""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.config.fields import (
    Field,
    Kind,
    OrNone,
    Real,
    Vector,
    invalid,
    sequence_items,
)
from pairflock_env.config.limits import MAX_POSITION, MAX_SPEED, MAX_TIME, MAX_TURNS
from pairflock_env.config.registry import LEADERS, Registered
from pairflock_env.config.schema import Rule, Section

__all__ = ["RULES", "SECTIONS"]

_START = Real(0.0, MAX_TIME)
_DURATION = Real(1e-3, MAX_TIME)
_ANGLE = Real(-720.0, 720.0)


class Turns(Kind):
    """Heading turns ((start s, duration s, angle deg), ...), in time order, not overlapping."""

    annotation = tuple
    type_name = "tuple of triples"

    def valid(self) -> str:
        return (
            f"up to {MAX_TURNS} (start, duration, angle) triples in time order without overlap, "
            f"start in {_START.interval()} s, duration in {_DURATION.interval()} s, "
            f"angle in {_ANGLE.interval()} deg"
        )

    def check(self, name: str, value: Any, ctx: Any = None) -> tuple[tuple[float, ...], ...]:
        turns = sequence_items(value)
        if turns is None:
            raise invalid(
                name,
                value,
                "must be a sequence of (start s, duration s, angle deg) triples",
                TypeError,
            )
        if len(turns) > MAX_TURNS:
            raise invalid(name, value, f"must hold at most {MAX_TURNS} turns")
        norm: list[tuple[float, float, float]] = []
        for k, tr in enumerate(turns):
            items = sequence_items(tr)
            if items is None or len(items) != 3:
                raise invalid(name, value, "each turn must be (start s, duration s, angle deg)")
            start = _START.check(f"{name}[{k}] start", items[0])
            dur = _DURATION.check(f"{name}[{k}] duration", items[1])
            ang = _ANGLE.check(f"{name}[{k}] angle", items[2])
            if norm and start < norm[-1][0] + norm[-1][1]:
                raise invalid(name, value, "turns must be in time order and must not overlap")
            norm.append((start, dur, ang))
        return tuple(norm)


def _heading_needed(v: Any) -> str | None:
    if v.leader == "climb_and_turn" and v.leader_turns and np.hypot(*v.leader_velocity[:2]) == 0:
        return "must have a non-zero horizontal part to define a heading for leader_turns"
    return None


LEADER = Section(
    "leader",
    "Virtual leader",
    "The trajectory the pinned UAVs follow.",
    (
        Field(
            "leader",
            Registered(LEADERS, after_sections=True),
            "constant_velocity",
            "",
            'Leader trajectory: "constant_velocity" or "climb_and_turn" (Sec. VI-B: climb, level '
            "off, smooth heading turns; see pairflock_env.swarm.leader.ClimbAndTurnLeader).",
        ),
        Field(
            "leader_position",
            Vector(Real(-MAX_POSITION, MAX_POSITION)),
            25.0,
            "m",
            "Leader position at t = 0.",
        ),
        Field(
            "leader_velocity",
            Vector(Real(-MAX_SPEED, MAX_SPEED)),
            0.5,
            "m/s",
            'Leader velocity at t = 0. "climb_and_turn": its horizontal part sets the ground '
            "speed and initial heading, its vertical part (3-D) the climb rate.",
        ),
        Field(
            "leader_climb_time",
            OrNone(Real(0.0, MAX_TIME), "the climb lasts forever"),
            None,
            "s",
            '"climb_and_turn": the climb (vertical velocity) lasts this long.',
        ),
        Field(
            "leader_level_time",
            Real(0.0, MAX_TIME),
            0.0,
            "s",
            '"climb_and_turn": after the climb, the vertical velocity fades to 0 over this '
            "time along a half-cosine (0 = levels off at once).",
        ),
        Field(
            "leader_turns",
            Turns(),
            (),
            "s, s, deg",
            '"climb_and_turn": heading turns ((start, duration, angle), ...); positive angles '
            "turn left (counter-clockwise seen from above). In a turn the heading follows "
            "psi0 + angle (1 - cos(pi (t - start) / duration)) / 2.",
        ),
    ),
)

SECTIONS = (LEADER,)

RULES = (
    Rule(
        ("leader_velocity", "leader", "leader_turns"),
        _heading_needed,
        '"climb_and_turn" with turns needs a horizontal leader velocity (the heading)',
    ),
)
