"""Markdown tables of per-run metric rows: the one summary-table writer and its cells.

Every summary of the project (benchmark, reproduction, quadrotor experiment, training
evaluation) is :func:`summary_table`: one line per group of rows, leading cells that name the
group, then ``median [min-max]`` over the group's runs per metric. :func:`safety_table` is the
safety filter's table of a benchmark whose runs carry the safety columns
(:data:`pairflock_env.task.metrics.SAFETY_METRIC_DOCS`): per (policy, scenario), what the
filter buys and what it costs.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from typing import Any

import numpy as np

from pairflock_env.task.metrics import METRIC_DOCS

__all__ = [
    "ACCURACY_METRICS",
    "COST_METRICS",
    "PIVOT_METRICS",
    "SAFETY_METRICS",
    "SCENARIO_KEYS",
    "has_safety_columns",
    "has_swarm_columns",
    "md_escape",
    "pivot_table",
    "safety_table",
    "stat_cell",
    "summarize",
    "summary_table",
    "swarm_table",
]

Row = Mapping[str, Any]
#: (metric, header, cell): ``cell`` is a format for :func:`stat_cell` or a function
#: ``(values, rows) -> str`` of the group's values and rows
Metric = tuple[str, str, "str | Callable[[list[Any], list[Row]], str]"]
#: (header, row key or function of the group's first row) of a leading column
Lead = tuple[str, "str | Callable[[Row], Any]"]
Keys = Sequence[tuple[str, str]]

#: (metric, header, format) of the benchmark's two summary tables
ACCURACY_METRICS = (
    ("s_settle_time", "s settle (s)", "{:.2f}"),
    ("band_time", "in 0.5 m band for good (s)", "{:.2f}"),
    ("ss_mean_error", "steady mean err (m)", "{:.3f}"),
    ("ss_max_error", "steady max err (m)", "{:.3f}"),
)
COST_METRICS = (
    ("peak_accel", "peak accel (m/s^2)", "{:.0f}"),
    ("effort", "effort (m^2/s^3)", "{:.3g}"),
    ("chattering", "chattering (m/s^3)", "{:.3g}"),
    ("peak_speed", "peak speed (m/s)", "{:.1f}"),
    ("min_pair_separation", "min pair-other dist (m)", "{:.2f}"),
    ("pair_collision_steps", "collision steps", "{:.0f}"),
    ("final_velocity_mismatch", "velocity mismatch (m/s)", "{:.3f}"),
    ("final_largest_component", "largest component", "{:.0f}"),
)
#: metrics also tabulated scenarios-down, policies-across (the robustness view)
PIVOT_METRICS = ("ss_mean_error", "ss_max_error", "band_time")
#: default leading columns of the benchmark tables: the scenario label
SCENARIO_KEYS: Keys = (("scenario", "scenario"),)

_UNKNOWN = sorted(m for m, _, _ in ACCURACY_METRICS + COST_METRICS if m not in METRIC_DOCS)
if _UNKNOWN:  # pragma: no cover - a table may name only metrics that exist
    raise ImportError(f"summary tables name unknown metrics {_UNKNOWN}")


def stat_cell(values: Sequence[float], fmt: str) -> str:
    """``median [min-max]`` over runs; NaN runs (a time never reached) are counted."""
    v = np.asarray(values, dtype=float)
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return "never"
    rng = f"{fmt.format(finite.min())}-{fmt.format(finite.max())}"
    if finite.size < v.size:
        return f"never in {v.size - finite.size}/{v.size}; others {rng}"
    return f"{fmt.format(np.median(v))} [{rng}]"


def md_escape(text: str) -> str:
    """Text for a markdown table cell (a bare '|' would end the cell)."""
    return text.replace("|", "\\|")


def _scenario(r: Row) -> str:
    return r["scenario"] if "scenario" in r else f"N={r['n_uavs']}"


def _getter(key: str | Callable[[Row], Any]) -> Callable[[Row], Any]:
    return key if callable(key) else (lambda r: r[key])


def _cell(cell, values: list[Any], rows: list[Row]) -> str:
    return cell(values, rows) if callable(cell) else stat_cell(values, cell)


def summary_table(
    rows: Sequence[Row],
    metrics: Sequence[Metric] = ACCURACY_METRICS,
    keys: Keys = SCENARIO_KEYS,
    *,
    lead: Sequence[Lead] | None = None,
    group: Callable[[Row], Hashable] | None = None,
    sort: Callable[[Hashable], Any] | None = None,
) -> str:
    """Markdown: one line per group of rows, ``median [min-max]`` of each metric.

    Default (the benchmark's tables): one line per (scenario, policy), scenarios in order of
    appearance, then their policies in order of appearance; leading columns ``keys`` (header,
    row key), e.g. ``(("N", "n_uavs"),)`` for a grid over N, then the policy.

    Args:
        rows: one mapping per run.  metrics: (metric, header, cell) per column.
        lead: (header, row key or function) of the leading columns, read from each group's
            first row; replaces ``keys`` + policy.
        group: row -> group key (default: the leading cells).
        sort: key function over group keys (default: order of first appearance).
    """
    if lead is None:
        lead = [
            *((h, lambda r, k=k: r.get(k, _scenario(r))) for h, k in keys),
            ("policy", "policy"),
        ]
        if group is None:
            group = lambda r: (_scenario(r), r["policy"])  # noqa: E731
            first: dict[str, int] = {}
            for r in rows:
                first.setdefault(_scenario(r), len(first))
            sort = sort or (lambda g: first[g[0]])  # a stable sort: policies stay in order
    getters = [_getter(k) for _, k in lead]
    group = group or (lambda r: tuple(str(g(r)) for g in getters))
    groups: dict[Hashable, list[Row]] = {}
    for r in rows:
        groups.setdefault(group(r), []).append(r)
    order = list(groups) if sort is None else sorted(groups, key=sort)
    heads = [h for h, _ in lead] + [h for _, h, _ in metrics]
    lines = ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
    for g in order:
        sel = groups[g]
        cells = [str(get(sel[0])) for get in getters]
        cells += [_cell(cell, [r[m] for r in sel], sel) for m, _, cell in metrics]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def summarize(rows: Sequence[Row], keys: Keys = SCENARIO_KEYS) -> str:
    """Both benchmark summary tables (accuracy, then cost and safety)."""
    return (
        summary_table(rows, ACCURACY_METRICS, keys)
        + "\n\n"
        + summary_table(rows, COST_METRICS, keys)
    )


def pivot_table(rows: Sequence[Row], metric: str, fmt: str, keys: Keys = SCENARIO_KEYS) -> str:
    """Markdown: scenarios down, policies across, ``median [min-max]`` of ``metric``."""
    pols = list(dict.fromkeys(r["policy"] for r in rows))
    heads = [h for h, _ in keys]
    lines = ["| " + " | ".join(heads + pols) + " |", "|" + "---|" * (len(pols) + len(keys))]
    for sc in dict.fromkeys(_scenario(r) for r in rows):
        sel = [r for r in rows if _scenario(r) == sc]
        cells = [str(sel[0].get(k, sc)) for _, k in keys]
        for pol in pols:
            vals = [r[metric] for r in sel if r["policy"] == pol]
            cells.append(stat_cell(vals, fmt) if vals else "-")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


# --------------------------------------------------------------------------- safety
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


def safety_table(rows: Sequence[Row], keys: Keys, metrics: Sequence[Metric] | None = None) -> str:
    """Markdown: one line per (policy, scenario), policies in order of appearance and their
    scenarios in order; leading columns the policy and ``keys`` (header, row key); columns
    ``metrics`` (default :data:`SAFETY_METRICS`)."""
    pols: dict[str, int] = {}
    scen: dict[str, int] = {}
    for r in rows:
        pols.setdefault(r["policy"], len(pols))
        scen.setdefault(r["scenario"], len(scen))
    lead = [("policy", "policy"), *((h, lambda r, k=k: r.get(k, r["scenario"])) for h, k in keys)]
    return summary_table(
        rows,
        SAFETY_METRICS if metrics is None else metrics,
        lead=lead,
        group=lambda r: (r["policy"], r["scenario"]),
        sort=lambda g: (pols[g[0]], scen[g[1]]),
    )


# --------------------------------------------------------------------------- every UAV
def _none_below(values: list[Any], rows: list[Row]) -> str:
    return f"{int(np.sum(np.asarray(values) == 0))}/{len(values)}"


def _smallest_int(values: list[Any], rows: list[Row]) -> str:
    return f"{int(np.min(values))}" if values else "-"


#: (metric, header, cell) of the whole swarm's table (one row per run: swarm metrics)
SWARM_METRICS = (
    ("swarm_closest", "closest two UAVs min (m)", lambda v, r: f"{np.min(v):.3f}"),
    ("swarm_steps_below", "runs never below D_s", _none_below),
    ("swarm_infeasible_uav_steps", "infeasible UAV-steps", _total_and_runs),
    ("swarm_active_uav_steps", "active UAV-steps median", _median("{:.0f}")),
    ("flock_gyration", "Rg median (m)", _median("{:.2f}")),
    ("flock_velocity_mismatch", "vel. mismatch median (m/s)", _median("{:.4f}")),
    ("flock_tracking", "tracking median (m)", _median("{:.3f}")),
    ("flock_lattice_deviation", "lattice dev. median (m^2)", _median("{:.3g}")),
    ("flock_min_component", "largest component min", _smallest_int),
)


def has_swarm_columns(rows: Sequence[Row]) -> bool:
    """Whether the runs carry the whole swarm's separation and flock metrics."""
    return bool(rows) and all("swarm_closest" in r for r in rows)


def swarm_table(rows: Sequence[Row], keys: Keys) -> str:
    """Markdown: :data:`SWARM_METRICS` per (policy, scenario), over runs (one row per swarm:
    the pair-0 rows, since a swarm's metrics repeat on each of its pairs' rows)."""
    return safety_table([r for r in rows if r["pair"] == 0], keys, SWARM_METRICS)
