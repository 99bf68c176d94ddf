"""The local backend of ``python -m train.sweep``: trials in worker processes, no Ray.

Each trial runs in its own ``python -m train.sweep.worker`` process (fresh interpreter, one
torch/BLAS thread), at most ``max_concurrent`` at a time, in the order of the plan. Workers
run in their own process group so that a Ctrl-C reaches each of them exactly once, through
the sweep: the first Ctrl-C stops every running trial cleanly (checkpoint, final model) and
starts no new one; a second one aborts the running trials at once; a third kills them.
A worker whose sweep process dies stops itself the same clean way.
"""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from train.sweep.plan import Trial
from train.sweep.trial import finished_result

__all__ = ["Outcome", "Progress", "run_local"]


class Progress:
    """Trials done / running / failed on the terminal (a tqdm bar on stderr)."""

    def __init__(self, total: int, done: int = 0, disable: bool = False) -> None:
        self.running: set[str] = set()
        self.started: list[str] = []
        self.failed = 0
        self.total = total
        self.done = done
        # a log file gets one plain line per event instead of a redrawn bar
        self.lines = not disable and not sys.stderr.isatty()
        self.bar = tqdm(
            total=total,
            initial=done,
            desc="sweep",
            unit="trial",
            disable=disable or self.lines,
            dynamic_ncols=True,
        )
        self._refresh()

    def _refresh(self, event: str = "") -> None:
        state = f"running {len(self.running)}, failed {self.failed}"
        self.bar.set_postfix_str(state)
        if self.lines and event:
            print(f"sweep: {event}; {self.done}/{self.total} done, {state}", file=sys.stderr)

    def start(self, name: str) -> None:
        """A trial started."""
        self.running.add(name)
        self.started.append(name)
        self._refresh(f"{name} started")

    def finish(self, name: str) -> None:
        """A trial finished with a result."""
        self.running.discard(name)
        self.done += 1
        self.bar.update(1)
        self._refresh(f"{name} finished")

    def fail(self, name: str, why: str) -> None:
        """A trial failed (counted, and said on the terminal)."""
        self.running.discard(name)
        self.failed += 1
        self.bar.write(f"trial {name} failed: {why}", file=sys.stderr)
        self._refresh(f"{name} failed")

    def stop(self, name: str) -> None:
        """A trial stopped before the end (it resumes with the sweep)."""
        self.running.discard(name)
        self._refresh(f"{name} stopped")

    def close(self) -> None:
        """Leave the final line on the terminal."""
        self.bar.close()


@dataclasses.dataclass
class Outcome:
    """What a backend ran: results by trial name, failures (name -> reason), interrupted."""

    results: dict[str, dict[str, Any]] = dataclasses.field(default_factory=dict)
    failed: dict[str, str] = dataclasses.field(default_factory=dict)
    interrupted: bool = False


class _Interrupts:
    """Counts Ctrl-C (SIGINT) and SIGTERM in the sweep process while the backend runs."""

    def __init__(self) -> None:
        self.count = 0
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> _Interrupts:
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum, frame) -> None:
        self.count += 1

    def __exit__(self, *exc) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


def _worker_env() -> dict[str, str]:
    root = str(Path(__file__).resolve().parents[1])
    path = os.environ.get("PYTHONPATH")
    env = {**os.environ, "PYTHONPATH": root if not path else f"{root}{os.pathsep}{path}"}
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        env.setdefault(var, "1")
    return env


def _launch(trial: Trial, sweep_dir: Path, env: dict[str, str]):
    log_path = sweep_dir / "logs" / f"{trial.name.replace('/', '__')}.log"
    log_path.parent.mkdir(parents=True, exist_ok=True)
    log = open(log_path, "ab")  # noqa: SIM115 (closed when the worker ends)
    proc = subprocess.Popen(
        [sys.executable, "-m", "train.sweep.worker", str(sweep_dir), trial.name],
        stdin=subprocess.DEVNULL,
        stdout=log,
        stderr=subprocess.STDOUT,
        env=env,
        start_new_session=True,  # Ctrl-C reaches it only through the sweep (exactly once)
    )
    return proc, log, log_path


def _signal_all(running: dict[str, tuple], level: int) -> None:
    sig = signal.SIGKILL if level >= 3 else signal.SIGINT
    for proc, _, _ in running.values():
        if proc.poll() is None:
            proc.send_signal(sig)


def run_local(
    trials: Sequence[Trial],
    sweep_dir: Path,
    max_concurrent: int,
    progress: Progress,
    poll_s: float = 0.2,
) -> Outcome:
    """Run ``trials`` in worker processes; returns when all ended or after an interrupt."""
    sweep_dir = Path(sweep_dir).resolve()
    env = _worker_env()
    pending, running, out = list(trials), {}, Outcome()
    by_name = {t.name: t for t in trials}
    forwarded = 0
    with _Interrupts() as stop:
        while running or (pending and not stop.count):
            if stop.count > forwarded:
                forwarded = stop.count
                _signal_all(running, forwarded)
            while pending and len(running) < max_concurrent and not stop.count:
                t = pending.pop(0)
                running[t.name] = _launch(t, sweep_dir, env)
                progress.start(t.name)
            for name, (proc, log, log_path) in list(running.items()):
                rc = proc.poll()
                if rc is None:
                    continue
                log.close()
                del running[name]
                result = finished_result(by_name[name], sweep_dir) if rc == 0 else None
                if result is not None:
                    out.results[name] = result
                    progress.finish(name)
                elif stop.count or rc in (130, -signal.SIGINT):
                    progress.stop(name)
                else:
                    out.failed[name] = f"exit status {rc}; log: {log_path}"
                    progress.fail(name, out.failed[name])
            time.sleep(poll_s)
        out.interrupted = stop.count > 0
    return out
