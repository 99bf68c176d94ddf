"""One training run: environment, model, callbacks, checkpoints, evaluation, run record.

Used by the CLI (:mod:`train.cli`); importable for notebooks and tests::

    from train.settings import settings_from_sources
    from train.run import train
    result = train(settings_from_sources(flags={"total_steps": 2000}), Path("runs/smoke"))
"""

from __future__ import annotations

import dataclasses
import math
import os
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np

from baselines.evaluation.parallel import pin_threads

from .settings import RunSettings

__all__ = ["METADATA_KEY", "RunResult", "evaluate_policy_rows", "make_vec_env", "train"]

METADATA_KEY = "pairflock"
FINAL_MODEL = "final_model.zip"
BEST_MODEL = "best_model.zip"


@dataclasses.dataclass
class RunResult:
    out: Path
    num_timesteps: int
    status: str  # "completed" | "interrupted (Ctrl-C)" | "time limit ..."
    wall_s: float
    final_summary: dict[str, float] | None

    @property
    def interrupted(self) -> bool:
        return self.status.startswith("interrupted")


def make_vec_env(settings: RunSettings, seed_offset: int = 0):
    """The native SB3 VecEnv of the training task, wrapped in a VecMonitor."""
    from stable_baselines3.common.vec_env import VecMonitor

    from pairflock_env.envs.sb3 import PairFlockVecEnv

    ss = np.random.SeedSequence([settings.seed, seed_offset])
    env = PairFlockVecEnv(
        settings.preset,
        num_swarms=settings.num_swarms,
        seed=ss,
        frame=settings.frame,
        frame_params=settings.frame_params,
        **settings.config_overrides(),
    )
    return VecMonitor(env)


def linear_schedule(start: float):
    """SB3 schedule falling linearly from ``start`` to 0 over training (rl-zoo's ``lin_<v>``)."""

    def schedule(progress_remaining: float) -> float:
        return progress_remaining * start

    schedule.start = start  # type: ignore[attr-defined]
    return schedule


def resolve_schedules(hp: dict[str, Any]) -> dict[str, Any]:
    """``"lin_3e-4"`` for learning_rate / clip_range means a linear decay from 3e-4 to 0."""
    out = dict(hp)
    for key in ("learning_rate", "clip_range"):
        v = out.get(key)
        if isinstance(v, str) and v.startswith("lin_"):
            try:
                start = float(v[4:])
            except ValueError:
                raise ValueError(
                    f"hyperparameter {key}={v!r} is invalid: use lin_<number>"
                ) from None
            if start <= 0:
                raise ValueError(f"hyperparameter {key}={v!r} is invalid: the start must be > 0")
            out[key] = linear_schedule(start)
    return out


def _build_model(settings: RunSettings, venv):
    import stable_baselines3 as sb3

    hp = resolve_schedules(settings.algo_hyperparameters())
    cls = getattr(sb3, settings.algo.upper())
    if settings.algo == "td3":
        from stable_baselines3.common.noise import NormalActionNoise

        std = float(hp.pop("action_noise_std"))
        D = venv.action_space.shape[0]
        hp["action_noise"] = NormalActionNoise(np.zeros(D), std * np.ones(D))
    return cls("MlpPolicy", venv, seed=settings.seed, device="cpu", verbose=0, **hp)


def evaluate_policy_rows(policy: Any, cfg: Any, seeds: list[int]) -> list[dict[str, Any]]:
    """Metrics per seed of ``policy`` on ``cfg`` with the baselines' rollout code."""
    from baselines.evaluation.rollout import rollout, trace_metrics

    return trace_metrics(rollout(cfg, policy, seeds))


def _metadata(settings: RunSettings, interface: Any, cfg: Any) -> dict[str, Any]:
    return {
        "algo": settings.algo.upper(),
        "interface": interface.to_dict(),
        "config": cfg.to_dict(),
        "settings": settings.to_dict(),
    }


def _write_settings(out: Path, settings: RunSettings) -> None:
    import yaml

    from baselines.evaluation.io import atomic_write_text

    text = yaml.safe_dump(settings.to_dict(), sort_keys=False, default_flow_style=None)
    atomic_write_text(out / "settings.yaml", text)


