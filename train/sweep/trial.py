"""One trial of a sweep: train (or resume) its run directory, then collect its result.

Both backends call :func:`run_trial`: the local one in a worker process
(``python -m train.sweep.worker SWEEP_DIR TRIAL_NAME``), the Ray one inside a Tune trial.
A trial's run directory is an ordinary ``python -m train`` run directory (resumable with
``python -m train --resume``); the sweep adds two files to it:

* ``sweep_eval_final.csv``: the final model on every evaluation seed (one row per seed),
  the rows the acceptance aims are judged on;
* ``sweep_trial.json``: the trial's result (final and best evaluation summaries, the
  evaluation curve, the aims met, wall times). Written last: its presence means done.

A trial that is started again continues where its run stopped: from the newest checkpoint
if there is one, straight to the result if training had finished, and not at all if its
result is already there (and was computed for the same trial definition).
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from baselines import make_pair_policy
from baselines.reporting.criteria import LEARNED, TARGETS, check_learned
from baselines.runtime.cli import ArgumentParser
from baselines.runtime.files import write_csv, write_json
from baselines.runtime.threads import pin_threads
from train.callbacks import GracefulInterrupt
from train.checkpoint import latest_checkpoint
from train.mix.evaluation import score_function, tagged_rows
from train.mix.tasks import evaluation_tasks, is_mix
from train.run import evaluate_policy_rows, train
from train.settings import settings_from_sources
from train.sweep.plan import SWEEP_FILE, Trial

try:
    import fcntl
except ImportError:  # not POSIX
    fcntl = None

__all__ = [
    "FINAL_ROWS",
    "RESULT_FILE",
    "aims",
    "finished_result",
    "result_scalars",
    "run_trial",
    "task_aims",
    "worker_main",
]

RESULT_FILE = "sweep_trial.json"
FINAL_ROWS = "sweep_eval_final.csv"


def finished_result(trial: Trial, sweep_dir: Path) -> dict[str, Any] | None:
    """The stored result of ``trial`` if it finished with this very definition, else None."""
    path = Path(sweep_dir) / trial.run_dir / RESULT_FILE
    if not path.is_file():
        return None
    try:
        result = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return result if result.get("spec_hash") == trial.spec_hash else None


def _newest_record(run_dir: Path) -> dict[str, Any] | None:
    """run.json, or the newest run_resumed_<N>.json after resumes."""
    names = sorted(run_dir.glob("run_resumed_*.json"))
    path = names[-1] if names else run_dir / "run.json"
    if not path.is_file():
        return None
    return json.loads(path.read_text(encoding="utf-8"))


def _has_checkpoint(run_dir: Path) -> bool:
    try:
        latest_checkpoint(run_dir)
    except FileNotFoundError:
        return False
    return True


def _train(trial: Trial, run_dir: Path, settings, interrupt) -> str:
    """Train or resume the run; its final status."""
    record = _newest_record(run_dir) if run_dir.is_dir() else None
    if (
        record is not None
        and record.get("status") == "completed"
        and int(record.get("num_timesteps", -1)) >= settings.total_steps
    ):
        return "completed"  # trained already; only the result is missing
    resume = run_dir if run_dir.is_dir() and _has_checkpoint(run_dir) else None
    # a run directory without a checkpoint holds nothing worth keeping: start it afresh
    res = train(
        settings, run_dir, resume=resume, quiet=True, overwrite=resume is None, interrupt=interrupt
    )
    return res.status


def _final_rows(run_dir: Path, settings) -> tuple[dict[str, list[dict[str, Any]]], dict]:
    """The final model evaluated on each evaluation seed of every evaluation task (the rows
    the aims judge), and the tasks' configs, both by task name (one task: the name "")."""
    rows, cfgs = {}, {}
    for task in evaluation_tasks(settings):
        cfg = cfgs[task.name] = task.config(settings.preset)
        policy = make_pair_policy(f"sb3:{run_dir / 'final_model.zip'}", cfg)
        rows[task.name] = evaluate_policy_rows(policy, cfg, settings.eval_seeds)
    return rows, cfgs


