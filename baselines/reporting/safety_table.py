"""The safety filter's table: per (policy, scenario), what the filter buys and what it costs.

One line per policy and scenario (the scenarios' grid axes as leading columns, e.g. N, init,
filter), from the per-run rows of a benchmark whose runs carry the safety columns
(:data:`pairflock_env.task.metrics.SAFETY_METRIC_DOCS`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from baselines.reporting.tables import Keys, summary_table

__all__ = ["SAFETY_METRICS", "has_safety_columns", "safety_table"]

Row = Mapping[str, Any]


def _finite(values: Sequence[Any]) -> tuple[np.ndarray, int]:
    v = np.asarray(values, dtype=float)
    return v[np.isfinite(v)], int(v.size)


def _median_worst(fmt: str):
    """``median / worst`` (largest); runs that never got there are counted."""

    def cell(values: list[Any], rows: list[Row]) -> str:
        f, n = _finite(values)
        if f.size == 0:
            return "never"
        text = f"{fmt.format(np.median(f))} / {fmt.format(f.max())}"
        return text if f.size == n else f"{text} (never in {n - f.size}/{n})"

    return cell


def _smallest(values: list[Any], rows: list[Row]) -> str:
    f, _ = _finite(values)
    return f"{f.min():.2f}" if f.size else "-"


def _count_ok(values: list[Any], rows: list[Row]) -> str:
    return f"{int(np.sum(values))}/{len(values)}"


def _total_and_runs(values: list[Any], rows: list[Row]) -> str:
    v = np.asarray(values, dtype=np.int64)
    return f"{int(v.sum())} ({int(np.count_nonzero(v))} runs)" if v.any() else "0"


def _median(fmt: str):
    def cell(values: list[Any], rows: list[Row]) -> str:
        f, _ = _finite(values)
        return fmt.format(np.median(f)) if f.size else "-"

    return cell


#: (metric, header, cell) of the safety table
SAFETY_METRICS = (
    ("ss_mean_error", "steady err median / worst (m)", _median_worst("{:.3f}")),
    ("band_time", "band time median / max (s)", _median_worst("{:.2f}")),
    ("closest_pass", "closest pass min (m)", _smallest),
    ("closest_pass_ok", "runs >= safety_distance", _count_ok),
    ("peak_accel", "peak accel median / max (m/s^2)", _median_worst("{:.0f}")),
    ("effort", "effort median (m^2/s^3)", _median("{:.3g}")),
    ("safety_infeasible_steps", "infeasible agent-steps", _total_and_runs),
    ("safety_active_steps", "active agent-steps median", _median("{:.0f}")),
)


def has_safety_columns(rows: Sequence[Row]) -> bool:
    """Whether the runs carry the safety filter's metrics."""
    return bool(rows) and all("closest_pass" in r for r in rows)


def safety_table(rows: Sequence[Row], keys: Keys) -> str:
    """Markdown: one line per (policy, scenario), policies in order of appearance and their
    scenarios in order; leading columns the policy and ``keys`` (header, row key)."""
    pols: dict[str, int] = {}
    scen: dict[str, int] = {}
    for r in rows:
        pols.setdefault(r["policy"], len(pols))
        scen.setdefault(r["scenario"], len(scen))
    lead = [("policy", "policy"), *((h, lambda r, k=k: r.get(k, r["scenario"])) for h, k in keys)]
    return summary_table(
        rows,
        SAFETY_METRICS,
        lead=lead,
        group=lambda r: (r["policy"], r["scenario"]),
        sort=lambda g: (pols[g[0]], scen[g[1]]),
    )
