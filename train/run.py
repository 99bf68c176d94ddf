"""One training run: environment, model, callbacks, checkpoints, evaluation, run record.

Used by the CLI (:mod:`train.cli`); importable for notebooks and tests::

    from train.settings import settings_from_sources
    from train.run import train
    result = train(settings_from_sources(flags={"total_steps": 2000}), Path("runs/smoke"))
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from stable_baselines3.common.logger import CSVOutputFormat, Logger, TensorBoardOutputFormat
from stable_baselines3.common.vec_env import VecMonitor

from baselines import make_pair_policy
from baselines.controllers.sb3 import SB3PairPolicy
from baselines.evaluation.rollout import rollout, trace_metrics
from baselines.reporting.criteria import TARGETS
from baselines.runtime.files import atomic_write_text, write_csv, write_json
from baselines.runtime.record import run_record
from baselines.runtime.threads import pin_threads
from pairflock_env import make_config
from pairflock_env.envs.sb3 import PairFlockSB3VecEnv
from train.callbacks import (
    CheckpointCallback,
    EvalCallback,
    GracefulInterrupt,
    ProgressCallback,
    StopCallback,
    StopTraining,
)
from train.checkpoint import (
    latest_checkpoint,
    load_checkpoint_state,
    restore_monitor,
    save_checkpoint,
    set_rng_state,
)
from train.mix.env import make_mix_vec_env
from train.mix.evaluation import score_function, summarize_tasks, tagged_rows
from train.mix.tasks import evaluation_tasks, is_mix, training_tasks
from train.model import METADATA_KEY, build_model, load_model, metadata, save_model_atomic
from train.settings import RunSettings

__all__ = [
    "ALREADY_COMPLETE",
    "RunResult",
    "evaluate_model",
    "evaluate_policy_rows",
    "make_vec_env",
    "train",
]

FINAL_MODEL = "final_model.zip"
#: the run's record; a resumed session writes its own (run_resumed_<steps>.json) and updates it
RUN_RECORD = "run.json"
BEST_MODEL = "best_model.zip"
#: status of a resumed run that had already reached its step target (nothing is changed)
ALREADY_COMPLETE = "already complete"


@dataclasses.dataclass
class RunResult:
    """What :func:`train` did: where, how many steps, how it ended, the last evaluation."""

    out: Path
    num_timesteps: int
    status: str  # "completed" | "interrupted (Ctrl-C)" | "time limit ..." | "already complete"
    wall_s: float
    final_summary: dict[str, float] | None

    @property
    def interrupted(self) -> bool:
        return self.status.startswith("interrupted")


def make_vec_env(settings: RunSettings, seed_offset: int = 0):
    """The native SB3 VecEnv of the training task, wrapped in a VecMonitor."""

    if settings.tasks is not None:  # a mix: one task env per task, rows concatenated
        return VecMonitor(make_mix_vec_env(settings, seed_offset))
    ss = np.random.SeedSequence([settings.seed, seed_offset])
    env = PairFlockSB3VecEnv(
        settings.preset,
        num_swarms=settings.num_swarms,
        seed=ss,
        **settings.env_kwargs(),
        **settings.config_overrides(),
    )
    return VecMonitor(env)


def evaluate_policy_rows(policy: Any, cfg: Any, seeds: list[int]) -> list[dict[str, Any]]:
    """Metrics per seed of ``policy`` on ``cfg`` with the baselines' rollout code."""
    return trace_metrics(rollout(cfg, policy, seeds))


def evaluate_model(model: Any, interface: Any, eval_cfgs, seeds, targets):
    """A model's evaluation as a run selects by: rows per task (``eval_cfgs``: task name ->
    config) on ``seeds``, and their summary (:func:`train.mix_eval.summarize_tasks`)."""
    iface = interface.to_dict()
    by_task = {
        task: evaluate_policy_rows(SB3PairPolicy(model, cfg, iface), cfg, list(seeds))
        for task, cfg in eval_cfgs.items()
    }
    return by_task, summarize_tasks(by_task, targets)


