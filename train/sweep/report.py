"""The report of ``python -m train.sweep``: sweep.csv, summary.md, curves.png.

Per setting and metric the summary gives the interquartile mean (IQM) over the training
seeds with a 95 % percentile confidence interval from the stratified bootstrap
(:func:`baselines.reporting.stats.iqm_ci`: ``rliable``'s estimates, drawing from an explicit
seeded generator so that the summary is reproducible). With fewer than four seeds the IQM
trims nothing (it is the mean).

A band time that is never reached (inf) counts as the evaluation episode's length, so the
statistics stay finite; the table marks such cells with ">=" (a lower bound).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from baselines.reporting.figures import save_figure
from baselines.reporting.stats import iqm_ci
from train.sweep.trial import result_scalars

__all__ = ["METRICS", "csv_rows", "curves_figure", "summary_markdown"]

#: (summary key, title, format) of the metrics in the tables and the figure
METRICS = (
    ("ss_error_median", "steady error (m)", "{:.3f}"),
    ("band_time_max", "into 0.5 m band, slowest seed (s)", "{:.2f}"),
    ("min_separation_min", "closest pass (m)", "{:.2f}"),
    ("peak_accel_max", "peak accel (m/s²)", "{:.0f}"),
    ("score", "score (0: every target met)", "{:.3f}"),
)
_CENSORED = ("band_time_max", "band_time_median")


def csv_rows(results: Sequence[Mapping[str, Any]], grid_keys: Sequence[str]) -> list[dict]:
    """One row per trial: setting, grid values, seed, metrics, aims; wall times last."""
    rows = []
    for r in results:
        row: dict[str, Any] = {"setting": r["setting"]}
        row.update({k: _cell(r["assignments"].get(k)) for k in grid_keys})
        row.update(seed=r["seed"], status=r["status"], num_timesteps=r["num_timesteps"])
        row.update(result_scalars(r))
        row.update({f"meets: {a['criterion']}": a["met"] for a in r.get("aims", [])})
        row.update(wall_train_s=r.get("wall_train_s"), wall_trial_s=r.get("wall_trial_s"))
        rows.append(row)
    return rows


def _cell(v: Any) -> Any:
    if isinstance(v, (list, dict)):
        return json.dumps(v, separators=(",", ":"))
    return v


def _values(results: Sequence[Mapping[str, Any]], part: str, key: str) -> tuple[list, int]:
    """Per-seed values (censored band times at the horizon) and how many were censored."""
    vals, censored = [], 0
    for r in results:
        v = float((r.get(part) or {}).get(key, math.nan))
        if key.rsplit("/", 1)[-1] in _CENSORED and not math.isfinite(v):
            v, censored = float(r["eval_horizon_s"]), censored + 1
        vals.append(v)
    return vals, censored


def _group(results: Sequence[Mapping[str, Any]]) -> dict[str, list[Mapping[str, Any]]]:
    groups: dict[str, list[Mapping[str, Any]]] = {}
    for r in results:
        groups.setdefault(r["label"], []).append(r)
    return groups


def _estimates(
    groups: Mapping[str, list],
    reps: int,
    prefix: str = "",
    parts: Sequence[str] = ("final", "best"),
) -> dict[tuple[str, str], list[str]]:
    """Table cells ``IQM [low, high]`` per (setting, part), one bootstrap per setting over
    all its columns (final and best metrics together); ``prefix`` selects an evaluation
    task's metrics (``<task>/``)."""
    cells: dict[tuple[str, str], list[str]] = {}
    for label, rs in groups.items():
        have = [p for p in parts if all(r.get(p) for r in rs)]
        cols = [(p, m, _values(rs, p, prefix + m[0])) for p in have for m in METRICS]
        if not cols:
            continue
        point, lo, hi = iqm_ci(np.array([c[2][0] for c in cols]).T, reps=reps)
        for (part, (_, _, fmt), (_, cens)), p, a, b in zip(cols, point, lo, hi, strict=True):
            mark = ">= " if cens else ""
            text = f"{mark}{fmt.format(p)} [{fmt.format(a)}, {fmt.format(b)}]"
            cells.setdefault((label, part), []).append(text)
    return cells


def _metric_table(groups: Mapping[str, list], part: str, cells: Mapping) -> list[str]:
    head = "| setting | seeds | " + " | ".join(t for _, t, _ in METRICS) + " |"
    lines = [head, "|" + "---|" * (len(METRICS) + 2)]
    for label, rs in groups.items():
        row = cells.get((label, part), ["-"] * len(METRICS))
        lines.append(f"| {label} | {len(rs)} | " + " | ".join(row) + " |")
    return lines


def _aims_table(groups: Mapping[str, list], by_row: bool = False) -> list[str]:
    """Seeds meeting each aim, one row per setting (``by_row``: one row per aim, for the
    many aims of several evaluation tasks)."""
    names: list[str] = []
    for rs in groups.values():
        for r in rs:
            names += [a["criterion"] for a in r.get("aims", []) if a["criterion"] not in names]
    if not names:
        return ["(no aims were evaluated)"]
    counts = {}
    for label, rs in groups.items():
        for n in names:
            met = [a["met"] for r in rs for a in r.get("aims", []) if a["criterion"] == n]
            counts[label, n] = f"{sum(met)}/{len(met)}" if met else "-"
    if by_row:
        lines = ["| aim | " + " | ".join(groups) + " |", "|" + "---|" * (len(groups) + 1)]
        return lines + [
            f"| {n} | " + " | ".join(counts[g, n] for g in groups) + " |" for n in names
        ]
    lines = ["| setting | " + " | ".join(names) + " |", "|" + "---|" * (len(names) + 1)]
    for label in groups:
        lines.append(f"| {label} | " + " | ".join(counts[label, n] for n in names) + " |")
    return lines


