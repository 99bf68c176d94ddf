"""The Ray backend of ``python -m train.sweep``: the same trials as Ray Tune trials.

A grid sweep is one ``tune.grid_search`` over the plan's trial records, so Tune runs exactly
the trials the local backend runs, each through :func:`train.sweep_trial.run_trial` (hence
identical results). A search sweep lets Tune's ``OptunaSearch`` draw the settings, each drawn
setting repeated once per seed (``tune.search.Repeater``; Optuna sees the mean of the metric
over the seeds). Resources per trial come from ``tune.with_resources``; Tune's experiment
state lives in ``<sweep>/ray/tune`` and an interrupted sweep continues with
``Tuner.restore``. Ray is imported only by this module (through
:mod:`train.sweep.backends`, when a sweep asks for it).
"""

from __future__ import annotations

import json
import logging
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import ray
from ray import tune
from ray.tune.search import ConcurrencyLimiter, Repeater
from ray.tune.search.repeater import TRIAL_INDEX

from baselines.runtime import optional
from train.sweep.local import Outcome, Progress
from train.sweep.plan import SweepPlan, Trial
from train.sweep.trial import result_scalars, run_trial

__all__ = ["EXPERIMENT", "run_ray"]

#: Tune's experiment directory inside the sweep directory
EXPERIMENT = ("ray", "tune")

# the progress display of this driver process; the Tune callback that feeds it is stored
# (pickled) with the experiment, so it holds no state of its own and looks this up
_PROGRESS: list[Progress] = []


class _TuneProgress(tune.Callback):
    """Forwards Tune's trial events to the sweep's progress display."""

    def _show(self, event: str, trial: Any, why: str = "") -> None:
        if not _PROGRESS:
            return
        name = _trial_name(trial.config) or trial.trial_id
        p = _PROGRESS[-1]
        if event == "start":
            p.start(name)
        elif event == "done":
            p.finish(name)
        else:
            p.fail(name, why)

    def on_trial_start(self, iteration, trials, trial, **info):
        self._show("start", trial)

    def on_trial_complete(self, iteration, trials, trial, **info):
        self._show("done", trial)

    def on_trial_error(self, iteration, trials, trial, **info):
        self._show("error", trial, f"see {trial.path}/error.txt")


def _trial_name(config: dict[str, Any]) -> str | None:
    trial = config.get("trial")
    return trial["name"] if isinstance(trial, dict) else None


def _dirname(trial: Any) -> str:
    name = _trial_name(trial.config)
    return name.replace("/", "__") if name else f"trial_{trial.trial_id}"


def _decode(value: Any, domain: dict[str, Any]) -> Any:
    if domain["kind"] == "choice":
        return json.loads(value)  # choices travel as JSON text (Optuna wants plain scalars)
    return int(value) if domain["kind"] == "int" else float(value)


def _trial_of(config: dict[str, Any], plan: dict[str, Any]) -> dict[str, Any]:
    """The trial record of a Tune configuration (grid: given; search: built from the draw)."""
    if "trial" in config:
        return config["trial"]
    p = SweepPlan.from_dict(plan)
    assignments = {k: _decode(config["params"][k], dom) for k, dom in p.grid}
    return p.make_trial(assignments, p.seeds[int(config.get(TRIAL_INDEX, 0))]).to_dict()


def _ray_trial(config: dict[str, Any], sweep_dir: str, plan: dict[str, Any]) -> None:
    """The Tune trainable: one sweep trial, reported once when it is done."""
    result = run_trial(_trial_of(config, plan), Path(sweep_dir))
    if result.get("status") != "completed":
        raise RuntimeError(f"trial {result.get('trial')} ended {result.get('status')!r}")
    # Tune's loggers take numbers (TensorBoard warns on inf): the finite ones, the objective,
    # and the whole result as JSON text for the driver
    scalars = {k: v for k, v in result_scalars(result).items() if math.isfinite(v)}
    if plan.get("search"):
        scalars[plan["metric"]] = result_scalars(result).get(plan["metric"], math.nan)
    tune.report({**scalars, "result_json": json.dumps(result)})