def aims(rows: list[dict[str, Any]], cfg: Any, targets: Any = None) -> list[dict[str, Any]]:
    """Which of the project's acceptance aims the evaluation ``rows`` meet.

    The thresholds are the project's (:func:`baselines.reporting.criteria.check_learned`;
    ``targets``, default ``LEARNED``, e.g. a run's ``eval_targets``), judged at the evaluation
    task's swarm size and start; each entry is ``{criterion, met, measured}``, with the
    criterion's task prefix (``N=20 corners:``) dropped so that settings share names.
    """
    tagged = [{**r, "policy": "learned", "n_uavs": cfg.n_uavs, "init": cfg.init} for r in rows]
    out = []
    checks = check_learned(tagged, n_uavs=cfg.n_uavs, init=cfg.init, targets=targets or LEARNED)
    for criterion, ok, measured in checks:
        out.append(
            {"criterion": criterion.split(": ", 1)[-1], "met": bool(ok), "measured": measured}
        )
    return out


def task_aims(
    rows: dict[str, list[dict[str, Any]]], cfgs: dict[str, Any], targets: Any = None
) -> list[dict]:
    """:func:`aims` of every evaluation task, named ``<task>: <criterion>``, then
    ``every task: <criterion>`` (met when every task meets it); one task (the name ""):
    :func:`aims` of its rows, unchanged."""
    if list(rows) == [""]:
        return aims(rows[""], cfgs[""], targets)
    per = {name: aims(r, cfgs[name], targets) for name, r in rows.items()}
    out = [{**a, "criterion": f"{name}: {a['criterion']}"} for name, s in per.items() for a in s]
    for criterion in dict.fromkeys(a["criterion"] for s in per.values() for a in s):
        missed = [
            n for n, s in per.items() for a in s if a["criterion"] == criterion and not a["met"]
        ]
        measured = "every task" if not missed else f"missed on {', '.join(missed)}"
        out.append(
            {"criterion": f"every task: {criterion}", "met": not missed, "measured": measured}
        )
    return out


def _read_curve(run_dir: Path) -> list[dict[str, float]]:
    path = run_dir / "eval.csv"
    if not path.is_file():
        return []
    with open(path, encoding="utf-8") as f:
        return [
            {k: float(v) for k, v in r.items() if k != "wall_s" and v not in ("", None)}
            for r in csv.DictReader(f)
        ]


def collect(trial: Trial, run_dir: Path, settings) -> dict[str, Any]:
    """The result of a trained trial (see the module docstring)."""
    record = _newest_record(run_dir) or {}
    best_path = run_dir / "best_model.json"
    best = json.loads(best_path.read_text(encoding="utf-8")) if best_path.is_file() else {}
    rows, cfgs = _final_rows(run_dir, settings)
    write_csv(run_dir / FINAL_ROWS, tagged_rows(rows))
    final = dict(record.get("final_summary") or {})
    if final and "score" not in final:
        # the final evaluation's summary carries no score when it ran after the last step
        final["score"] = score_function(settings)(final)
    tasks = {"eval_tasks": list(rows)} if is_mix(settings) else {}
    return {
        "trial": trial.name,
        "setting": trial.setting,
        "label": trial.label,
        "assignments": trial.assignments,
        "seed": trial.seed,
        "spec_hash": trial.spec_hash,
        "status": record.get("status", "unknown"),
        "num_timesteps": int(record.get("num_timesteps", 0)),
        "final": final,
        "best": best.get("summary", {}),
        "best_step": best.get("step"),
        "aims": task_aims(rows, cfgs, TARGETS[settings.eval_targets]),
        "curve": _read_curve(run_dir),
        **tasks,
        # the longest evaluation episode: what a never-reached band time counts as
        "eval_horizon_s": max(float(c.horizon) for c in cfgs.values()),
        "wall_train_s": float(record.get("wall_s", 0.0)),
    }