def _write_settings(out: Path, settings: RunSettings) -> None:

    text = yaml.safe_dump(settings.to_dict(), sort_keys=False, default_flow_style=None)
    atomic_write_text(out / "settings.yaml", text)


def _prepare_dir(out: Path, overwrite: bool) -> None:
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise FileExistsError(
                f"--out {str(out)!r} is not empty; pass --overwrite to replace it or "
                f"--resume {str(out)!r} to continue it"
            )
        shutil.rmtree(out)
    out.mkdir(parents=True, exist_ok=True)


def _last_summary(history: list[dict[str, Any]], step: int) -> dict[str, float] | None:
    if history and history[-1]["step"] == step:
        return {k: v for k, v in history[-1].items() if k not in ("step", "wall_s")}
    return None


class _Session:
    """The state of one :func:`train` call; its methods run in the order ``train`` calls
    them (the order of random draws is part of the bit-for-bit determinism)."""

    def __init__(self, settings: RunSettings, out: Path, ckpt: Path | None, state, quiet: bool):
        self.settings, self.out, self.ckpt, self.state, self.quiet = (
            settings,
            out,
            ckpt,
            state,
            quiet,
        )
        self.t_start = time.perf_counter()
        tasks = training_tasks(settings)
        self.task_cfgs = {t.name: t.config(settings.preset) for t in tasks or []}
        # one task: its config; a mix: the first task's (model metadata, run.json "config")
        self.cfg = (
            next(iter(self.task_cfgs.values()))
            if tasks
            else make_config(settings.preset, **settings.config_overrides())
        )
        #: evaluation configs by task name (one task: the name "")
        self.eval_cfgs = {t.name: t.config(settings.preset) for t in evaluation_tasks(settings)}
        self.eval_cfg = next(iter(self.eval_cfgs.values()))

        #: the targets each evaluation task is scored by (the ``eval_targets`` setting)
        self.targets = TARGETS[settings.eval_targets]
        self.history: list[dict[str, Any]] = list(state["history"]) if state else []
        self.wall_before = float(state.get("wall_s", 0.0)) if state else 0.0
        self.checkpointer = None

    def wall(self) -> float:
        return self.wall_before + time.perf_counter() - self.t_start

    # ------------------------------------------------------------------ env and model
    def build_model(self) -> None:
        self.venv = make_vec_env(self.settings)
        self.interface = self.venv.unwrapped.interface
        if self.state is None:
            self.model = build_model(self.settings, self.venv)
        else:
            self.model = load_model(self.settings, self.ckpt, self.venv)
            self.venv.unwrapped.set_state(self.state["env"])
            restore_monitor(self.venv, self.state["monitor"])
            set_rng_state(self.model, self.state["rng"])
        setattr(self.model, METADATA_KEY, metadata(self.settings, self.interface, self.cfg))
        self.start_steps = int(self.model.num_timesteps)

    def set_logger(self) -> None:
        logs = self.out / "logs"
        logs.mkdir(exist_ok=True)
        formats = [CSVOutputFormat(str(logs / f"progress_from_{self.start_steps:012d}.csv"))]
        if self.settings.tensorboard:
            formats.append(TensorBoardOutputFormat(str(self.out / "tensorboard")))
        self.model.set_logger(Logger(folder=str(logs), output_formats=formats))

    # ------------------------------------------------------------------ evaluation
    def baseline_summaries(self) -> dict[str, dict[str, float]]:
        """The analytic controllers on the evaluation seeds, computed once per run."""
        path, s = self.out / "eval_baselines.json", self.settings
        if self.state is not None and path.is_file():
            return json.loads(path.read_text(encoding="utf-8"))["summary"]
        summaries, all_rows = {}, []
        for name in s.eval_baselines:
            by_task = {
                task: evaluate_policy_rows(make_pair_policy(name, cfg), cfg, s.eval_seeds)
                for task, cfg in self.eval_cfgs.items()
            }
            summaries[name] = summarize_tasks(by_task, self.targets)
            all_rows += tagged_rows(by_task, policy=name)
        write_json(path, {"seeds": s.eval_seeds, "summary": summaries, "rows": all_rows})
        return summaries

    def evaluate(self):
        by_task, summary = evaluate_model(
            self.model, self.interface, self.eval_cfgs, self.settings.eval_seeds, self.targets
        )
        return tagged_rows(by_task), summary

    def on_result(self, step: int, rows, summary, improved: bool) -> None:
        self.history.append({"step": step, "wall_s": round(self.wall(), 1), **summary})
        columns = list(dict.fromkeys(k for r in self.history for k in r))
        write_csv(self.out / "eval.csv", self.history, columns)
        if improved:
            save_model_atomic(self.model, self.out / BEST_MODEL)
            record = {"step": step, "summary": summary, "seeds": self.settings.eval_seeds}
            write_json(self.out / "best_model.json", record)

    # ------------------------------------------------------------------ callbacks
    def make_callbacks(self, baselines: dict[str, dict[str, float]]) -> None:
        s, st = self.settings, self.state
        self.progress = ProgressCallback(s.total_steps, disable=self.quiet)
        # a new run evaluates its initial policy first; a resumed one keeps its schedule
        self.evaluator = EvalCallback(
            self.evaluate,
            baselines,
            s.eval_every,
            self.on_result,
            self.progress,
            next_eval=0 if st is None else st["next_eval"],
            best_score=st["best_score"] if st else math.inf,
            score=score_function(s),
        )
        next_save = s.checkpoint_every if st is None else st["next_checkpoint"]
        self.checkpointer = CheckpointCallback(self.save, s.checkpoint_every, next_save=next_save)

    def save(self, step: int) -> Path:
        extra = {
            "history": self.history,
            "next_eval": self.evaluator.next_eval,
            "best_score": self.evaluator.best_score,
            "next_checkpoint": self.checkpointer.next_save if self.checkpointer else step,
            "wall_s": self.wall(),
        }
        return save_checkpoint(
            self.out / "checkpoints", self.model, self.venv, extra, self.settings.keep_checkpoints
        )

    # ------------------------------------------------------------------ learning
    def start_record(self) -> None:
        mix = {}
        if is_mix(self.settings):  # every task's config (the first is "config" too)
            mix = {
                "task_configs": {k: c.to_dict() for k, c in self.task_cfgs.items()},
                "eval_task_configs": {k: c.to_dict() for k, c in self.eval_cfgs.items()},
            }
        self.record = run_record(
            settings=self.settings.to_dict(),
            config=self.cfg.to_dict(),
            eval_config=self.eval_cfg.to_dict(),
            interface=self.interface.to_dict(),
            seed=self.settings.seed,
            resumed_from=None if self.state is None else str(self.ckpt),
            start_steps=self.start_steps,
            status="running",
            **mix,
        )
        resumed = f"run_resumed_{self.start_steps:012d}.json"
        self.record_name = RUN_RECORD if self.state is None else resumed
        write_json(self.out / self.record_name, self.record)

    def learn(self, interrupt: Any) -> str:
        """Learn to the step target; a stop (Ctrl-C, time limit) ends at a rollout boundary,
        where the checkpoint written next resumes exactly."""
        s = self.settings
        time_limit = None if s.time_limit is None else s.time_limit * 60.0 - self.wall_before
        guard = GracefulInterrupt() if interrupt is None else contextlib.nullcontext(interrupt)
        with guard as interrupt:
            stopper = StopCallback(interrupt, time_limit, self.t_start)
            try:
                self.model.learn(
                    s.total_steps - self.start_steps,
                    callback=[stopper, self.progress, self.checkpointer, self.evaluator],
                    reset_num_timesteps=False,
                    progress_bar=False,
                )
            except StopTraining:
                self.progress.on_training_end()
        return stopper.reason or "completed"

    def finish(self, status: str, baselines) -> RunResult:
        """Final checkpoint, model and evaluation (also after Ctrl-C: nothing is lost)."""
        model = self.model
        ck = self.save(model.num_timesteps)
        save_model_atomic(model, self.out / FINAL_MODEL)
        final_summary = None
        if status == "completed":
            final_summary = _last_summary(self.history, model.num_timesteps)
            if final_summary is None:
                self.evaluator.num_timesteps = model.num_timesteps
                final_summary = self.evaluator.run_now()
        session_s = time.perf_counter() - self.t_start
        self.record.update(
            status=status,
            num_timesteps=int(model.num_timesteps),
            wall_s=round(self.wall(), 1),
            session_wall_s=round(session_s, 1),
            steps_per_s=round((model.num_timesteps - self.start_steps) / max(session_s, 1e-9), 1),
            last_checkpoint=str(ck),
            final_summary=final_summary,
            baselines=baselines,
        )
        write_json(self.out / self.record_name, self.record)
        if self.record_name != RUN_RECORD:
            self._update_run_record()
        self.venv.close()
        return RunResult(self.out, int(model.num_timesteps), status, self.wall(), final_summary)

    def _update_run_record(self) -> None:
        """After a resumed session, ``run.json`` says how the run stands now (its status,
        steps, time, last checkpoint and final evaluation) and names the session records;
        the first session's configuration stays as it was."""
        path = self.out / RUN_RECORD
        try:
            run = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):  # no readable record of the first session
            return
        for key in ("status", "num_timesteps", "wall_s", "last_checkpoint", "final_summary"):
            run[key] = self.record[key]
        run["resumed_sessions"] = [*run.get("resumed_sessions", []), self.record_name]
        write_json(path, run)