def _csv_rows_text(rows: list[dict[str, Any]]) -> str:
    import csv
    import io

    from baselines.evaluation.io import format_value

    cols: list[str] = []
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: format_value(r.get(k)) for k in cols})
    return buf.getvalue()


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

    ``interrupt``: a :class:`~train.callbacks.GracefulInterrupt` already installed by the
    caller (the CLI installs it first thing, so Ctrl-C during setup also stops cleanly); by
    default one is installed around learning.
    """
    pin_threads(load_torch=True)
    import stable_baselines3 as sb3
    from stable_baselines3.common.logger import CSVOutputFormat, Logger, TensorBoardOutputFormat

    from baselines import make_pair_policy
    from baselines.controllers.sb3 import SB3PairPolicy
    from baselines.evaluation.io import atomic_write_text, run_record, write_json
    from pairflock_env import make_config

    from .callbacks import (
        CheckpointCallback,
        EvalCallback,
        GracefulInterrupt,
        ProgressCallback,
        StopCallback,
        summarize_metrics,
    )
    from .checkpoint import (
        latest_checkpoint,
        load_checkpoint_state,
        restore_monitor,
        save_checkpoint,
        set_rng_state,
    )

    out = Path(out)
    t_start = time.perf_counter()
    cfg = make_config(settings.preset, **settings.config_overrides())
    eval_cfg = make_config(settings.preset, **settings.eval_overrides())

    # ------------------------------------------------------------------ run directory
    ckpt_state = None
    if resume is not None:
        ckpt = latest_checkpoint(resume)
        ckpt_state = load_checkpoint_state(ckpt)
    else:
        if out.exists() and any(out.iterdir()):
            if not overwrite:
                raise FileExistsError(
                    f"--out {str(out)!r} is not empty; pass --overwrite to replace it or "
                    f"--resume {str(out)!r} to continue it"
                )
            shutil.rmtree(out)
        out.mkdir(parents=True, exist_ok=True)
    _write_settings(out, settings)

    # ------------------------------------------------------------------ env and model
    venv = make_vec_env(settings)
    interface = venv.unwrapped.interface
    algo_cls = getattr(sb3, settings.algo.upper())
    if ckpt_state is None:
        model = _build_model(settings, venv)
        wall_before = 0.0
    else:
        # force_reset=False keeps the saved last observation: the env continues, not resets
        model = algo_cls.load(str(ckpt / "model.zip"), env=venv, device="cpu", force_reset=False)
        if (ckpt / "replay_buffer.pkl").is_file():
            model.load_replay_buffer(str(ckpt / "replay_buffer.pkl"))
        venv.unwrapped.set_state(ckpt_state["env"])
        restore_monitor(venv, ckpt_state["monitor"])
        set_rng_state(model, ckpt_state["rng"])
        wall_before = float(ckpt_state.get("wall_s", 0.0))
    setattr(model, METADATA_KEY, _metadata(settings, interface, cfg))
    start_steps = int(model.num_timesteps)

    # ------------------------------------------------------------------ logging
    logs = out / "logs"
    logs.mkdir(exist_ok=True)
    formats = [CSVOutputFormat(str(logs / f"progress_from_{start_steps:012d}.csv"))]
    if settings.tensorboard:
        formats.append(TensorBoardOutputFormat(str(out / "tensorboard")))
    model.set_logger(Logger(folder=str(logs), output_formats=formats))

    # ------------------------------------------------------------------ evaluation
    base_path = out / "eval_baselines.json"
    if ckpt_state is not None and base_path.is_file():
        import json

        baselines = json.loads(base_path.read_text(encoding="utf-8"))["summary"]
    else:
        baselines, base_rows = {}, []
        for name in settings.eval_baselines:
            rows = evaluate_policy_rows(
                make_pair_policy(name, eval_cfg), eval_cfg, settings.eval_seeds
            )
            baselines[name] = summarize_metrics(rows)
            base_rows += [{"policy": name, **r} for r in rows]
        write_json(
            base_path, {"seeds": settings.eval_seeds, "summary": baselines, "rows": base_rows}
        )

    history: list[dict[str, Any]] = list(ckpt_state["history"]) if ckpt_state else []

    def evaluate():
        pol = SB3PairPolicy(model, eval_cfg, interface.to_dict())
        rows = evaluate_policy_rows(pol, eval_cfg, settings.eval_seeds)
        return rows, summarize_metrics(rows)

    def on_result(step: int, rows, summary, improved: bool) -> None:
        history.append({"step": step, "wall_s": round(wall(), 1), **summary})
        atomic_write_text(out / "eval.csv", _csv_rows_text(history))
        if improved:
            _save_model_atomic(model, out / BEST_MODEL)
            write_json(
                out / "best_model.json",
                {"step": step, "summary": summary, "seeds": settings.eval_seeds},
            )

    def wall() -> float:
        return wall_before + time.perf_counter() - t_start

    progress = ProgressCallback(settings.total_steps, disable=quiet)
    # a new run evaluates its initial policy first; a resumed one keeps its schedule
    evaluator = EvalCallback(
        evaluate,
        baselines,
        settings.eval_every,
        on_result,
        progress,
        next_eval=0 if ckpt_state is None else ckpt_state["next_eval"],
        best_score=ckpt_state["best_score"] if ckpt_state else math.inf,
    )
    checkpointer = None

    def save(step: int) -> Path:
        return save_checkpoint(
            out / "checkpoints",
            model,
            venv,
            {
                "history": history,
                "next_eval": evaluator.next_eval,
                "best_score": evaluator.best_score,
                "next_checkpoint": checkpointer.next_save if checkpointer else step,
                "wall_s": wall(),
            },
            settings.keep_checkpoints,
        )

    checkpointer = CheckpointCallback(
        save,
        settings.checkpoint_every,
        next_save=settings.checkpoint_every
        if ckpt_state is None
        else ckpt_state["next_checkpoint"],
    )

    record = run_record(
        settings=settings.to_dict(),
        config=cfg.to_dict(),
        eval_config=eval_cfg.to_dict(),
        interface=interface.to_dict(),
        seed=settings.seed,
        resumed_from=None if ckpt_state is None else str(ckpt),
        start_steps=start_steps,
        status="running",
    )
    record_name = "run.json" if ckpt_state is None else f"run_resumed_{start_steps:012d}.json"
    write_json(out / record_name, record)

    # ------------------------------------------------------------------ learn
    remaining = settings.total_steps - start_steps
    status = "completed"
    time_limit = None if settings.time_limit is None else settings.time_limit * 60.0 - wall_before
    import contextlib

    guard = GracefulInterrupt() if interrupt is None else contextlib.nullcontext(interrupt)
    with guard as interrupt:
        stopper = StopCallback(interrupt, time_limit, t_start)
        if remaining > 0:
            model.learn(
                remaining,
                callback=[stopper, progress, checkpointer, evaluator],
                reset_num_timesteps=False,
                progress_bar=False,
            )
        else:
            progress.disable = True
        if stopper.reason is not None:
            status = stopper.reason
    # final checkpoint, model and evaluation (also after Ctrl-C: nothing is lost)
    ck = save(model.num_timesteps)
    _save_model_atomic(model, out / FINAL_MODEL)
    final_summary = None
    if status == "completed":
        if evaluator.model is None:
            evaluator.init_callback(model)
        evaluator.num_timesteps = model.num_timesteps
        if not history or history[-1]["step"] != model.num_timesteps:
            final_summary = evaluator.run_now()
        else:
            final_summary = {k: v for k, v in history[-1].items() if k not in ("step", "wall_s")}
    record.update(
        status=status,
        num_timesteps=int(model.num_timesteps),
        wall_s=round(wall(), 1),
        session_wall_s=round(time.perf_counter() - t_start, 1),
        steps_per_s=round(
            (model.num_timesteps - start_steps) / max(time.perf_counter() - t_start, 1e-9), 1
        ),
        last_checkpoint=str(ck),
        final_summary=final_summary,
        baselines=baselines,
    )
    write_json(out / record_name, record)
    venv.close()
    return RunResult(out, int(model.num_timesteps), status, wall(), final_summary)


def _save_model_atomic(model: Any, path: Path) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.zip")
    model.save(tmp)
    os.replace(tmp, path)
