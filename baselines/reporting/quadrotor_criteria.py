"""The Sec. VI-B criteria of the quadrotor experiment and the check that applies them.

Re-exported by :mod:`baselines.reporting.criteria` (the home of every threshold); they live
here so that the check can serve any pair controller, not only sliding mode:
``check_quadrotor(rows, policies=("smc", "sb3:pair_quad3d"))`` gives the same criteria for
each, every line prefixed with the controller's name.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["QUADROTOR", "QuadrotorCriteria", "check_quadrotor"]


@dataclasses.dataclass(frozen=True)
class QuadrotorCriteria:
    """Sec. VI-B, a pair controller on the quadrotor, every seed (times in s, distances in m);
    the paper states them for sliding mode."""

    band: float = 0.5  # |pair error| band
    band_entry_by: float = 10.0  # first in the band by this time
    straight_max: float = 0.5  # max |error| in straight flight
    turn_peak_max: float = 0.6  # peak |error| in and after the turns
    min_distance: float = 0.5  # no two UAVs closer than this
    velocity_tolerance: float = 0.6  # m/s: unpaired UAVs' speed error to the leader
    attitude_cost: float = 0.35  # quadrotor minus particle straight-flight max error


QUADROTOR = QuadrotorCriteria()


def _range_s(v: np.ndarray) -> str:
    return f"{np.nanmin(v):.2f}-{np.nanmax(v):.2f} s" if np.isfinite(v).any() else "never"


def _misses(ok: np.ndarray) -> str:
    """How many runs miss a criterion: the criteria hold on every seed, so one run decides a
    set, and the count tells a rare tail from a general shortfall."""
    return f"{int(np.size(ok) - np.count_nonzero(ok))}/{np.size(ok)} runs miss"


def _runs(rows: Sequence[Mapping[str, Any]], dynamics: str, policy: str) -> list:
    sel = (r for r in rows if r["dynamics"] == dynamics and r["policy"] == policy)
    return sorted(sel, key=lambda r: r["seed"])


def _policy_checks(rows, name: str, c: QuadrotorCriteria) -> list[tuple[str, bool, str]]:
    """The criteria for controller ``name`` (its quadrotor rows, and its particle rows for the
    cost of the attitude loop)."""
    quad = _runs(rows, "quadrotor", name)
    if not quad:
        return []

    def arr(key: str) -> np.ndarray:
        return np.array([float(r[key]) for r in quad])

    entry, s, tp = arr("band_entry_time"), arr("straight_max_error"), arr("turn_peak_error")
    md, vm, crashed = arr("min_distance"), arr("velocity_mismatch"), arr("crashed")
    full_runs = arr("steps_run") == float(quad[0]["steps_run"])
    full_length = bool(np.all(full_runs))
    out = [
        (
            f"{name}: first in the {c.band} m band within {c.band_entry_by:g} s",
            bool(np.all(entry <= c.band_entry_by)),
            f"{_range_s(entry)}; {_misses(entry <= c.band_entry_by)}",
        ),
        (
            f"{name}: max abs pair error <= {c.straight_max} m in [15,20], [27,50], [57,65] s",
            bool(np.all(s <= c.straight_max)),
            f"max {np.max(s):.3f} m; {_misses(s <= c.straight_max)}",
        ),
        (
            f"{name}: peak abs pair error in the turns <= {c.turn_peak_max} m",
            bool(np.all(tp <= c.turn_peak_max)),
            f"max {np.max(tp):.3f} m; {_misses(tp <= c.turn_peak_max)}",
        ),
        (
            f"{name}: no two UAVs closer than {c.min_distance} m",
            bool(np.all(md >= c.min_distance)),
            f"min {np.min(md):.2f} m; {_misses(md >= c.min_distance)}",
        ),
        (
            f"{name}: unpaired velocity within {c.velocity_tolerance} m/s of the leader "
            "in [35,50], [60,65] s",
            bool(np.all(vm <= c.velocity_tolerance)),
            f"max {np.max(vm):.3f} m/s; {_misses(vm <= c.velocity_tolerance)}",
        ),
        (
            f"{name}: no crash, every episode runs 65 s",
            bool(np.all(crashed == 0) and full_length),
            f"{int(crashed.sum())} crashes; {_misses((crashed == 0) & full_runs)}",
        ),
    ]
    return out + _attitude_cost(rows, name, quad, s, c)


def _attitude_cost(rows, name: str, quad: list, s: np.ndarray, c: QuadrotorCriteria) -> list:
    """Quadrotor minus particle straight-flight max error, same seeds (none without them)."""
    part = {r["seed"]: r for r in _runs(rows, "particle", name)}
    if not part or not all(r["seed"] in part for r in quad):
        return []
    cost = s - np.array([float(part[r["seed"]]["straight_max_error"]) for r in quad])
    return [
        (
            f"{name}: attitude loop costs <= {c.attitude_cost} m over the particle "
            "(straight-flight max error, same seed)",
            bool(np.all(cost <= c.attitude_cost)),
            f"{np.min(cost):+.3f} to {np.max(cost):+.3f} m; {_misses(cost <= c.attitude_cost)}",
        )
    ]


def check_quadrotor(
    rows: Sequence[Mapping[str, Any]],
    criteria: QuadrotorCriteria = QUADROTOR,
    policies: Sequence[str] = ("smc",),
) -> list[tuple[str, bool, str]]:
    """The Sec. VI-B criteria, every seed, for each controller in ``policies`` that has
    quadrotor rows (in that order; by default sliding mode only, as in the paper); the rows
    are those of :func:`baselines.experiments.quadrotor_runs.run_job` (both vehicle models).

    Raises ``TypeError`` if ``policies`` is a string rather than a sequence of names.
    """
    if isinstance(policies, str):
        raise TypeError(f"policies={policies!r} is invalid: give a sequence of names")
    return [chk for name in dict.fromkeys(policies) for chk in _policy_checks(rows, name, criteria)]
