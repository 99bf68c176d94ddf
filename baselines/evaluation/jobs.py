"""Jobs of a benchmark grid and the backends that run them (local processes or Ray).

A job is one (scenario, policy) over a block of seeds, run as one batched core through
:func:`baselines.evaluation.rollout.rollout`. A swarm's result depends only on its config,
policy and seed (each swarm has its own generator; nothing in a step mixes swarms), so it does not
matter how seeds are grouped into jobs or where a job runs: the local and the Ray backend
return identical numbers, and ``tests/test_benchmark.py`` checks both properties.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from baselines.evaluation.recording import RecordOptions, recorded_rollout
from baselines.evaluation.rollout import trace_metrics
from baselines.evaluation.specs import PolicySpec
from baselines.runtime import optional
from baselines.runtime.pool import imap_unordered
from baselines.runtime.threads import pin_threads
from pairflock_env import PairFlockConfig

__all__ = ["BACKENDS", "Job", "make_jobs", "run_job", "run_jobs"]

BACKENDS = ("local", "ray")


@dataclasses.dataclass(frozen=True)
class Job:
    """One (scenario, policy) over ``seeds``; ``record_seed`` (if any) keeps its trajectory
    every ``record_stride`` control steps for figures and video; ``recording`` (if any)
    writes the run's recordings (:mod:`baselines.evaluation.recording`)."""

    scenario: int
    policy: int
    config: PairFlockConfig
    spec: PolicySpec
    seeds: tuple[int, ...]
    record_seed: int | None = None
    record_stride: int = 1
    metric_kwargs: tuple[tuple[str, Any], ...] = ()
    recording: RecordOptions | None = None

    @property
    def cost(self) -> float:
        """Rough relative cost, to start the slowest jobs first."""
        c = self.config
        return len(self.seeds) * c.episode_steps * c.n_uavs * c.n_uavs


def make_jobs(
    configs: Sequence[PairFlockConfig],
    specs: Sequence[PolicySpec],
    seeds: Sequence[int],
    *,
    batch_size: int | None = None,
    record: Callable[[int, int], bool] = lambda i, j: False,
    record_stride: Callable[[PairFlockConfig], int] = lambda cfg: 1,
    metric_kwargs: dict[str, Any] | None = None,
    recording: Callable[[int, int], RecordOptions | None] = lambda i, j: None,
) -> list[Job]:
    """Every (scenario i, policy j) x seed block; the first seed is recorded where
    ``record(i, j)``, the recordings written as ``recording(i, j)`` says. Every policy gets
    the same seeds, hence the same initial states."""
    seeds = tuple(int(s) for s in seeds)
    bs = len(seeds) if batch_size is None else int(batch_size)
    if bs < 1:
        raise ValueError(f"batch_size={batch_size!r} is invalid: must be >= 1")
    mk = tuple(sorted((metric_kwargs or {}).items()))
    jobs = []
    for i, cfg in enumerate(configs):
        for j, spec in enumerate(specs):
            for start in range(0, len(seeds), bs):
                block = seeds[start : start + bs]
                rec = seeds[0] if (start == 0 and record(i, j)) else None
                jobs.append(
                    Job(i, j, cfg, spec, block, rec, record_stride(cfg), mk, recording(i, j))
                )
    return jobs


def run_job(job: Job) -> dict[str, Any]:
    """Simulate one job; returns its metric rows and, for the recorded seed, the series.

    Top-level and free of closures so that process pools and Ray can ship it.
    """
    pin_threads()
    cpu0, wall0 = time.process_time(), time.perf_counter()
    policy = job.spec.build(job.config)
    rec_rows = () if job.record_seed is None else (job.seeds.index(job.record_seed),)
    tr = recorded_rollout(job.recording, job.config, policy, job.seeds, record_rows=rec_rows)
    out: dict[str, Any] = {
        "scenario": job.scenario,
        "policy": job.policy,
        "rows": trace_metrics(tr, **dict(job.metric_kwargs)),
        # CPU seconds do not grow when other processes share the cores; wall seconds do
        "cpu_s": time.process_time() - cpu0,
        "wall_s": time.perf_counter() - wall0,
    }
    if rec_rows:
        r = rec_rows[0]
        k = np.arange(0, len(tr.t), job.record_stride)
        if k[-1] != len(tr.t) - 1:
            k = np.append(k, len(tr.t) - 1)  # always keep the final state
        out["trace"] = {
            "seed": job.record_seed,
            "t": tr.t,
            "pair_error": tr.pair_error[r],
            "surface": tr.surface[r],
            "frame_t": tr.t[k],
            "positions": tr.positions[r][k].astype(np.float32),
            "velocities": tr.velocities[r][k].astype(np.float32),
            "leader_positions": tr.leader_positions[r][k].astype(np.float32),
        }
    return out


def _local(jobs: Sequence[Job], workers: int) -> Iterator[tuple[Job, dict[str, Any]]]:
    for i, result in imap_unordered(run_job, [(job,) for job in jobs], workers):
        yield jobs[i], result


def _ray(
    jobs: Sequence[Job], workers: int, address: str | None
) -> Iterator[tuple[Job, dict[str, Any]]]:
    ray = optional.load("ray", "--backend ray")
    started = False
    if not ray.is_initialized():
        kwargs: dict[str, Any] = dict(include_dashboard=False, log_to_driver=False)
        if address:
            kwargs["address"] = address
        else:
            kwargs["num_cpus"] = workers
        ray.init(**kwargs)
        started = True
    try:
        task = ray.remote(num_cpus=1)(run_job)
        pending = {task.remote(job): job for job in jobs}
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                yield pending.pop(ref), ray.get(ref)
    finally:
        if started:
            ray.shutdown()


def run_jobs(
    jobs: Sequence[Job],
    *,
    backend: str = "local",
    workers: int = 1,
    ray_address: str | None = None,
) -> Iterator[tuple[Job, dict[str, Any]]]:
    """Run ``jobs`` (slowest first) and yield ``(job, result)`` as they finish."""
    if backend not in BACKENDS:
        raise ValueError(f"backend={backend!r} is invalid: must be one of {', '.join(BACKENDS)}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers={workers!r} is invalid: must be an integer >= 1")
    order = sorted(jobs, key=lambda j: -j.cost)
    if backend == "ray":
        return _ray(order, workers, ray_address)
    return _local(order, workers)
