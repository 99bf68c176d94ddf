"""The Sec. VI-B criteria of the quadrotor experiment and the check that applies them.

The check serves any pair controller, not only sliding mode:
``check_quadrotor(rows, policies=("smc", "sb3:pair_quad3d"))`` gives the same criteria for
each, every line prefixed with the controller's name.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["CRITERIA_KEYS", "QUADROTOR", "QuadrotorCriteria", "check_quadrotor", "run_outcomes"]


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
    return sorted(sel, key=lambda r: int(float(r["seed"])))  # seeds may be CSV text


#: the criteria per run, in the order of :func:`check_quadrotor`'s lines, and the metric of
#: ``results.csv`` each one bounds
CRITERIA_KEYS = {
    "band_entry": "band_entry_time",
    "straight_max": "straight_max_error",
    "turn_peak": "turn_peak_error",
    "separation": "min_distance",
    "unpaired_velocity": "velocity_mismatch",
    "no_crash": "crashed",
    "attitude_cost": "straight_max_error",  # minus the particle's, same seed
}


def run_outcomes(
    rows: Sequence[Mapping[str, Any]], name: str, criteria: QuadrotorCriteria = QUADROTOR
) -> dict[str, np.ndarray]:
    """Which of controller ``name``'s quadrotor runs meet each criterion: ``"seed"`` (int)
    and one boolean array per key of :data:`CRITERIA_KEYS`, in seed order. The attitude
    cost needs the particle run of every seed and is left out without them; no quadrotor
    rows give an empty dict. One implementation for :func:`check_quadrotor` (every run must
    pass) and for per-run comparisons (:mod:`baselines.experiments.quadrotor.paired`)."""
    c = criteria
    quad = _runs(rows, "quadrotor", name)
    if not quad:
        return {}

    def arr(key: str) -> np.ndarray:
        return np.array([float(r[key]) for r in quad])

    full = arr("steps_run") == float(quad[0]["steps_run"])
    out = {
        "seed": np.array([int(float(r["seed"])) for r in quad]),
        "band_entry": arr("band_entry_time") <= c.band_entry_by,
        "straight_max": arr("straight_max_error") <= c.straight_max,
        "turn_peak": arr("turn_peak_error") <= c.turn_peak_max,
        "separation": arr("min_distance") >= c.min_distance,
        "unpaired_velocity": arr("velocity_mismatch") <= c.velocity_tolerance,
        "no_crash": (arr("crashed") == 0) & full,
    }
    cost = _attitude_cost_values(rows, name, quad)
    if cost is not None:
        out["attitude_cost"] = cost <= c.attitude_cost
    return out


def _policy_checks(rows, name: str, c: QuadrotorCriteria) -> list[tuple[str, bool, str]]:
    """The criteria for controller ``name`` (its quadrotor rows, and its particle rows for the
    cost of the attitude loop)."""
    ok = run_outcomes(rows, name, c)
    if not ok:
        return []
    quad = _runs(rows, "quadrotor", name)

    def arr(key: str) -> np.ndarray:
        return np.array([float(r[key]) for r in quad])

    entry, s, tp = arr("band_entry_time"), arr("straight_max_error"), arr("turn_peak_error")
    md, vm, crashed = arr("min_distance"), arr("velocity_mismatch"), arr("crashed")

    def line(text: str, key: str, detail: str) -> tuple[str, bool, str]:
        return f"{name}: {text}", bool(np.all(ok[key])), f"{detail}; {_misses(ok[key])}"

    out = [
        line(
            f"first in the {c.band} m band within {c.band_entry_by:g} s",
            "band_entry",
            _range_s(entry),
        ),
        line(
            f"max abs pair error <= {c.straight_max} m in [15,20], [27,50], [57,65] s",
            "straight_max",
            f"max {np.max(s):.3f} m",
        ),
        line(
            f"peak abs pair error in the turns <= {c.turn_peak_max} m",
            "turn_peak",
            f"max {np.max(tp):.3f} m",
        ),
        line(
            f"no two UAVs closer than {c.min_distance} m", "separation", f"min {np.min(md):.2f} m"
        ),
        line(
            f"unpaired velocity within {c.velocity_tolerance} m/s of the leader "
            "in [35,50], [60,65] s",
            "unpaired_velocity",
            f"max {np.max(vm):.3f} m/s",
        ),
        line("no crash, every episode runs 65 s", "no_crash", f"{int(crashed.sum())} crashes"),
    ]
    if "attitude_cost" in ok:
        cost = _attitude_cost_values(rows, name, quad)
        out.append(
            line(
                f"attitude loop costs <= {c.attitude_cost} m over the particle "
                "(straight-flight max error, same seed)",
                "attitude_cost",
                f"{np.min(cost):+.3f} to {np.max(cost):+.3f} m",
            )
        )
    return out


def _attitude_cost_values(rows, name: str, quad: list) -> np.ndarray | None:
    """Quadrotor minus particle straight-flight max error per seed (None without the
    particle run of every seed)."""
    part = {r["seed"]: r for r in _runs(rows, "particle", name)}
    if not part or not all(r["seed"] in part for r in quad):
        return None
    s = np.array([float(r["straight_max_error"]) for r in quad])
    return s - np.array([float(part[r["seed"]]["straight_max_error"]) for r in quad])


def check_quadrotor(
    rows: Sequence[Mapping[str, Any]],
    criteria: QuadrotorCriteria = QUADROTOR,
    policies: Sequence[str] = ("smc",),
) -> list[tuple[str, bool, str]]:
    """The Sec. VI-B criteria, every seed, for each controller in ``policies`` that has
    quadrotor rows (in that order; by default sliding mode only, as in the paper); the rows
    are those of :func:`baselines.experiments.quadrotor.runs.run_job` (both vehicle models).

    Raises ``TypeError`` if ``policies`` is a string rather than a sequence of names.
    """
    if isinstance(policies, str):
        raise TypeError(f"policies={policies!r} is invalid: give a sequence of names")
    return [chk for name in dict.fromkeys(policies) for chk in _policy_checks(rows, name, criteria)]
