"""``summary.md`` of a benchmark run: scenarios, the summary tables, criteria, metric docs."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from baselines.reporting import tables
from baselines.reporting.criteria import Check, criteria_table
from baselines.reporting.tables import (
    has_safety_columns,
    has_swarm_columns,
    safety_table,
    swarm_table,
)
from pairflock_env.task.metrics import (
    FLOCK_METRIC_DOCS,
    METRIC_DOCS,
    SAFETY_METRIC_DOCS,
    SWARM_SAFETY_METRIC_DOCS,
)

__all__ = ["summary_markdown"]


def _intro(plan) -> list[str]:
    seeds = plan.seeds
    horizons = sorted({c.episode_steps * c.dt for c in plan.configs})
    window = plan.metric_kwargs.get("steady_window")
    md = [
        f"# Benchmark `{plan.suite_name}`",
        "",
        f"Preset `{plan.preset}`; policies {', '.join(f'`{s.label}`' for s in plan.specs)}; "
        f"{len(seeds)} seeds ({seeds[0]}-{seeds[-1]}) per scenario and policy, the same seeds "
        f"and initial states for every policy; horizon {', '.join(f'{h:g}' for h in horizons)} s"
        + (f"; steady state = last {window:g} s" if window else "")
        + ". "
        'Cells: median [min-max] over runs; "never in k/n": k runs never got there.',
        "",
        "## Scenarios",
        "",
        "| scenario | overrides of the preset |",
        "|---|---|",
    ]
    for sc in plan.scenarios:
        ov = ", ".join(f"`{k}={v}`" for k, v in sc.overrides) or "none"
        md.append(f"| {sc.label} | {ov} |")
    return md


def _tables(plan, rows: Sequence[Mapping[str, Any]]) -> list[str]:
    keys = plan.keys
    md = [
        "",
        "## Convergence and accuracy",
        "",
        tables.summary_table(rows, tables.ACCURACY_METRICS, keys),
        "",
        "## Cost and safety",
        "",
        tables.summary_table(rows, tables.COST_METRICS, keys),
        "",
        "## By scenario and policy",
        "",
    ]
    table_fmt = {m: (h, f) for m, h, f in tables.ACCURACY_METRICS + tables.COST_METRICS}
    for metric in tables.PIVOT_METRICS:
        head, fmt = table_fmt[metric]
        md += [f"{head}:", "", tables.pivot_table(rows, metric, fmt, keys), ""]
    steps = {sc.label: c.episode_steps for sc, c in zip(plan.scenarios, plan.configs, strict=True)}
    ended = [r for r in rows if r["steps_run"] < steps[r["scenario"]]]
    if ended:
        md += [
            f"{len(ended)} runs ended early (divergence or collision termination); their "
            "series are frozen at the last state (column `steps_run`).",
            "",
        ]
    return md


def summary_markdown(
    plan, rows: Sequence[Mapping[str, Any]], checks: Sequence[Check], fig_paths: Sequence[Path]
) -> str:
    """The text of ``summary.md`` for a run of ``plan`` (a benchmark ``Plan``)."""
    md = _intro(plan) + _tables(plan, rows)
    docs = dict(METRIC_DOCS)
    if has_safety_columns(rows):
        md += [
            "## Safety filter",
            "",
            "Per policy and scenario over runs: median / worst; closest pass includes the "
            "partner; infeasible agent-steps summed over runs (runs with any).",
            "",
            safety_table(rows, plan.keys),
            "",
        ]
        docs.update(SAFETY_METRIC_DOCS)
    if has_swarm_columns(rows):
        md += [
            "## Every UAV and the flock",
            "",
            "Per policy and scenario over runs (one per swarm): the closest two UAVs of the "
            "swarm, runs with no step below safety_distance, infeasible UAV-steps summed over "
            "runs (runs with any), and the flock's quality over the steady window "
            "(docs/swarm-safety.md).",
            "",
            swarm_table(rows, plan.keys),
            "",
        ]
        docs.update(SWARM_SAFETY_METRIC_DOCS)
        docs.update(FLOCK_METRIC_DOCS)
    if checks:
        md += ["## Acceptance criteria (paper)", "", *criteria_table(checks), ""]
    md += ["## Metrics", "", "| column | unit | meaning |", "|---|---|---|"]
    md += [f"| `{k}` | {u} | {tables.md_escape(m)} |" for k, (u, m) in docs.items()]
    if fig_paths:
        md += ["", "## Figures", ""]
        md += [f"- `{p.relative_to(plan.out)}`" for p in fig_paths]
    return "\n".join(md) + "\n"
