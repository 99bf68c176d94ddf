"""Training on a mix of tasks: settings validation, the concatenated VecEnv against the task
envs row for row, seeding per task, multi-task evaluation and best-model selection."""

from __future__ import annotations

import csv
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from bench_scripts import load_script
from view_helpers import snapshot

from baselines.reporting.criteria import learned_score

pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")

from stable_baselines3.common.logger import Logger

from pairflock_env.envs.sb3 import PairFlockSB3VecEnv
from train.callbacks import EvalCallback, eval_score, summarize_metrics
from train.cli import main
from train.mix.env import TaskMixVecEnv, task_seeds
from train.mix.evaluation import score_function, summarize_tasks
from train.mix.tasks import evaluation_tasks, training_tasks
from train.run import train
from train.settings import settings_from_sources

#: two small tasks whose episodes end at different decisions (4 and 6 of 5 control steps)
TASK_A = {"n_uavs": 6, "init": "corners", "max_cycles": 20}
TASK_B = {"n_uavs": 8, "init": "random", "max_cycles": 30}


def _settings(**flags):
    base = dict(
        env={"pair_accel_limit": 50.0, "max_cycles": 100},
        tasks=[{"n_uavs": 6, "num_swarms": 2}, {"n_uavs": 8, "init": "random", "num_swarms": 1}],
        eval_env={"horizon": 0.3},
        eval_seeds=[1000],
        num_swarms=2,
        eval_baselines=[],
        tensorboard=False,
        hyperparameters=dict(
            n_steps=16, batch_size=32, n_epochs=2, policy_kwargs={"net_arch": [8]}
        ),
    )
    base.update(flags)
    return settings_from_sources(base)


# --------------------------------------------------------------------------- settings
@pytest.mark.parametrize(
    "flags, error, message",
    [
        ({"tasks": {"n_uavs": 6}}, TypeError, "tasks={'n_uavs': 6} is invalid: must be a list"),
        ({"tasks": []}, ValueError, "tasks=[] is invalid"),
        ({"tasks": [{"n_uavs": 6}, 20]}, TypeError, "tasks[1]=20 is invalid"),
        ({"tasks": [{"n_uav": 6}]}, TypeError, "tasks[0]: got an unexpected keyword argument"),
        ({"tasks": [{"n_uavs": 6}, {"n_uavs": 1}]}, ValueError, "tasks[1]: n_uavs=1 is invalid"),
        ({"tasks": [{"n_uavs": 6, "num_swarms": 0}]}, ValueError, "tasks[0]: num_swarms=0"),
        ({"tasks": [{"num_swarms": 1.5}]}, TypeError, "tasks[0]: num_swarms=1.5"),
        ({"tasks": [{"preset": "paper"}]}, ValueError, "tasks[0]: key 'preset'"),
        ({"tasks": [{"n_uavs": 6}, {"n_uavs": 6}]}, ValueError, "the same name 'n6_corners'"),
        ({"tasks": [{"name": "a b"}]}, ValueError, "tasks[0]: name='a b' is invalid"),
        (
            {"tasks": [{"n_uavs": 6}, {"n_uavs": 8, "obs_neighbors": 3}]},
            ValueError,
            "tasks[1] gives other observation/action spaces",
        ),
        (
            {"tasks": [{"n_uavs": 6}, {"n_uavs": 8, "pair_accel_limit": 100.0}]},
            ValueError,
            "pair_accel_limit=100.0 vs 50.0",
        ),
        (
            {"eval_tasks": [{"n_uavs": 8, "obs_neighbors": 4}]},
            ValueError,
            "eval_tasks[0] (evaluation) gives other",
        ),
        ({"eval_tasks": [{"num_swarms": 2}]}, ValueError, "eval_tasks[0]: key 'num_swarms'"),
        ({"eval_aggregate": "mean"}, ValueError, "eval_aggregate='mean' is invalid"),
    ],
)
def test_bad_tasks_are_named(flags, error, message):
    with pytest.raises(error) as e:
        _settings(**flags)
    assert message in str(e.value), str(e.value)


def test_mismatch_says_what_must_be_shared():
    with pytest.raises(ValueError) as e:
        _settings(tasks=[{"n_uavs": 6}, {"n_uavs": 8, "obs_neighbors": 3}])
    msg = str(e.value)
    assert "obs_neighbors=3 vs 6" in msg and "observation size" in msg
    assert "the same pair_accel_limit, dim and obs_neighbors" in msg


