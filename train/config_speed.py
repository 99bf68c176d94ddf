"""Training speed of run configs (``python -m train.throughput --config A.yaml --config B.yaml``).

For each settings file, the run's own VecEnv (one task, or the concatenated task envs of a
mix) and model are built as ``python -m train`` builds them; after a warm-up of one rollout
and update, ``model.learn`` is timed for ``--steps`` decisions, in CPU time of this process
(one thread: what a dedicated core gives, and far steadier than wall time on a shared machine)
and in wall time. The configs alternate ``--repeats`` times; medians are reported. One
periodic evaluation (the policy on every evaluation task and seed, full episodes) is timed
too, and the whole run is estimated as ``total_steps`` / rate + evaluations + baselines.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["estimate_run_s", "measure_config", "run_configs"]


def _settings(path: Path):
    from train.settings import load_yaml, settings_from_sources

    return settings_from_sources(load_yaml(path))


def measure_config(path: Path, steps: int) -> dict[str, float]:
    """Decisions per CPU second and per wall second of ``model.learn`` for the config at
    ``path`` (after a warm-up), and the CPU seconds of one evaluation."""
    from baselines.controllers.sb3 import SB3PairPolicy
    from train.model import build_model
    from train.run import evaluate_policy_rows, make_vec_env
    from train.tasks import evaluation_tasks

    s = _settings(path)
    venv = make_vec_env(s)
    model = build_model(s, venv)
    n_steps = s.algo_hyperparameters().get("n_steps", 2)
    model.learn(n_steps * venv.num_envs)  # warm-up: JIT, allocations, first update
    start, c0, w0 = model.num_timesteps, time.process_time(), time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    done = model.num_timesteps - start
    iface = venv.unwrapped.interface.to_dict()
    c0 = time.process_time()
    for task in evaluation_tasks(s):
        cfg = task.config(s.preset)
        evaluate_policy_rows(SB3PairPolicy(model, cfg, iface), cfg, s.eval_seeds)
    eval_s = time.process_time() - c0
    venv.close()
    return {"rows": venv.num_envs, "cpu": done / cpu, "wall": done / wall, "eval_cpu_s": eval_s}


def estimate_run_s(settings: Any, rate: float, eval_s: float) -> float:
    """CPU seconds of the whole run: learning at ``rate`` decisions/s, every periodic and the
    final evaluation, and the baselines (about one evaluation each, once)."""
    n_evals = 1
    if settings.eval_every > 0:
        n_evals = 1 + settings.total_steps // settings.eval_every
        n_evals += int(settings.total_steps % settings.eval_every != 0)
    return settings.total_steps / rate + (n_evals + len(settings.eval_baselines)) * eval_s


def run_configs(paths: Sequence[Path], steps: int, repeats: int) -> dict[str, Any]:
    """Every config, alternating, ``repeats`` times; per config the medians and the estimate."""
    from tqdm import tqdm

    raw: dict[str, list[dict[str, float]]] = {str(p): [] for p in paths}
    with tqdm(total=repeats * len(paths), desc="throughput", unit="run") as bar:
        for _ in range(repeats):
            for p in paths:
                raw[str(p)].append(measure_config(Path(p), steps))
                bar.update()
    out: dict[str, Any] = {}
    for p, ms in raw.items():
        med = {k: statistics.median(m[k] for m in ms) for k in ("cpu", "wall", "eval_cpu_s")}
        s = _settings(Path(p))
        out[p] = {
            "rows": ms[0]["rows"],
            "measurements": ms,
            "median": med,
            "total_steps": s.total_steps,
            "estimated_run_cpu_min": estimate_run_s(s, med["cpu"], med["eval_cpu_s"]) / 60,
        }
    return out


def report(results: dict[str, Any], steps: int, repeats: int) -> str:
    """The terminal lines of :func:`run_configs`'s results."""
    lines = [f"model.learn, {steps} decisions per measurement, median of {repeats}:"]
    for p, r in results.items():
        m = r["median"]
        lines.append(
            f"  {Path(p).stem}: {r['rows']} rows, {m['cpu']:.0f} decisions/CPU-s "
            f"({m['wall']:.0f}/wall-s here), one evaluation {m['eval_cpu_s']:.1f} CPU-s; "
            f"{r['total_steps']:.3g} decisions ~ {r['estimated_run_cpu_min']:.1f} min on one core"
        )
    return "\n".join(lines)
