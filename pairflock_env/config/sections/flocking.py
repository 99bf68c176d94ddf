"""Section ``flocking``: the protocol of eqs. 11-19 (attraction/repulsion, consensus, pinning)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pairflock_env.config.fields import Field, Kind, Real, invalid, sequence_items
from pairflock_env.config.limits import MAX_DISTANCE, MAX_GAIN
from pairflock_env.config.schema import Derived, Rule, Section

__all__ = ["DERIVED", "RULES", "SECTIONS", "repulsion_floor", "repulsion_peak", "repulsion_sigma2"]


class Pinning(Kind):
    """``"all"``, a count k in [0, n_uavs], or distinct UAV indices (stored sorted)."""

    annotation = Any
    type_name = "str, int or tuple"

    @property
    def needs(self) -> tuple[str, ...]:
        return ("n_uavs",)

    def valid(self) -> str:
        return '"all", an integer k in [0, n_uavs] or a sequence of distinct UAV indices'

    def check(self, name: str, value: Any, ctx: Any) -> Any:
        n = ctx["n_uavs"]
        if isinstance(value, str):
            if value != "all":
                raise invalid(name, value, f"must be {self.valid()}")
            return "all"
        if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
            if not 0 <= value <= n:
                raise invalid(name, value, f"must be an integer in [0, {n}] (n_uavs={n})")
            return int(value)
        items = sequence_items(value)
        if items is None:
            raise invalid(name, value, f"must be {self.valid()}", TypeError)
        idx = []
        for x in items:
            if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer)):
                raise invalid(name, value, f"indices must be integers in [0, {n - 1}]", TypeError)
            if not 0 <= x < n:
                raise invalid(name, value, f"indices must be integers in [0, {n - 1}]")
            idx.append(int(x))
        if len(set(idx)) != len(idx):
            raise invalid(name, value, "indices must be distinct")
        return tuple(sorted(idx))


def repulsion_sigma2(v: Any) -> float:
    """sigma^2 of the repulsion, chosen so that g_r(spacing) = attraction (m^2)."""
    return v.spacing**2 / math.log(v.repulsion / v.attraction)


def repulsion_peak(v: Any) -> float:
    """rho* (m): the distance in (0, spacing) at which the repulsion between two UAVs,
    F(rho) = rho (b_r exp(-rho^2 / sigma^2) - a), is strongest; closer than rho* it weakens
    as they approach. x = rho*^2 / sigma^2 solves b_r e^-x (1 - 2 x) = a on (0, 1/2), where
    the left side falls (bisection to the last bit)."""
    a, br, s2 = v.attraction, v.repulsion, repulsion_sigma2(v)
    lo, hi = 0.0, 0.5
    while True:
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            return math.sqrt(lo * s2)
        if br * math.exp(-mid) * (1.0 - 2.0 * mid) > a:
            lo = mid
        else:
            hi = mid


def repulsion_floor(v: Any) -> tuple[float, float]:
    """(rho*^2, F* rho*) of the swarm layer's repulsion floor (docs/swarm-safety.md), with
    F* = F(rho*): closer than rho* the repulsion is held at F* rho* / rho instead of
    fading; (0, 0) when the floor is off (``safety_scope`` "pairs" or
    ``swarm_repulsion_floor`` False): the paper's law."""
    if v.safety_scope != "swarm" or not v.swarm_repulsion_floor:
        return 0.0, 0.0
    rho = repulsion_peak(v)
    F = rho * (v.repulsion * math.exp(-rho * rho / repulsion_sigma2(v)) - v.attraction)
    return rho * rho, F * rho


_GAIN = Real(0.0, MAX_GAIN)

FLOCKING = Section(
    "flocking",
    "Flocking protocol (eqs. 11-19)",
    "Attraction and bounded repulsion within the perception radius, velocity consensus, "
    "pinning to the virtual leader.",
    (
        Field(
            "spacing",
            Real(1e-3, MAX_DISTANCE),
            7.0,
            "m",
            "Desired inter-UAV distance d of eq. 4; attraction and repulsion balance here.",
        ),
        Field(
            "radius",
            Real(1e-3, MAX_DISTANCE),
            8.4,
            "m",
            "Perception radius r of eq. 2: UAVs farther apart than r do not interact.",
        ),
        Field(
            "attraction",
            Real(1e-6, MAX_GAIN),
            1.0,
            "1/s^2",
            "Slope a of the linear attraction g_a.",
        ),
        Field(
            "repulsion",
            Real(1e-6, MAX_GAIN),
            10.0,
            "1/s^2",
            "Peak b_r of the bounded repulsion g_r(rho) = b_r exp(-rho^2/sigma^2); sigma is set "
            "by g_r(spacing) = attraction, so repulsion must exceed attraction.",
        ),
        Field("consensus", _GAIN, 1.0, "1/s", "Velocity-consensus weight b of eq. 18."),
        Field(
            "pinning",
            Pinning(),
            "all",
            "",
            'Pinned UAVs h_i of eq. 6: "all", an int k (the k UAVs nearest to the leader at '
            "reset) or a tuple of UAV indices.",
        ),
        Field("pin_position_gain", _GAIN, 0.1, "1/s^2", "c1 of eq. 19."),
        Field("pin_velocity_gain", _GAIN, 0.632, "1/s", "c2 of eq. 19."),
    ),
)

SECTIONS = (FLOCKING,)

RULES = (
    Rule(
        ("radius", "spacing"),
        lambda v: "must exceed spacing (eq. 4: d < r)" if v.radius <= v.spacing else None,
        "radius > spacing (eq. 4: d < r)",
    ),
    Rule(
        ("repulsion", "attraction"),
        lambda v: (
            "must exceed attraction so that g_r(spacing) = attraction"
            if v.repulsion <= v.attraction
            else None
        ),
        "repulsion > attraction (g_r(spacing) = attraction defines sigma)",
    ),
)

DERIVED = (
    Derived(
        "sigma^2",
        ("spacing", "attraction", "repulsion"),
        repulsion_sigma2,
        1e-30,
        1e30,
        "m^2",
        "spacing^2 / ln(repulsion / attraction)",
    ),
    Derived(
        "1/sigma^2",
        ("spacing", "attraction", "repulsion"),
        lambda v: 1.0 / repulsion_sigma2(v),
        1e-30,
        1e30,
        "1/m^2",
        "the exponent scale of the repulsion in the flocking pass",
    ),
    Derived(
        "rho*",
        ("spacing", "attraction", "repulsion"),
        repulsion_peak,
        0.0,
        MAX_DISTANCE,
        "m",
        "where the repulsion rho (b_r exp(-rho^2/sigma^2) - a) peaks; below it the swarm "
        "scope's repulsion floor holds it at F(rho*) rho*/rho (docs/swarm-safety.md)",
    ),
    Derived(
        "r^2",
        ("radius",),
        lambda v: v.radius**2,
        1e-6,
        MAX_DISTANCE**2,
        "m^2",
        "squared perception radius of the flocking and neighbour passes",
    ),
)