def test_the_cli_names_a_bad_task_of_a_config_file(tmp_path, capsys):
    cfg = tmp_path / "mix.yaml"
    cfg.write_text("tasks:\n  - {n_uavs: 6}\n  - {n_uavs: 8, obs_neighbors: 3}\n")
    with pytest.raises(SystemExit) as e:
        main(["--config", str(cfg), "--out", str(tmp_path / "x")])
    assert e.value.code == 2 and "tasks[1] gives other" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_tasks_resolve_on_the_shared_env_and_single_task_settings_stay_as_they_were():
    s = _settings(eval_env={"horizon": 0.3, "init": "corners"})
    a, b = training_tasks(s)
    assert (a.name, a.num_swarms, b.name, b.num_swarms) == ("n6_corners", 2, "n8_random", 1)
    assert b.overrides == {
        "pair_accel_limit": 50.0,
        "max_cycles": 100,
        "n_uavs": 8,
        "init": "random",
    }
    ea, eb = evaluation_tasks(s)  # the training tasks, with the evaluation's episode length
    assert eb.overrides == {"pair_accel_limit": 50.0, "horizon": 0.3, "init": "random", "n_uavs": 8}
    assert ea.num_swarms == 0 and ea.config("paper").horizon == 0.3
    assert "tasks" in s.to_dict()
    one = _settings(tasks=None)
    assert not {"tasks", "eval_tasks", "eval_aggregate"} & set(one.to_dict())
    assert training_tasks(one) is None and evaluation_tasks(one)[0].name == ""

    assert score_function(one) is eval_score
    # one training task, selected on several
    sel = _settings(
        tasks=None, env={"n_uavs": 6, "pair_accel_limit": 50.0}, eval_tasks=[{}, TASK_B]
    )
    assert training_tasks(sel) is None and score_function(sel) is not eval_score
    assert [t.name for t in evaluation_tasks(sel)] == ["n6_corners", "n8_random"]
    assert evaluation_tasks(sel)[1].overrides["max_cycles"] == 30  # the task's own length wins


# --------------------------------------------------------------------------- the VecEnv
def _task_env(seed, **cfg):
    n = cfg.pop("num_swarms", 2)
    return PairFlockSB3VecEnv(
        "paper", num_swarms=n, seed=seed, pair_accel_limit=50.0, info_keys="all", **cfg
    )


def _mix_and_separate(seed=7):
    mix = TaskMixVecEnv([_task_env(0, **TASK_A), _task_env(0, **TASK_B)], ["a", "b"])
    sep = [_task_env(0, **TASK_A), _task_env(0, **TASK_B)]
    mix.seed(seed)
    for env, s in zip(sep, task_seeds(seed, 2), strict=True):
        env.seed(s)
    return mix, sep


