"""Section ``timing``: how fast the clock ticks and how long an episode lasts."""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import Auto, Choice, Field, Int, OrNone, Real
from pairflock_env.config.limits import MAX_EPISODE_STEPS, MAX_SUBSTEPS, MAX_TIME
from pairflock_env.config.registry import VEHICLES
from pairflock_env.config.schema import Derived, Section

__all__ = ["DERIVED", "SECTIONS", "episode_steps", "physics_dt"]


def episode_steps(v: Any) -> int:
    """Control steps per episode: ``max_cycles``, or ``round(horizon / dt)`` (at least 1)."""
    if v.max_cycles is not None:
        return int(v.max_cycles)
    return max(1, round(v.horizon / v.dt))


def physics_dt(v: Any) -> float:
    """Physics step dt / substeps (s)."""
    return v.dt / v.substeps


def _default_substeps(v: Any) -> int:
    rule = VEHICLES[v.dynamics].substeps
    return 1 if rule is None else rule(v)


TIMING = Section(
    "timing",
    "Timing",
    "Control period, physics substeps and episode length.",
    (
        Field(
            "dt",
            Real(1e-6, 1.0),
            0.01,
            "s",
            "Control period: the protocol and the pair action are held over it (zero-order hold).",
        ),
        Field(
            "substeps",
            Int(1, MAX_SUBSTEPS),
            1,
            "steps",
            "Physics substeps per control period (physics step = dt / substeps).",
            auto=Auto(
                _default_substeps,
                ("dynamics", "dt"),
                '1; with dynamics="quadrotor" the fewest that resolve the attitude loop (a '
                "vehicle model may give its own default)",
            ),
        ),
        Field(
            "integrator",
            Choice(("semi_implicit", "exact")),
            "semi_implicit",
            "",
            'Particle integrator: "semi_implicit" (symplectic Euler, the paper\'s) or "exact" '
            "(exact solution of the double integrator under a held acceleration).",
        ),
        Field(
            "horizon",
            Real(0.0, MAX_TIME, lo_open=True),
            50.0,
            "s",
            "Episode length (truncation); ignored when max_cycles is set.",
        ),
        Field(
            "max_cycles",
            OrNone(Int(1, MAX_EPISODE_STEPS), "use horizon"),
            None,
            "steps",
            "Episode length in control steps; overrides horizon when given.",
        ),
    ),
)

SECTIONS = (TIMING,)

DERIVED = (
    Derived(
        "episode_steps",
        ("horizon", "dt", "max_cycles"),
        episode_steps,
        1,
        MAX_EPISODE_STEPS,
        "steps",
        "max_cycles or round(horizon / dt)",
    ),
    Derived(
        "episode end time",
        ("horizon", "dt", "max_cycles"),
        lambda v: episode_steps(v) * v.dt,
        0.0,
        MAX_TIME,
        "s",
        "episode_steps x dt, the sim time at truncation",
    ),
    Derived(
        "physics_dt",
        ("substeps", "dt"),
        physics_dt,
        1e-10,
        1.0,
        "s",
        "dt / substeps",
    ),
)