def result_scalars(result: dict[str, Any]) -> dict[str, float]:
    """The numbers of a result by column name: ``final_<summary key>``, ``best_<summary
    key>``, ``best_step`` and ``aims_met`` (how many aims the final model meets)."""
    out: dict[str, float] = {}
    for part in ("final", "best"):
        for k, v in (result.get(part) or {}).items():
            out[f"{part}_{k}"] = float(v)
    if result.get("best_step") is not None:
        out["best_step"] = float(result["best_step"])
    out["aims_met"] = float(sum(a["met"] for a in result.get("aims", [])))
    return out


def run_trial(trial: Trial | dict[str, Any], sweep_dir: Path, interrupt: Any = None) -> dict:
    """Run one trial to completion (or until ``interrupt`` asks to stop) and return its result.

    The result of a finished trial is ``sweep_trial.json``; an interrupted trial returns
    ``{"trial": name, "status": "interrupted ..."}`` and writes no result, so that the next
    start resumes it.
    """
    pin_threads()
    trial = trial if isinstance(trial, Trial) else Trial.from_dict(trial)
    with _exclusive(Path(sweep_dir), trial):
        done = finished_result(trial, sweep_dir)
        if done is not None:
            return done
        t0 = time.perf_counter()
        run_dir = Path(sweep_dir) / trial.run_dir
        settings = settings_from_sources(trial.settings)
        status = _train(trial, run_dir, settings, interrupt)
        if status != "completed":
            return {"trial": trial.name, "status": status}
        result = collect(trial, run_dir, settings)
        result["wall_trial_s"] = round(time.perf_counter() - t0, 2)
        write_json(run_dir / RESULT_FILE, result)
    return result


@contextlib.contextmanager
def _exclusive(sweep_dir: Path, trial: Trial, wait_s: float = 120.0) -> Iterator[None]:
    """Hold the trial's lock file: a worker of an earlier, killed sweep session may still be
    writing its last checkpoint when the sweep is resumed; the new one waits for it."""
    if fcntl is None:  # no POSIX locks: nothing to guard with
        yield
        return
    path = sweep_dir / ".locks" / f"{trial.name.replace('/', '__')}.lock"
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a", encoding="utf-8") as f:
        deadline = time.monotonic() + wait_s
        while True:
            try:
                fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise RuntimeError(
                        f"trial {trial.name} is being run by another process (lock {path})"
                    ) from None
                time.sleep(0.5)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _watch_parent(parent: int) -> None:
    """Stop cleanly (as on Ctrl-C) if the sweep process that started this worker dies."""

    def loop() -> None:
        while os.getppid() == parent:
            time.sleep(1.0)
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=loop, name="sweep-parent-watch", daemon=True).start()


def worker_main(argv: Sequence[str] | None = None) -> int:
    """Worker of the local backend (``python -m train.sweep.worker SWEEP_DIR NAME``): run the
    trial NAME of the sweep in SWEEP_DIR; exit status 0 (done), 130 (stopped), 2 (bad input)."""
    parser = ArgumentParser(prog="python -m train.sweep.worker", description="one sweep trial")
    parser.add_argument("sweep_dir", type=Path, help="the sweep's directory")
    parser.add_argument("trial", help="the trial's name, e.g. default/seed_0")
    args = parser.parse_args(argv)
    sweep_dir, name = args.sweep_dir, args.trial
    stored = json.loads((sweep_dir / SWEEP_FILE).read_text(encoding="utf-8"))
    match = [t for t in stored["trials"] if t["name"] == name]
    if not match:
        parser.error(f"trial {name!r} is not in {sweep_dir / SWEEP_FILE}")
    _watch_parent(os.getppid())
    with GracefulInterrupt() as interrupt:
        result = run_trial(match[0], sweep_dir, interrupt)
    print(f"{name}: {result['status']}", file=sys.stderr)
    return 0 if result["status"] == "completed" else 130
