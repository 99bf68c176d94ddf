"""SB3 callbacks of the training CLI: progress bar, periodic evaluation, checkpoints, stop.

Evaluation runs the policy in memory through ``baselines.evaluation.rollout.rollout`` (the
rollout and metrics code of the paper reproduction and the benchmark), on the evaluation seeds,
and logs it next to the analytic controllers (computed once per run). Checkpoints and stops
(Ctrl-C, time limit) happen at the start of a rollout, after the previous gradient update,
where the model, the environment and the random generators together define the rest of the
run exactly.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from tqdm import tqdm

from baselines.reporting.criteria import learned_score

#: the score the best model is kept by (:func:`baselines.reporting.criteria.learned_score`)
eval_score = learned_score

__all__ = [
    "CheckpointCallback",
    "EvalCallback",
    "GracefulInterrupt",
    "ProgressCallback",
    "StopCallback",
    "StopTraining",
    "eval_score",
    "summarize_metrics",
]

#: summary statistics logged per evaluation: name -> (metric, reduction)
SUMMARY = {
    "ss_error_median": ("ss_mean_error", "median"),
    "ss_error_max": ("ss_mean_error", "max"),
    "ss_max_error_max": ("ss_max_error", "max"),
    "band_time_max": ("band_time", "max"),
    "band_time_median": ("band_time", "median"),
    "min_separation_min": ("min_pair_separation", "min"),
    "min_separation_median": ("min_pair_separation", "median"),
    "peak_accel_max": ("peak_accel", "max"),
}


def summarize_metrics(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Median/max/min over seeds of the reproduction metrics; a band time that is never
    reached counts as +inf (so the max shows it)."""
    out: dict[str, float] = {}
    for name, (metric, how) in SUMMARY.items():
        v = np.array([r[metric] for r in rows], dtype=float)
        if metric == "band_time":
            v = np.where(np.isnan(v), np.inf, v)
        out[name] = float(getattr(np, how)(v))
    out["band_never"] = float(sum(math.isnan(r["band_time"]) for r in rows))
    return out


class GracefulInterrupt:
    """First Ctrl-C (SIGINT) sets a flag the callbacks turn into a clean stop; a second one
    raises KeyboardInterrupt as usual. Restores the previous handler on exit."""

    def __init__(self) -> None:
        self.requested = False
        self._previous: Any = None

    def __enter__(self) -> GracefulInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.getsignal(signal.SIGINT)
            signal.signal(signal.SIGINT, self._handle)
        return self

    def _handle(self, signum, frame) -> None:
        if self.requested:
            signal.signal(signal.SIGINT, self._previous)
            raise KeyboardInterrupt
        self.requested = True

    def __exit__(self, *exc) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None


class StopTraining(Exception):
    """Raised by :class:`StopCallback` at a rollout boundary to end ``model.learn()`` there."""


class StopCallback(BaseCallback):
    """Stops learning on Ctrl-C (see :class:`GracefulInterrupt`) or after a wall-time limit,
    at the start of the next rollout: after the last gradient update, before any new step,
    the point where a checkpoint continues exactly (so a stopped run, resumed, ends where an
    uninterrupted one ends). SB3 lets a callback stop only from a step, one step into the
    rollout, so it raises :class:`StopTraining` instead; :func:`train.run.train` catches it.
    """

    def __init__(self, interrupt: GracefulInterrupt, time_limit_s: float | None, start: float):
        super().__init__()
        self.interrupt = interrupt
        self.time_limit_s = time_limit_s
        self.start = start
        self.reason: str | None = None

    def _on_rollout_start(self) -> None:
        if self.interrupt.requested:
            self.reason = "interrupted (Ctrl-C)"
        elif self.time_limit_s is not None and time.perf_counter() - self.start > self.time_limit_s:
            self.reason = f"time limit of {self.time_limit_s / 60:.1f} min reached"
        if self.reason is not None:
            raise StopTraining(self.reason)

    def _on_step(self) -> bool:
        return True


