"""The Sec. VI-B criteria of the quadrotor experiment and the check that applies them.

The check serves any pair controller, not only sliding mode:
``check_quadrotor(rows, policies=("smc", "sb3:pair_quad3d"))`` gives the same criteria for
each, every line prefixed with the controller's name.

The criteria are stated for the ``paper-quadrotor`` scenario (:data:`QUADROTOR`). A scaled
scenario gets them through :func:`criteria_for`: every threshold with a unit of length
(m, and m/s) times the scenario's length scale, ``d_m`` over the paper's (0.25 for the
``crazyflie`` preset, whose spacing and radius are scaled by the same factor); times stay in
seconds (the scaled presets keep the paper's flocking gains and control period); the time
windows are the scenario's (:data:`SCENARIO_WINDOWS`), placed by its leader's manoeuvres.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from pairflock_env import make_config

__all__ = [
    "CRITERIA_KEYS",
    "LENGTH_FIELDS",
    "QUADROTOR",
    "REFERENCE_PRESET",
    "SCENARIO_WINDOWS",
    "QuadrotorCriteria",
    "check_quadrotor",
    "criteria_for",
    "length_scale",
    "run_outcomes",
    "windows_text",
]

Windows = tuple[tuple[float, float], ...]


@dataclasses.dataclass(frozen=True)
class QuadrotorCriteria:
    """Sec. VI-B, a pair controller on the quadrotor, every seed (times in s, distances in m);
    the paper states them for sliding mode. ``vehicle`` is the ``dynamics`` of the runs under
    test (the particle runs of the same seeds give the attitude cost); the windows are where
    the straight-flight, turn and velocity criteria look (s)."""

    band: float = 0.5  # |pair error| band
    band_entry_by: float = 10.0  # first in the band by this time
    straight_max: float = 0.5  # max |error| in straight flight
    turn_peak_max: float = 0.6  # peak |error| in and after the turns
    min_distance: float = 0.5  # no two UAVs closer than this
    velocity_tolerance: float = 0.6  # m/s: unpaired UAVs' speed error to the leader
    attitude_cost: float = 0.35  # quadrotor minus particle straight-flight max error
    vehicle: str = "quadrotor"
    straight_windows: Windows = ((15.0, 20.0), (27.0, 50.0), (57.0, 65.0))
    turn_windows: Windows = ((20.0, 27.0), (50.0, 57.0))  # each turn and 5 s after it
    velocity_windows: Windows = ((35.0, 50.0), (60.0, 65.0))

    def scaled(self, length: float) -> QuadrotorCriteria:
        """These criteria with every threshold in m or m/s (:data:`LENGTH_FIELDS`) times
        ``length``; times and windows unchanged."""
        if not (np.isfinite(length) and length > 0):
            raise ValueError(f"length={length!r} is invalid: must be a positive number")
        return dataclasses.replace(self, **{f: getattr(self, f) * length for f in LENGTH_FIELDS})


#: the thresholds with a unit of length (m, m/s), which :meth:`QuadrotorCriteria.scaled` scales
LENGTH_FIELDS = (
    "band",
    "straight_max",
    "turn_peak_max",
    "min_distance",
    "velocity_tolerance",
    "attitude_cost",
)

QUADROTOR = QuadrotorCriteria()
#: the scenario the thresholds are stated for
REFERENCE_PRESET = "paper-quadrotor"

#: the time windows of each scenario (s): straight flight, the turns with 5 s of recovery,
#: the velocity check. The ``crazyflie`` leader turns every 10 s (at 10, 20, ..., 60 s, 2 s
#: each); the paper's rule (from 15 s on: each turn and 5 s after it, straight flight the
#: rest) leaves 3 s legs. Its velocity windows are those legs from 35 s on, as the paper's
#: first; the paper's start 8-13 s after a turn ends, which no 10 s leg allows (these: 5 s)
SCENARIO_WINDOWS: dict[str, tuple[Windows, Windows, Windows]] = {
    "paper-quadrotor": (
        QUADROTOR.straight_windows,
        QUADROTOR.turn_windows,
        QUADROTOR.velocity_windows,
    ),
    "crazyflie": (
        tuple((10.0 * k + 7.0, 10.0 * k + 10.0) for k in range(1, 6)),
        ((15.0, 17.0), *((10.0 * k, 10.0 * k + 7.0) for k in range(2, 6)), (60.0, 65.0)),
        ((37.0, 40.0), (47.0, 50.0), (57.0, 60.0)),
    ),
}


def length_scale(preset: str) -> float:
    """The preset's ``d_m`` over the reference scenario's (2.5 m): 1 for
    ``paper-quadrotor``, 0.25 for ``crazyflie``."""
    return float(make_config(preset).d_m[0] / make_config(REFERENCE_PRESET).d_m[0])


def criteria_for(preset: str) -> QuadrotorCriteria:
    """The Sec. VI-B criteria of the scenario ``preset`` (a key of :data:`SCENARIO_WINDOWS`):
    :data:`QUADROTOR` scaled by :func:`length_scale`, the preset's vehicle and windows.
    ``ValueError`` names the valid presets."""
    if preset not in SCENARIO_WINDOWS:
        valid = ", ".join(SCENARIO_WINDOWS)
        raise ValueError(f"preset {preset!r} has no Sec. VI-B criteria: valid are {valid}")
    straight, turns, velocity = SCENARIO_WINDOWS[preset]
    return dataclasses.replace(
        QUADROTOR.scaled(length_scale(preset)),
        vehicle=make_config(preset).dynamics,
        straight_windows=straight,
        turn_windows=turns,
        velocity_windows=velocity,
    )


def windows_text(windows: Windows) -> str:
    """``[15,20], [27,50]``: time windows as the criteria and summaries write them."""
    return ", ".join(f"[{a:g},{b:g}]" for a, b in windows)


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
    """Which of controller ``name``'s runs on ``criteria.vehicle`` (the quadrotor unless
    told) meet each criterion: ``"seed"`` (int) and one boolean array per key of
    :data:`CRITERIA_KEYS`, in seed order. The attitude cost needs the particle run of every
    seed and is left out without them; no rows of the vehicle give an empty dict. One
    implementation for :func:`check_quadrotor` (every run must pass) and for per-run
    comparisons (:mod:`baselines.experiments.quadrotor.paired`)."""
    c = criteria
    quad = _runs(rows, c.vehicle, name)
    if not quad:
        return {}

    def arr(key: str) -> np.ndarray:
        return np.array([float(r[key]) for r in quad])

    # a run is full when it ran as long as the longest run of the experiment (an episode
    # ends early only when a swarm crashes or diverges; the particle runs never crash)
    full = arr("steps_run") == max(float(r["steps_run"]) for r in rows)
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
    """The criteria for controller ``name`` (its rows on ``c.vehicle``, and its particle rows
    for the cost of the attitude loop)."""
    ok = run_outcomes(rows, name, c)
    if not ok:
        return []
    quad = _runs(rows, c.vehicle, name)

    def arr(key: str) -> np.ndarray:
        return np.array([float(r[key]) for r in quad])

    entry, s, tp = arr("band_entry_time"), arr("straight_max_error"), arr("turn_peak_error")
    md, vm, crashed = arr("min_distance"), arr("velocity_mismatch"), arr("crashed")

    def line(text: str, key: str, detail: str) -> tuple[str, bool, str]:
        return f"{name}: {text}", bool(np.all(ok[key])), f"{detail}; {_misses(ok[key])}"

    out = [
        line(
            f"first in the {c.band:g} m band within {c.band_entry_by:g} s",
            "band_entry",
            _range_s(entry),
        ),
        line(
            f"max abs pair error <= {c.straight_max:g} m in {windows_text(c.straight_windows)} s",
            "straight_max",
            f"max {np.max(s):.3f} m",
        ),
        line(
            f"peak abs pair error in the turns <= {c.turn_peak_max:g} m",
            "turn_peak",
            f"max {np.max(tp):.3f} m",
        ),
        line(
            f"no two UAVs closer than {c.min_distance:g} m",
            "separation",
            f"min {np.min(md):.3f} m{_ellipsoid_detail(quad)}",
        ),
        line(
            f"unpaired velocity within {c.velocity_tolerance:g} m/s of the leader "
            f"in {windows_text(c.velocity_windows)} s",
            "unpaired_velocity",
            f"max {np.max(vm):.3f} m/s",
        ),
        line("no crash, every episode runs 65 s", "no_crash", f"{int(crashed.sum())} crashes"),
    ]
    if "attitude_cost" in ok:
        cost = _attitude_cost_values(rows, name, quad)
        out.append(
            line(
                f"attitude loop costs <= {c.attitude_cost:g} m over the particle "
                "(straight-flight max error, same seed)",
                "attitude_cost",
                f"{np.min(cost):+.3f} to {np.max(cost):+.3f} m",
            )
        )
    return out


def _ellipsoid_detail(quad: list) -> str:
    """The closest pass in the collision ellipsoid's measure, where the runs report it
    (``min_ellipsoid_separation``, >= 1: no downwash contact; ``ellipsoid_contact_steps``):
    reported beside the separation criterion, which it does not change."""
    if not quad or "min_ellipsoid_separation" not in quad[0]:
        return ""
    e = np.array([float(r["min_ellipsoid_separation"]) for r in quad])
    hit = np.array([float(r["ellipsoid_contact_steps"]) for r in quad])
    return (
        f"; ellipsoid: min {np.min(e):.2f} (>= 1: no contact), contact in "
        f"{int(np.count_nonzero(hit))}/{hit.size} runs, {int(hit.sum())} steps"
    )


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
    rows on ``criteria.vehicle`` (in that order; by default sliding mode only, as in the
    paper); the rows are those of :func:`baselines.experiments.quadrotor.runs.run_job` (both
    vehicle models). ``criteria_for("crazyflie")`` gives the scaled scenario's criteria.

    Raises ``TypeError`` if ``policies`` is a string rather than a sequence of names.
    """
    if isinstance(policies, str):
        raise TypeError(f"policies={policies!r} is invalid: give a sequence of names")
    return [chk for name in dict.fromkeys(policies) for chk in _policy_checks(rows, name, criteria)]
