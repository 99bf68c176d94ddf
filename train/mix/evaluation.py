"""Evaluation on several tasks: per-task summaries, their aggregate, and one selection score.

A run's evaluation (:class:`train.callbacks.EvalCallback`) rolls the policy out on every
evaluation task (:func:`train.tasks.evaluation_tasks`) with the evaluation seeds. The summary
it logs (``eval.csv``, TensorBoard) holds, for a run with tasks,

* ``<task>/<metric>`` and ``<task>/score``: each task's :func:`train.callbacks.
  summarize_metrics` and its :func:`baselines.reporting.criteria.learned_score`;
* ``<metric>``: the aggregate, the worst task's value of each metric (the largest error, band
  time and acceleration, the smallest separation; ``band_never`` summed over tasks);
* ``score`` (added by the callback): the run's selection score, by ``eval_aggregate``:
  ``worst`` (default), the largest per-task score, or ``sum``, their sum.

Why the worst task by default: the learned-policy targets hold per task (every seed of each
swarm size and start), so a generalist is as good as its worst task; a sum lets a gain on an
easy task hide a loss on the hardest one, which is the failure a mix is meant to fix. With
every target met on every task, each task's score is its median error, and ``worst`` keeps
the model whose least accurate task is most accurate.

A run on one task (no ``tasks``, no ``eval_tasks``) keeps its single summary without
prefixes and :func:`baselines.reporting.criteria.learned_score` as its score.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from baselines.reporting.criteria import LEARNED, TARGETS, learned_score
from train.callbacks import SUMMARY, eval_score, summarize_metrics
from train.mix.tasks import evaluation_tasks, is_mix

__all__ = ["aggregate_score", "score_function", "summarize_tasks", "tagged_rows"]


def summarize_tasks(
    rows_by_task: Mapping[str, list[dict[str, Any]]], targets: Any = None
) -> dict[str, float]:
    """The evaluation summary of rows per task (see the module docstring); a single task
    named ``""`` gives :func:`train.callbacks.summarize_metrics` of its rows, unchanged.
    ``targets`` (:class:`baselines.reporting.criteria.LearnedTargets`, default ``LEARNED``)
    give each task's score."""
    if list(rows_by_task) == [""]:
        return summarize_metrics(rows_by_task[""])
    per = {name: summarize_metrics(rows) for name, rows in rows_by_task.items()}
    out: dict[str, float] = {}
    for key, (metric, _) in SUMMARY.items():
        vals = [s[key] for s in per.values()]
        out[key] = float(np.min(vals) if metric == "min_pair_separation" else np.max(vals))
    out["band_never"] = float(sum(s["band_never"] for s in per.values()))
    for name, s in per.items():
        out.update({f"{name}/{k}": v for k, v in s.items()})
        out[f"{name}/score"] = float(learned_score(s, targets or LEARNED))
    return out


def aggregate_score(summary: Mapping[str, float], names: list[str], how: str) -> float:
    """The selection score of a multi-task summary: the worst (largest) or the sum of the
    per-task scores ``<task>/score``."""
    scores = [float(summary[f"{n}/score"]) for n in names]
    return max(scores) if how == "worst" else float(sum(scores))


def score_function(settings: Any) -> Callable[[Mapping[str, float]], float]:
    """The score a run keeps its best model by: lower is better, 0 when every target is met
    (plus the median error as a tie-breaker)."""
    if not is_mix(settings):
        if settings.eval_targets == "learned":
            return eval_score
        targets = TARGETS[settings.eval_targets]
        return lambda summary: learned_score(summary, targets)
    names = [t.name for t in evaluation_tasks(settings)]
    how = settings.eval_aggregate

    def score(summary: Mapping[str, float]) -> float:
        return aggregate_score(summary, names, how)

    return score


def tagged_rows(rows_by_task: Mapping[str, list[dict[str, Any]]], **tags: Any) -> list[dict]:
    """The rows of every task, each with ``tags`` and (several tasks) its ``task`` first."""
    if list(rows_by_task) == [""]:
        return [{**tags, **r} for r in rows_by_task[""]]
    return [{**tags, "task": n, **r} for n, rows in rows_by_task.items() for r in rows]