def _open(settings: RunSettings, out: Path, resume: Path | None, overwrite: bool):
    """(checkpoint, its state) to resume from, or (None, None) for a new run in a fresh
    ``out``; a resumed run that has reached its target gives a :class:`RunResult`."""
    if resume is None:
        _prepare_dir(out, overwrite)
        return None, None, None
    ckpt = latest_checkpoint(resume)
    state = load_checkpoint_state(ckpt)
    steps = int(state["num_timesteps"])
    if steps >= settings.total_steps:  # nothing to do, and nothing is written
        summary = _last_summary(list(state["history"]), steps)
        done = RunResult(out, steps, ALREADY_COMPLETE, float(state.get("wall_s", 0.0)), summary)
        return ckpt, state, done
    return ckpt, state, None


def train(
    settings: RunSettings,
    out: Path,
    *,
    resume: Path | None = None,
    quiet: bool = False,
    overwrite: bool = False,
    interrupt: Any = None,
) -> RunResult:
    """Train (or resume) a run in ``out``; see :mod:`train.cli` for the files written.

    ``resume``: the run (or checkpoint) to continue; if it already reached
    ``settings.total_steps`` nothing is changed and the status is ``"already complete"``.
    ``interrupt``: a :class:`~train.callbacks.GracefulInterrupt` already installed by the
    caller (the CLI installs it first thing, so Ctrl-C during setup also stops cleanly); by
    default one is installed around learning. A stop (Ctrl-C, time limit) takes effect at
    the end of the current rollout, so the run resumes exactly where it stopped.
    """
    pin_threads()
    out = Path(out)
    ckpt, state, done = _open(settings, out, resume, overwrite)
    if done is not None:
        return done
    session = _Session(settings, out, ckpt, state, quiet)
    _write_settings(out, settings)
    session.build_model()
    session.set_logger()
    baselines = session.baseline_summaries()
    session.make_callbacks(baselines)
    session.start_record()
    status = session.learn(interrupt)
    return session.finish(status, baselines)
