"""A synthetic row of the quadrotor experiment's ``results.csv`` that meets every Sec. VI-B
criterion with room to spare; tests override the metrics they want to miss."""

from __future__ import annotations

from baselines.experiments.quadrotor.criteria import QUADROTOR


def quad_row(policy: str, dynamics: str, seed, **over) -> dict:
    """One run of ``policy`` on ``dynamics`` with seed ``seed`` (an int, or text as read
    back from a CSV), every metric halfway inside its criterion, ``over`` on top."""
    c = QUADROTOR
    row = {
        "dynamics": dynamics,
        "policy": policy,
        "seed": seed,
        "band_entry_time": c.band_entry_by / 2,
        "straight_max_error": c.straight_max / 2,
        "turn_peak_error": c.turn_peak_max / 2,
        "min_distance": 2 * c.min_distance,
        "velocity_mismatch": c.velocity_tolerance / 2,
        "crashed": 0,
        "steps_run": 10,
    }
    return {**row, **over}