def _search_space(plan: SweepPlan) -> dict[str, Any]:
    space = {}
    for key, dom in plan.grid:
        if dom["kind"] == "choice":
            space[key] = tune.choice([json.dumps(v) for v in dom["values"]])
        elif dom["kind"] == "uniform":
            space[key] = tune.uniform(dom["low"], dom["high"])
        elif dom["kind"] == "loguniform":
            space[key] = tune.loguniform(dom["low"], dom["high"])
        else:
            space[key] = tune.randint(dom["low"], dom["high"] + 1)
    return {"params": space}


def _new_tuner(plan: SweepPlan, trials: Sequence[Trial], trainable, exp: Path, limit):
    if plan.search is None:
        param_space = {"trial": tune.grid_search([t.to_dict() for t in trials])}
        tune_config = tune.TuneConfig(max_concurrent_trials=limit, trial_dirname_creator=_dirname)
    else:
        optional.load("optuna", "--search optuna")
        search = optional.load("ray.tune.search.optuna", "--search optuna")
        optuna = search.OptunaSearch(metric=plan.metric, mode=plan.mode, seed=0)
        searcher = Repeater(optuna, repeat=len(plan.seeds), set_index=True)
        param_space = _search_space(plan)
        if limit:
            searcher = ConcurrencyLimiter(searcher, max_concurrent=limit)
        tune_config = tune.TuneConfig(
            search_alg=searcher,
            num_samples=plan.samples * len(plan.seeds),
            trial_dirname_creator=_dirname,
        )
    run_config = tune.RunConfig(
        name=exp.name,
        storage_path=str(exp.parent),
        verbose=0,
        callbacks=[_TuneProgress()],
        failure_config=tune.FailureConfig(max_failures=0),
    )
    return tune.Tuner(
        trainable, param_space=param_space, tune_config=tune_config, run_config=run_config
    )


def _collect(grid: Any, expected: int | None) -> Outcome:
    """Results and failures of Tune's result grid; interrupted if a trial did not end (or,
    for a search, fewer than ``expected`` trials were started)."""
    out, unfinished = Outcome(), 0
    for r in grid:
        name = _trial_name(r.config or {}) or str(r.path)
        if r.error is not None:
            out.failed[name] = f"{type(r.error).__name__}; see {r.path}/error.txt"
        elif r.metrics and "result_json" in r.metrics:
            result = json.loads(r.metrics["result_json"])
            out.results[result["trial"]] = result
        else:
            unfinished += 1
    out.interrupted = unfinished > 0 or (expected is not None and len(grid) < expected)
    return out


def run_ray(
    plan: SweepPlan,
    trials: Sequence[Trial],
    sweep_dir: Path,
    progress: Progress,
    *,
    address: str | None = None,
    num_cpus: int | None = None,
    cpus_per_trial: float = 1.0,
    max_concurrent: int | None = None,
) -> Outcome:
    """Run the sweep on Ray Tune (a new local Ray instance, or the cluster at ``address``,
    or the Ray instance this process already joined)."""
    sweep_dir = Path(sweep_dir).resolve()
    exp = sweep_dir.joinpath(*EXPERIMENT)
    # the sweep draws its own progress display instead of Tune's tables
    os.environ.setdefault("RAY_AIR_NEW_OUTPUT", "0")
    logging.getLogger("ray.tune").setLevel(logging.WARNING)
    started = False
    if not ray.is_initialized():
        kwargs: dict[str, Any] = dict(
            include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING
        )
        if address:
            kwargs["address"] = address
        else:
            kwargs["num_cpus"] = num_cpus
        try:
            ray.init(**kwargs)
        except ConnectionError as e:
            raise ConnectionError(
                f"--address {address!r}: cannot join the Ray cluster ({e}). A cluster with "
                "token authentication needs RAY_AUTH_MODE=token and its token here (see "
                "docs/sweeps.md)"
            ) from None
        started = True
    _PROGRESS.append(progress)
    try:
        trainable = tune.with_resources(
            tune.with_parameters(_ray_trial, sweep_dir=str(sweep_dir), plan=plan.to_dict()),
            {"cpu": cpus_per_trial},
        )
        if tune.Tuner.can_restore(exp):
            tuner = tune.Tuner.restore(
                str(exp), trainable, resume_unfinished=True, resume_errored=True
            )
        else:
            tuner = _new_tuner(plan, trials, trainable, exp, max_concurrent)
        grid = tuner.fit()
        return _collect(grid, None if plan.search is None else plan.samples * len(plan.seeds))
    finally:
        _PROGRESS.remove(progress)
        if started:
            ray.shutdown()