def _same_infos(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert x.keys() == y.keys()
        for k in x:
            assert np.array_equal(np.asarray(x[k]), np.asarray(y[k])), k


def test_concatenated_vecenv_matches_the_task_envs_row_for_row():
    mix, sep = _mix_and_separate()
    assert mix.num_envs == 4 + 4 and [s.start for s in mix.row_slices] == [0, 4]
    obs = mix.reset()
    assert np.array_equal(obs, np.concatenate([e.reset() for e in sep]))
    _same_infos(mix.reset_infos, [i for e in sep for i in e.reset_infos])
    rng = np.random.default_rng(0)
    ended = terminal = 0
    for _ in range(13):  # past the ends of both tasks' episodes (4 and 6 decisions)
        act = rng.uniform(-1, 1, (mix.num_envs, 2)).astype(np.float32)
        o, r, d, info = mix.step(act)
        parts = [e.step(act[s]) for e, s in zip(sep, mix.row_slices, strict=True)]
        for i, arr in enumerate((o, r, d)):
            assert np.array_equal(arr, np.concatenate([p[i] for p in parts]))
        _same_infos(info, [x for p in parts for x in p[3]])
        ended += int(d.sum())
        terminal += sum("terminal_observation" in x for x in info)
    assert ended >= 4 + 8 and terminal == ended  # both tasks ended and were auto-reset
    assert [c.n_uavs for c in mix.get_attr("config")] == [6] * 4 + [8] * 4
    assert mix.task_of_row(-1) == 1 and mix.env_method("swarm_state", indices=[5])[0]["steps"] > 0


def test_attributes_state_and_bad_actions_delegate_by_row_range():
    mix, sep = _mix_and_separate()
    mix.reset()
    for e in sep:
        e.reset()
    mix.set_attr("tag", "x", indices=[1, 6])
    assert mix.get_attr("tag", [1, -2]) == ["x", "x"]
    assert mix.envs[1].get_attr("tag", [2]) == ["x"]  # global row 6 = row 2 of task 1
    with pytest.raises(IndexError, match=r"rows are 0\.\.7"):
        mix.get_attr("config", [8])
    state = mix.get_state()
    act = np.full((8, 2), 0.3, np.float32)
    first = mix.step(act)
    bad = act.copy()
    bad[6, 0] = np.nan  # a row of the second task: the first task gets no pending step either
    with pytest.raises(ValueError):
        mix.step_async(bad)
    with pytest.raises(RuntimeError, match="without a pending step_async"):
        mix.step_wait()
    mix.set_state(state)
    again = mix.step(act)
    for x, y in zip(first[:3], again[:3], strict=True):
        assert np.array_equal(x, y)
    other = _task_env(0, **TASK_A)

    with pytest.raises(ValueError, match="state of task 1"):
        TaskMixVecEnv([_task_env(0, **TASK_A), other], ["a", "b"]).set_state(state)
    with pytest.raises(ValueError, match="same spaces"):
        TaskMixVecEnv([_task_env(0, **TASK_A), _task_env(0, n_uavs=6, obs_neighbors=3)])


def test_rejected_seeds_and_options_change_no_task_and_name_the_task():
    mix, _ = _mix_and_separate()
    mix.seed(0)
    mix.reset()
    a_rows = mix.row_slices[0].stop
    n, dim = mix.envs[0].config.n_uavs, mix.envs[0].config.dim
    good = {"positions": np.arange(n * dim, dtype=float).reshape(n, dim) * 3}
    bad = {"positions": np.full((n, dim), np.nan)}
    calls = [
        ("set_options", [good] * a_rows + [bad] * (mix.num_envs - a_rows), ValueError),
        ("seed", [1] * mix.envs[0].num_swarms + ["x"] * mix.envs[1].num_swarms, TypeError),
    ]
    for method, arg, error in calls:
        before = snapshot(mix.envs)
        with pytest.raises(error, match=rf"task 1 \({mix.task_names[1]}, rows {a_rows}-"):
            getattr(mix, method)(arg)
        assert snapshot(mix.envs) == before, method  # task 0 took nothing either


def test_each_task_draws_from_its_own_seed_stream():
    twins = [dict(n_uavs=6, init="random", num_swarms=2) for _ in range(2)]
    mix = TaskMixVecEnv([_task_env(0, **c) for c in twins])
    global_state = np.random.get_state()[1].copy()
    seeds = mix.seed(11)
    keys = [s.spawn_key for s in seeds[::2]]  # one per swarm (2 rows each)
    assert keys == [(0, 0), (0, 1), (1, 0), (1, 1)] and {s.entropy for s in seeds} == {11}
    obs = mix.reset()
    assert not np.array_equal(obs[:4], obs[4:])  # same config, own stream
    mix.seed(11)
    assert np.array_equal(mix.reset(), obs)  # the same seed, the same episodes
    mix.seed(12)
    assert not np.array_equal(mix.reset(), obs)
    mix.seed(None)  # fresh entropy, not the global generator
    mix.reset()
    assert np.array_equal(np.random.get_state()[1], global_state)
    with pytest.raises(TypeError):
        mix.seed("1")


# --------------------------------------------------------------------------- evaluation
def _summary(scores):
    """A multi-task summary whose tasks have the given scores."""
    out = {"ss_error_median": 1.0, "band_time_max": 1.0, "min_separation_min": 1.0}
    out.update(peak_accel_max=1.0)
    for i, sc in enumerate(scores):
        out[f"t{i}/score"] = sc
    return out


@pytest.mark.parametrize("how, best", [("worst", 1), ("sum", 0)])
def test_best_model_is_chosen_on_the_aggregate_of_the_task_scores(how, best):
    s = _settings(eval_tasks=[{"n_uavs": 6, "name": "t0"}, {"n_uavs": 8, "name": "t1"}])
    s = s.replace(eval_aggregate=how)
    scripted = iter([_summary([0.1, 5.0]), _summary([3.0, 3.0])])  # sum: first; worst: second
    kept = []
    cb = EvalCallback(
        lambda: ([], next(scripted)),
        {},
        1,
        lambda step, rows, summary, improved: kept.append((step, summary["score"], improved)),
        score=score_function(s),
    )
    cb.model = SimpleNamespace(logger=Logger(folder=None, output_formats=[]))
    for step in (1, 2):
        cb.num_timesteps = step
        cb.run_now()
    assert [k[1] for k in kept] == ([5.0, 3.0] if how == "worst" else [5.1, 6.0])
    winner = max(i for i, k in enumerate(kept) if k[2])  # the last improvement is kept
    assert winner == best


def test_summary_per_task_and_worst_task_aggregate():
    def row(err, band, sep):
        keys = ("ss_mean_error", "ss_max_error", "band_time", "min_pair_separation", "peak_accel")
        return dict(zip(keys, (err, err, band, sep, 40.0), strict=True))

    a = [row(0.01, 4.0, 2.0), row(0.02, 5.0, 0.5)]
    b = [row(0.2, math.nan, 3.0), row(0.1, 7.0, 4.0)]
    s = summarize_tasks({"a": a, "b": b})
    assert s["a/ss_error_max"] == 0.02 and s["b/band_never"] == 1.0
    assert s["ss_error_median"] == pytest.approx(0.15) and s["band_time_max"] == math.inf
    assert s["min_separation_min"] == 0.5 and s["band_never"] == 1.0
    assert s["a/score"] == learned_score(summarize_metrics(a))
    assert summarize_tasks({"": a}) == summarize_metrics(a)  # one task: as before


def test_two_task_training_logs_every_eval_task_and_keeps_the_best(tmp_path):
    s = _settings(
        eval_tasks=[{"n_uavs": 6, "name": "small"}, {"n_uavs": 10, "init": "random"}],
        eval_baselines=["smc"],
        total_steps=192,
        eval_every=96,
        checkpoint_every=0,
    )
    res = train(s, tmp_path / "run", quiet=True)
    assert res.status == "completed" and res.num_timesteps == 192
    with open(tmp_path / "run" / "eval.csv", encoding="utf-8") as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    assert len(rows) == 3 and {"small/ss_error_median", "n10_random/score", "score"} <= set(rows[0])
    for r in rows:
        assert r["score"] == max(r["small/score"], r["n10_random/score"])
        assert r["min_separation_min"] == min(
            r["small/min_separation_min"], r["n10_random/min_separation_min"]
        )
    best = json.loads((tmp_path / "run" / "best_model.json").read_text())
    scores = [r["score"] for r in rows]
    assert best["step"] == rows[int(np.argmin(scores))]["step"]
    base = json.loads((tmp_path / "run" / "eval_baselines.json").read_text())
    assert {r["task"] for r in base["rows"]} == {"small", "n10_random"}
    assert "n10_random/ss_error_median" in base["summary"]["smc"]
    rec = json.loads((tmp_path / "run" / "run.json").read_text())
    assert set(rec["task_configs"]) == {"n6_corners", "n8_random"}
    assert rec["eval_task_configs"]["n10_random"]["horizon"] == 0.3


def test_throughput_measures_run_configs_and_estimates_the_run(tmp_path):
    bench = load_script("bench_training")
    estimate_run_s, main = bench.estimate_run_s, bench.main

    cfg = tmp_path / "mix.yaml"
    cfg.write_text(
        "env: {pair_accel_limit: 50.0, max_cycles: 100}\neval_env: {horizon: 0.2}\n"
        "tasks: [{n_uavs: 6, num_swarms: 1}, {n_uavs: 8, init: random, num_swarms: 1}]\n"
        "eval_seeds: [1000]\neval_baselines: [smc]\ntotal_steps: 1000\neval_every: 300\n"
        "hyperparameters: {n_steps: 8, batch_size: 16, n_epochs: 1,"
        " policy_kwargs: {net_arch: [8]}}\n"
    )
    out = tmp_path / "speed.json"
    assert main(["--config", str(cfg), "--steps", "32", "--repeats", "1", "--out", str(out)]) == 0
    r = json.loads(out.read_text())["configs"][str(cfg)]
    assert r["rows"] == 4 and r["median"]["cpu"] > 0 and r["median"]["eval_cpu_s"] > 0
    s = _settings(total_steps=1000, eval_every=300, eval_baselines=["smc"])
    # 1000 / rate, plus evaluations at 0, 300, 600, 900 and the final one, plus one baseline
    assert estimate_run_s(s, 100.0, 2.0) == pytest.approx(10.0 + 6 * 2.0)