class ProgressCallback(BaseCallback):
    """A tqdm bar over environment steps (rows x vector steps), with the latest evaluation."""

    def __init__(self, total: int, disable: bool = False) -> None:
        super().__init__()
        self.total = total
        self.disable = disable
        self.bar = None
        self.postfix: dict[str, str] = {}

    def _on_training_start(self) -> None:

        interval = 0.2 if sys.stderr.isatty() else 30.0  # log files get a line every 30 s
        self.bar = tqdm(
            total=self.total,
            initial=self.num_timesteps,
            unit="step",
            unit_scale=True,
            desc="train",
            disable=self.disable,
            smoothing=0.05,
            mininterval=interval,
        )

    def _on_step(self) -> bool:
        if self.bar is not None:
            self.bar.update(self.num_timesteps - self.bar.n)
        return True

    def set_postfix(self, **kw: str) -> None:
        self.postfix.update(kw)
        if self.bar is not None:
            self.bar.set_postfix(self.postfix, refresh=True)

    def _on_training_end(self) -> None:
        if self.bar is not None:  # also called after a stop (StopTraining)
            self.bar.update(self.num_timesteps - self.bar.n)
            self.bar.close()
            self.bar = None


class EvalCallback(BaseCallback):
    """Every ``every`` steps: roll out the current policy on the evaluation seeds with the
    baselines' rollout code, log the summary (and the baselines' for comparison) to the SB3
    logger (TensorBoard, CSV), append to ``history`` and save the best model so far.

    ``score`` turns a summary into the number the best model is kept by (lower is better;
    default :data:`eval_score`; a run on several tasks passes
    :func:`train.mix_eval.score_function`)."""

    def __init__(
        self,
        evaluate: Callable[[], tuple[list[dict[str, Any]], dict[str, float]]],
        baselines: dict[str, dict[str, float]],
        every: int,
        on_result: Callable[[int, list[dict[str, Any]], dict[str, float], bool], None],
        progress: ProgressCallback | None = None,
        next_eval: int = 0,
        best_score: float = math.inf,
        score: Callable[[dict[str, float]], float] = eval_score,
    ) -> None:
        super().__init__()
        self.score = score
        self.evaluate = evaluate
        self.baselines = baselines
        self.every = every
        self.on_result = on_result
        self.progress = progress
        self.next_eval = next_eval
        self.best_score = best_score

    def _on_step(self) -> bool:
        if self.every > 0 and self.num_timesteps >= self.next_eval:
            self.run_now()
            while self.next_eval <= self.num_timesteps:
                self.next_eval += self.every
        return True

    def run_now(self) -> dict[str, float]:
        rows, summary = self.evaluate()
        score = self.score(summary)
        improved = score < self.best_score
        if improved:
            self.best_score = score
        for k, v in summary.items():
            self.logger.record(f"eval/{k}", _finite(v))
        self.logger.record("eval/score", _finite(score))
        for name, s in self.baselines.items():
            for k in ("ss_error_median", "band_time_max", "min_separation_min", "peak_accel_max"):
                self.logger.record(f"eval_{name}/{k}", _finite(s[k]))
        self.logger.dump(self.num_timesteps)
        self.on_result(self.num_timesteps, rows, {**summary, "score": score}, improved)
        if self.progress is not None:
            self.progress.set_postfix(
                err=f"{summary['ss_error_median']:.3f}m",
                band=f"{summary['band_time_max']:.1f}s",
                sep=f"{summary['min_separation_min']:.2f}m",
            )
        return summary


def _finite(v: float) -> float:
    return float(v) if math.isfinite(v) else 1e9


class CheckpointCallback(BaseCallback):
    """Calls ``save(num_timesteps)`` at the first rollout start at or after every ``every``
    steps (a point between gradient updates, so a resumed run continues exactly)."""

    def __init__(self, save: Callable[[int], Path], every: int, next_save: int) -> None:
        super().__init__()
        self.save = save
        self.every = every
        self.next_save = next_save

    def _on_rollout_start(self) -> None:
        if self.every > 0 and self.num_timesteps >= self.next_save:
            while self.next_save <= self.num_timesteps:
                self.next_save += self.every
            self.save(self.num_timesteps)

    def _on_step(self) -> bool:
        return True