def _task_table(groups: Mapping[str, list], reps: int) -> list[str]:
    """The final model's metrics per evaluation task: IQM [95 % CI] over seeds."""
    tasks = list(dict.fromkeys(t for rs in groups.values() for r in rs for t in r["eval_tasks"]))
    head = "| setting | task | seeds | " + " | ".join(t for _, t, _ in METRICS) + " |"
    lines = [head, "|" + "---|" * (len(METRICS) + 3)]
    for task in tasks:
        cells = _estimates(groups, reps, prefix=f"{task}/", parts=("final",))
        for label, rs in groups.items():
            row = cells.get((label, "final"), ["-"] * len(METRICS))
            lines.append(f"| {label} | {task} | {len(rs)} | " + " | ".join(row) + " |")
    return lines


def summary_markdown(
    results: Sequence[Mapping[str, Any]],
    header: Sequence[str],
    reps: int = 2000,
    figure: str | None = "curves.png",
) -> str:
    """The summary: IQM [95 % CI] tables (final and best model) and the aims met."""
    groups = _group(results)
    cells = _estimates(groups, reps)
    mix = any(r.get("eval_tasks") for r in results)
    lines = [*header, ""]
    lines += ["## Final model: IQM [95 % CI] over seeds", ""]
    if mix:
        lines += [
            "Several evaluation tasks: each metric is the worst task's, the score the run's "
            "selection score over the tasks (`eval_aggregate`; train/mix/evaluation.py).",
            "",
        ]
    lines += _metric_table(groups, "final", cells)
    if mix:
        lines += ["", "## Final model per evaluation task: IQM [95 % CI] over seeds", ""]
        lines += _task_table(groups, reps)
    lines += ["", "## Best model during training: IQM [95 % CI] over seeds", ""]
    lines += [
        "Picked on the same evaluation seeds it is scored on, so optimistic.",
        "",
        *_metric_table(groups, "best", cells),
    ]
    lines += ["", "## Aims: seeds whose final model meets each", ""]
    lines += [*_aims_table(groups, by_row=mix), ""]
    if figure:
        lines += [f"![validation curves]({figure})", ""]
    lines += [
        "IQM: interquartile mean over training seeds (`rliable.metrics.aggregate_iqm`; the "
        "mean below four seeds); CI: 95 % percentile interval of the stratified bootstrap over "
        f"seeds (`rliable.library.StratifiedBootstrap`, {reps} resamples, seed 0). Metrics are "
        "the training evaluation's summaries over its evaluation seeds (median steady error, "
        "slowest band entry, closest pass of the pair to another UAV, peak pair acceleration); "
        "'>=': a seed never entered the band, counted as the evaluation episode's length.",
    ]
    return "\n".join(lines) + "\n"


def _curve_matrix(rs: Sequence[Mapping[str, Any]], key: str) -> tuple[np.ndarray, np.ndarray]:
    """Steps evaluated by every seed and the (seeds, steps) values there."""
    common = set.intersection(*({int(c["step"]) for c in r.get("curve", [])} for r in rs))
    steps = np.array(sorted(common), dtype=float)
    vals = []
    for r in rs:
        by_step = {int(c["step"]): float(c.get(key, math.nan)) for c in r["curve"]}
        row = [by_step[int(s)] for s in steps]
        if key in _CENSORED:
            row = [v if math.isfinite(v) else float(r["eval_horizon_s"]) for v in row]
        vals.append(row)
    return steps, np.array(vals, dtype=float).reshape(len(rs), len(steps))


def curves_figure(results: Sequence[Mapping[str, Any]], path: Path, reps: int = 1000) -> Path:
    """Validation curves per setting: IQM over seeds with a 95 % CI band, per metric."""
    shown = METRICS[:4]
    fig = Figure(figsize=(11, 7.5), constrained_layout=True)
    axes = fig.subplots(2, 2)
    for i, (label, rs) in enumerate(_group(results).items()):
        mats = [_curve_matrix(rs, key) for key, _, _ in shown]
        steps = mats[0][0]
        if not len(steps):
            continue
        point, lo, hi = (
            a.reshape(len(shown), len(steps))
            for a in iqm_ci(np.concatenate([m[1] for m in mats], axis=1), reps=reps, seed=i)
        )
        for j, ax in enumerate(axes.flat):
            ax.plot(steps, point[j], color=f"C{i}", label=f"{label} ({len(rs)} seeds)")
            ax.fill_between(steps, lo[j], hi[j], color=f"C{i}", alpha=0.2, linewidth=0)
    for ax, (key, title, _) in zip(axes.flat, shown, strict=True):
        ax.set_title(title)
        ax.set_xlabel("training steps")
        if key == "ss_error_median":
            ax.set_yscale("log")
        ax.grid(alpha=0.3)
    axes.flat[0].legend(fontsize=8)
    fig.suptitle("Evaluation during training: IQM over seeds, 95 % stratified-bootstrap CI")
    return save_figure(fig, Path(path), dpi=110)
