"""Section ``robustness``: the imperfections the paper's proofs assume away (noise, delay,
disturbance), and the memory the delay costs."""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import Field, Int, Real
from pairflock_env.config.limits import MAX_DELAY_BYTES, MAX_GAIN, MAX_PARTNER_DELAY
from pairflock_env.config.schema import Derived, Section

__all__ = ["DERIVED", "SECTIONS", "delay_buffer_bytes"]


def delay_buffer_bytes(v: Any) -> int:
    """Bytes of the partner-delay ring buffer of one swarm: (q, p, flocking command) of every
    agent over partner_delay + 1 steps."""
    if v.partner_delay == 0:
        return 0
    return 3 * (v.partner_delay + 1) * 2 * len(v.pairs) * v.dim * 8


_NOISE = Real(0.0, MAX_GAIN)

ROBUSTNESS = Section(
    "robustness",
    "Robustness",
    "Noise, delay and disturbances (all off in the paper).",
    (
        Field(
            "obs_noise_position",
            _NOISE,
            0.0,
            "m",
            "Std of white Gaussian noise on the observed partner offset y, per axis and step.",
        ),
        Field(
            "obs_noise_velocity",
            _NOISE,
            0.0,
            "m/s",
            "Std of white Gaussian noise on the observed relative velocity y'.",
        ),
        Field(
            "partner_delay",
            Int(0, MAX_PARTNER_DELAY),
            0,
            "steps",
            "Communication delay of the partner's state (position, velocity, flocking "
            "command) as each agent sees it.",
        ),
        Field(
            "disturbance_std",
            _NOISE,
            0.0,
            "m/s^2",
            "Std of a random acceleration added to every UAV's command, per axis, drawn each "
            "control period and held over it.",
        ),
    ),
)

SECTIONS = (ROBUSTNESS,)

DERIVED = (
    Derived(
        "partner-delay buffer",
        ("partner_delay", "pairs", "dim"),
        delay_buffer_bytes,
        0,
        MAX_DELAY_BYTES,
        "bytes per swarm",
        "3 (partner_delay + 1) x 2 len(pairs) x dim x 8",
    ),
)
