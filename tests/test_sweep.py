"""Training sweeps (``python -m train.sweep``): settings mapping, statistics, resume after a
kill, and the Ray Tune backend against a local Ray instance giving the local numbers."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from baselines.reporting.stats import iqm_ci

pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")
pytest.importorskip("rliable")

from rliable import metrics

from train.checkpoint import latest_checkpoint
from train.mix.evaluation import aggregate_score
from train.settings import load_yaml, settings_from_sources
from train.sweep.cli import main
from train.sweep.local import Progress, run_local
from train.sweep.plan import SweepPlan, parse_grid
from train.sweep.report import csv_rows, summary_markdown
from train.sweep.trial import FINAL_ROWS, run_trial

ROOT = Path(__file__).resolve().parents[1]
ENV_OVERRIDES = {"OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
ENV = {**os.environ, **ENV_OVERRIDES}

#: a tiny task (8-UAV swarms, 1-s training episodes, 0.5-s evaluation on one seed, tiny net)
TINY = [
    *("--set", "env.n_uavs=8", "--set", "env.pair_accel_limit=50", "--set", "env.max_cycles=100"),
    *("--set", "eval_env.horizon=0.5", "--set", "eval_seeds=[1000]", "--set", "num_swarms=2"),
    *("--set", "hp.n_steps=16", "--set", "hp.batch_size=32", "--set", "hp.n_epochs=2"),
    *("--set", "hp.policy_kwargs.net_arch=[16,16]", "--set", "eval_baselines=[]"),
    *("--set", "tensorboard=false", "--set", "eval_every=128", "--set", "checkpoint_every=128"),
]
SWEEP = [*TINY, "--seeds", "0", "1", "--total-steps", "256", "--bootstrap-reps", "200"]


def _cli(*args: str, timeout: float = 240, **kw) -> subprocess.CompletedProcess:
    # the environment as it is now: a Ray instance started here adds its auth settings
    return subprocess.run(
        [sys.executable, "-m", "train.sweep", *args],
        cwd=ROOT,
        env={**os.environ, **ENV_OVERRIDES},
        capture_output=True,
        text=True,
        timeout=timeout,
        **kw,
    )


def _rows_without_wall(path: Path) -> list[dict[str, str]]:
    with open(path, encoding="utf-8") as f:
        return [
            {k: v for k, v in r.items() if not k.startswith("wall_")} for r in csv.DictReader(f)
        ]


def _descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (from /proc; workers run in their own sessions)."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    out, todo = [], [pid]
    while todo:
        kids = children.get(todo.pop(), [])
        out += kids
        todo += kids
    return out


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory):
    """A two-seed local sweep, killed (SIGKILL, sweep and workers) once its first trial is
    done, then resumed by running the same command again."""
    if not Path("/proc/self/stat").exists():
        pytest.skip("needs /proc to find the worker processes")
    out = tmp_path_factory.mktemp("sweep") / "local"
    args = [*SWEEP, "--backend", "local", "--max-concurrent", "1", "--out", str(out), "--quiet"]
    first = out / "trials" / "default" / "seed_0"
    p = subprocess.Popen(
        [sys.executable, "-m", "train.sweep", *args],
        cwd=ROOT,
        env=ENV,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.time() + 180
        while time.time() < deadline and p.poll() is None:
            if (first / "sweep_trial.json").is_file():
                break
            time.sleep(0.1)
        os.kill(p.pid, signal.SIGSTOP)  # frozen, the sweep starts no worker we would miss
        for pid in [*_descendants(p.pid), p.pid]:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        p.wait(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert (first / "sweep_trial.json").is_file(), p.stderr.read().decode()[-3000:]
    p.stderr.close()
    before = {n: (first / n).stat().st_mtime_ns for n in ("run.json", "sweep_trial.json")}

    assert main(args) == 0
    return out, before


def test_resumed_sweep_runs_only_the_unfinished_trial(local_sweep):
    out, before = local_sweep
    first = out / "trials" / "default" / "seed_0"
    assert {n: (first / n).stat().st_mtime_ns for n in before} == before  # untouched
    session = json.loads((out / "sweep.json").read_text())["sessions"][-1]
    assert session["skipped"] == ["default/seed_0"] and session["ran"] == ["default/seed_1"]
    rows = _rows_without_wall(out / "sweep.csv")
    assert [(r["setting"], r["seed"], r["status"]) for r in rows] == [
        ("default", "0", "completed"),
        ("default", "1", "completed"),
    ]
    assert all(float(r["num_timesteps"]) == 256 for r in rows)
    assert {"final_ss_error_median", "best_min_separation_min", "aims_met"} <= set(rows[0])
    with open(out / "sweep.csv", encoding="utf-8") as f:
        assert {"wall_train_s", "wall_trial_s"} <= set(next(csv.reader(f)))


def test_each_trial_is_an_ordinary_resumable_run_directory(local_sweep):
    out, _ = local_sweep
    trials = json.loads((out / "sweep.json").read_text())["trials"]
    for t in trials:
        run = out / t["run_dir"]
        for name in ("settings.yaml", "run.json", "eval.csv", "final_model.zip", "best_model.zip"):
            assert (run / name).is_file(), (run, name)
        assert json.loads((run / "run.json").read_text())["status"] == "completed"
        assert latest_checkpoint(run).parent.parent == run
        s = settings_from_sources(load_yaml(run / "settings.yaml"))
        assert s.seed == t["seed"] and s.to_dict() == t["settings"]


def test_summary_has_iqm_ci_tables_aims_and_figure(local_sweep):
    out, _ = local_sweep
    md = (out / "summary.md").read_text()
    assert "## Final model: IQM [95 % CI] over seeds" in md and "rliable" in md
    row = next(line for line in md.splitlines() if line.startswith("| default | 2 |"))
    assert row.count("[") == 5  # an interval for every metric
    assert "## Aims: seeds whose final model meets each" in md and "/2 |" in md
    assert (out / "curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_ray_backend_gives_the_local_results(local_sweep, tmp_path):
    """Ray Tune on a local instance (joined through --address) == the local backend."""
    ray = pytest.importorskip("ray")
    pytest.importorskip("ray.tune")
    out = tmp_path / "ray"
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        address = ray.get_runtime_context().gcs_address
        r = _cli(*SWEEP, "--backend", "ray", "--address", address, "--out", str(out), "--no-figure")
        assert r.returncode == 0, r.stderr[-3000:]
    finally:
        ray.shutdown()
    assert _rows_without_wall(out / "sweep.csv") == _rows_without_wall(local_sweep[0] / "sweep.csv")
    assert (out / "ray" / "tune" / "tuner.pkl").is_file()  # Tune's experiment, for restore


def test_a_sweep_stopped_by_ctrl_c_resumes_to_the_uninterrupted_results(local_sweep, tmp_path):
    """Ctrl-C while the first trial learns stops it at the end of a rollout with a checkpoint
    (exit status 130); the sweep run again gives the results of a sweep never stopped, and
    the stopped trial's run.json says it completed."""
    out = tmp_path / "stopped"
    args = [*SWEEP, "--backend", "local", "--max-concurrent", "1", "--out", str(out)]
    args += ["--quiet", "--no-figure"]
    first = out / "trials" / "default" / "seed_0"
    p = subprocess.Popen(
        [sys.executable, "-m", "train.sweep", *args],
        cwd=ROOT,
        env=ENV,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.time() + 180
        while time.time() < deadline and not list((first / "logs").glob("progress_*.csv")):
            time.sleep(0.05)
        p.send_signal(signal.SIGINT)  # learning has started: stop mid-trial
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, err.decode()[-3000:]
    assert not (first / "sweep_trial.json").exists()  # stopped before its end
    assert json.loads((first / "run.json").read_text())["status"].startswith("interrupted")
    r = _cli(*args)
    assert r.returncode == 0, r.stderr[-3000:]
    assert _rows_without_wall(out / "sweep.csv") == _rows_without_wall(local_sweep[0] / "sweep.csv")
    record = json.loads((first / "run.json").read_text())
    assert record["status"] == "completed" and record["resumed_sessions"]


def test_help_shows_usage_and_examples():
    r = _cli("--help", timeout=60)
    assert r.returncode == 0
    for text in ("--grid", "--seeds", "--backend", "--address", "--cpus-per-trial", "--resume"):
        assert text in r.stdout, text
    assert "examples:" in r.stdout and "ray start --head" in r.stdout
    tomllib = pytest.importorskip("tomllib")
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["pairflock-sweep"] == "train.sweep.__main__:main"


def test_dotted_keys_map_onto_run_settings():
    assert parse_grid("hp.learning_rate=3e-4,1e-4") == ("hp.learning_rate", [3e-4, 1e-4])
    key, vals = parse_grid("hp.policy_kwargs.net_arch=[64,64],[128,128]")
    assert vals == [[64, 64], [128, 128]]
    plan = SweepPlan(
        base={},
        fixed=[("eval_env.horizon", 5.0), ("interface.w_band", 0.5)],
        grid=[("env.n_uavs", [8, 10]), (key, vals), ("num_swarms", [4])],
        seeds=[3, 4],
        total_steps=1000,
    )
    trials = plan.trials()
    assert len(trials) == 8 and len({t.run_dir for t in trials}) == 8
    t = trials[-1]
    s = t.settings
    assert (s["env"]["n_uavs"], s["num_swarms"], s["seed"], s["total_steps"]) == (10, 4, 4, 1000)
    assert s["hyperparameters"]["policy_kwargs"]["net_arch"] == [128, 128]
    assert s["eval_env"] == {"horizon": 5.0} and s["interface_params"]["w_band"] == 0.5
    assert t.label == "env.n_uavs=10 hp.policy_kwargs.net_arch=[128,128] num_swarms=4"


@pytest.mark.parametrize(
    "args, message",
    [
        (["--grid", "env.n_uav=8,10"], "Did you mean 'n_uavs'"),
        (["--grid", "hp.learning_rat=1e-3"], "Did you mean 'learning_rate'"),
        (["--grid", "foo.bar=1"], "'foo.bar' is invalid"),
        (["--grid", "num_swarm=2"], "Did you mean 'num_swarms'"),
        (["--grid", "seed=1,2"], "--seeds"),
        (["--grid", "env.n_uavs=8,"], "empty value"),
        (["--set", "env.n_uavs=8,10"], "one value"),
        (["--seeds", "1", "1"], "distinct"),
        (["--grid", "env.pair_accel_limit=50,-5"], "pair_accel_limit=-5"),
        (["--search", "optuna", "--samples", "2", "--grid", "hp.learning_rate=1e-4,3e-4"], "ray"),
        (["--search", "optuna", "--backend", "ray", "--grid", "hp.gamma=0.9,0.99"], "--samples"),
        (["--metric", "final_score"], "--search optuna"),
        (["--max-concurrent", "0"], "--max-concurrent 0"),
    ],
)
def test_bad_sweeps_are_named_before_anything_runs(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as e:
        main([*args, "--out", str(tmp_path / "x"), "--quiet"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and message in err, err
    assert not (tmp_path / "x").exists()


def test_out_and_resume_are_protected(tmp_path, capsys):
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "file").write_text("x")
    for argv, message in [
        (["--out", str(tmp_path / "busy")], "--overwrite"),
        (["--resume", str(tmp_path / "busy")], "no sweep.json"),
        (["--resume", str(tmp_path / "busy"), "--grid", "env.n_uavs=8"], "drop ['grid']"),
        (["--seeds", "0"], "--out is required"),
    ]:
        with pytest.raises(SystemExit) as e:
            main([*argv, "--quiet"])
        err = capsys.readouterr().err
        assert e.value.code == 2 and message in err, err


def test_a_failing_worker_is_reported_and_the_others_go_on(tmp_path):
    plan = SweepPlan(base={}, fixed=[], grid=[], seeds=[0])
    (trial,) = plan.trials()
    (tmp_path / "sweep.json").write_text(json.dumps({"trials": []}))  # the worker won't find it
    progress = Progress(1, disable=True)
    out = run_local([trial], tmp_path, 1, progress, poll_s=0.05)
    assert list(out.failed) == [trial.name] and not out.results and not out.interrupted
    assert progress.failed == 1 and progress.started == [trial.name]
    log = (tmp_path / "logs" / "default__seed_0.log").read_text()
    assert "is not in" in log


def test_iqm_and_interval_are_rliables_and_reproducible():
    x = np.random.default_rng(5).random((7, 3))
    global_state = np.random.get_state()[1].copy()
    point, lo, hi = iqm_ci(x, reps=300)
    assert np.array_equal(np.random.get_state()[1], global_state)  # own generator only
    assert np.allclose(point, [metrics.aggregate_iqm(x[:, j]) for j in range(3)])
    assert np.all(lo <= point) and np.all(point <= hi) and np.all(lo < hi)
    again = iqm_ci(x, reps=300)
    assert all(np.array_equal(a, b) for a, b in zip((point, lo, hi), again, strict=True))
    one = iqm_ci(np.array([[2.0, 3.0]]), reps=50)
    assert np.array_equal(one[0], [2.0, 3.0]) and np.array_equal(one[1], one[2])


def test_never_reached_band_is_censored_and_marked():
    def result(seed, band):
        s = dict(
            ss_error_median=0.1, band_time_max=band, min_separation_min=2.0, peak_accel_max=40.0
        )
        s["score"] = 1.0
        curve = [{"step": 0.0, **s}, {"step": 10.0, **s}]
        return dict(
            setting="default",
            label="default",
            assignments={},
            seed=seed,
            status="completed",
            num_timesteps=10,
            final=s,
            best=s,
            aims=[{"criterion": "a", "met": seed == 0, "measured": ""}],
            curve=curve,
            eval_horizon_s=50.0,
        )

    md = summary_markdown([result(0, 3.0), result(1, float("inf"))], ["# t"], reps=100)
    row = next(line for line in md.splitlines() if line.startswith("| default | 2 |"))
    assert ">= 26.50 [3.00, 50.00]" in row  # IQM of {3, 50}: the mean, marked a lower bound
    assert "| default | 1/2 |" in md
    with io.StringIO(md) as f:
        assert "nan" not in f.read()


def test_a_sweep_of_a_task_mix_reports_the_aggregate_and_every_task(tmp_path):
    """Trials of a multi-task config (train/tasks.py): final evaluation and aims per evaluation
    task plus over every task; the summary has a table per task next to the aggregate."""
    base = {
        "env": {"n_uavs": 8, "pair_accel_limit": 50.0, "max_cycles": 100},
        "tasks": [{"name": "a", "num_swarms": 1}, {"name": "b", "init": "random", "num_swarms": 1}],
        "eval_env": {"horizon": 0.3},
        "eval_seeds": [1000],
        "eval_baselines": [],
        "tensorboard": False,
        "eval_every": 0,
        "checkpoint_every": 0,
        "hyperparameters": {"n_steps": 16, "batch_size": 32, "n_epochs": 1},
    }
    plan = SweepPlan(base=base, fixed=[], grid=[], seeds=[0, 1], total_steps=64)
    results = [run_trial(t, tmp_path) for t in plan.trials()]
    r = results[0]
    assert r["status"] == "completed" and r["eval_tasks"] == ["a", "b"]
    assert r["final"]["score"] == aggregate_score(r["final"], ["a", "b"], "worst")
    names = [a["criterion"] for a in r["aims"]]
    assert names[0].startswith("a: ") and names[-1].startswith("every task: ")
    assert len(names) == 3 * len([n for n in names if n.startswith("a: ")])
    with open(tmp_path / plan.trials()[0].run_dir / FINAL_ROWS, encoding="utf-8") as f:
        assert [row["task"] for row in csv.DictReader(f)] == ["a", "b"]
    row = csv_rows(results, [])[0]
    assert {"final_score", "final_a/ss_error_median", "final_b/score", "aims_met"} <= set(row)
    md = summary_markdown(results, ["# t"], reps=50, figure=None)
    assert "## Final model per evaluation task" in md and "| aim | default |" in md
    for task in ("a", "b"):
        line = next(x for x in md.splitlines() if x.startswith(f"| default | {task} | 2 |"))
        assert line.count("[") == 5 and "nan" not in line
