"""The training CLI: help, a subprocess smoke run, determinism, exact resume, Ctrl-C, errors."""

from __future__ import annotations

import csv
import io
import json
import os
import pickle
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from bench_scripts import load_script

from baselines import make_pair_policy
from baselines.evaluation.rollout import rollout, trace_metrics
from baselines.evaluation.specs import parse_value
from pairflock_env import make_config

pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")

import torch

import train.run as run_mod
from train.checkpoint import latest_checkpoint, load_checkpoint_state
from train.cli import _new_settings, build_parser, main
from train.evaluate import cli as evaluate
from train.evaluate.cli import _task_overrides
from train.hyperparameters import resolve_schedules
from train.run import train
from train.settings import RunSettings, load_yaml, settings_from_sources

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}

#: a tiny task: 8-UAV swarms, 1-s training episodes, 0.5-s evaluation on one seed
TINY = [
    "--set",
    "n_uavs=8",
    "--set",
    "pair_accel_limit=50",
    "--set",
    "max_cycles=100",
    "--eval-set",
    "horizon=0.5",
    "--eval-seeds",
    "1000",
    "--num-swarms",
    "2",
    "--hp",
    "n_steps=16",
    "--hp",
    "batch_size=32",
    "--hp",
    "n_epochs=2",
    "--hp",
    "policy_kwargs.net_arch=[16,16]",
]


def _cli(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "train", *args],
        cwd=ROOT,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def _settings(**flags):
    base = dict(
        env={"n_uavs": 8, "pair_accel_limit": 50.0, "max_cycles": 100},
        eval_env={"horizon": 0.5},
        eval_seeds=[1000],
        num_swarms=2,
        eval_baselines=["smc"],
        tensorboard=False,
    )
    hp = dict(n_steps=16, batch_size=32, n_epochs=2, policy_kwargs={"net_arch": [16, 16]})
    if flags.get("algo") in ("sac", "td3"):
        hp = dict(
            buffer_size=2000,
            learning_starts=64,
            batch_size=32,
            policy_kwargs={"net_arch": [16, 16]},
        )
    base["hyperparameters"] = {**hp, **flags.pop("hyperparameters", {})}
    base.update(flags)
    return settings_from_sources(base)


def _params(zip_path: Path) -> dict:
    with zipfile.ZipFile(zip_path) as z:
        out = {"policy": torch.load(io.BytesIO(z.read("policy.pth")), weights_only=True)}
        for name in z.namelist():
            if name.endswith("optimizer.pth"):
                out[name] = torch.load(io.BytesIO(z.read(name)), weights_only=False)
    return out


def _assert_same_params(a: Path, b: Path) -> None:
    pa, pb = _params(a), _params(b)
    assert pa["policy"].keys() == pb["policy"].keys()
    for k in pa["policy"]:
        assert torch.equal(pa["policy"][k], pb["policy"][k]), k
    opt = [k for k in pa if k.endswith("optimizer.pth")]
    assert opt, "the model file holds the optimizer state"
    for k in opt:
        sa, sb = pa[k]["state"], pb[k]["state"]
        assert sa.keys() == sb.keys()
        for i in sa:
            for name, v in sa[i].items():
                assert torch.equal(torch.as_tensor(v), torch.as_tensor(sb[i][name])), (k, i, name)


def _curve(run: Path) -> list[dict]:
    """The SB3 training log without wall-clock columns."""
    rows = []
    for f in sorted((run / "logs").glob("progress_*.csv")):
        with open(f, encoding="utf-8") as fh:
            for r in csv.DictReader(fh):
                rows.append({k: v for k, v in r.items() if not k.startswith("time/")})
    return rows


def test_help_documents_every_cli():
    out = _cli("--help")
    assert out.returncode == 0
    for flag in (
        "--algo",
        "--config",
        "--set",
        "--hp",
        "--total-steps",
        "--seed",
        "--out",
        "--resume",
        "--eval-every",
        "--checkpoint-every",
        "--time-limit",
        "Ctrl-C",
    ):
        assert flag in out.stdout, flag
    for cmd in (["-m", "train.evaluate"], ["benchmarks/bench_training.py"]):
        r = subprocess.run(
            [sys.executable, *cmd, "--help"],
            cwd=ROOT,
            env=ENV,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert r.returncode == 0 and "usage:" in r.stdout


def test_cli_smoke_run_writes_a_complete_run_directory(tmp_path):
    out = tmp_path / "run"
    r = _cli(
        *TINY,
        "--total-steps",
        "256",
        "--eval-every",
        "128",
        "--checkpoint-every",
        "128",
        "--eval-baselines",
        "smc",
        "--seed",
        "3",
        "--out",
        str(out),
        "--quiet",
    )
    assert r.returncode == 0, r.stderr[-2000:]
    assert "completed: 256 steps" in r.stderr
    for name in (
        "settings.yaml",
        "run.json",
        "eval.csv",
        "eval_baselines.json",
        "best_model.zip",
        "final_model.zip",
        "checkpoints/latest",
    ):
        assert (out / name).is_file(), name
    assert list((out / "tensorboard").iterdir()), "tensorboard events"
    rec = json.loads((out / "run.json").read_text())
    assert rec["status"] == "completed" and rec["num_timesteps"] == 256
    assert rec["seed"] == 3 and rec["config"]["n_uavs"] == 8
    assert rec["versions"]["stable-baselines3"] and "git_commit" in rec
    assert rec["interface"]["name"] == "pair" and rec["final_summary"]["ss_error_median"] >= 0
    with open(out / "eval.csv", encoding="utf-8") as f:
        steps = [int(row["step"]) for row in csv.DictReader(f)]
    assert steps[0] < 128 and steps[-1] == 256  # initial policy, periodic, final
    # the saved policy plugs into the action slot and runs the baselines' rollout

    cfg = make_config("paper", n_uavs=8, pair_accel_limit=50.0, horizon=0.3)
    pol = make_pair_policy(f"sb3:{out / 'final_model.zip'}", cfg)
    rows = trace_metrics(rollout(cfg, pol, [5]))
    assert np.isfinite(rows[0]["ss_mean_error"])


def test_same_seed_same_training_curve_and_evaluation(tmp_path):
    runs = []
    for name in ("a", "b"):
        s = _settings(seed=7, total_steps=512, eval_every=256, checkpoint_every=0)
        train(s, tmp_path / name, quiet=True)
        runs.append(tmp_path / name)
    ca, cb = _curve(runs[0]), _curve(runs[1])
    assert len(ca) >= 4 and ca == cb
    ea = (runs[0] / "eval.csv").read_text().splitlines()
    eb = (runs[1] / "eval.csv").read_text().splitlines()
    strip = lambda lines: [",".join(x for i, x in enumerate(r.split(",")) if i != 1) for r in lines]  # noqa: E731
    assert strip(ea) == strip(eb)  # identical evaluations (wall time column aside)
    _assert_same_params(runs[0] / "final_model.zip", runs[1] / "final_model.zip")
    other = _settings(seed=8, total_steps=512, eval_every=0, checkpoint_every=0)
    train(other, tmp_path / "c", quiet=True)
    assert _curve(tmp_path / "c") != ca


#: a run on two tasks (train/tasks.py): 8-UAV corners and 6-UAV random starts
TWO_TASKS = [{"num_swarms": 1}, {"n_uavs": 6, "init": "random", "max_cycles": 60, "num_swarms": 1}]


@pytest.mark.parametrize(
    "algo, tasks", [("ppo", None), ("sac", None), ("ppo", TWO_TASKS)], ids=["ppo", "sac", "mix"]
)
def test_resume_continues_exactly(tmp_path, algo, tasks):
    """A run resumed from a mid-run checkpoint ends bit-identical to the uninterrupted run:
    step count, parameters, optimizer state and (SAC) replay buffer; also on two tasks, whose
    task envs are all saved and restored."""
    total, every = (512, 256) if algo == "ppo" else (192, 96)
    s = _settings(
        algo=algo,
        seed=1,
        total_steps=total,
        eval_every=0,
        checkpoint_every=every,
        keep_checkpoints=0,
        **({"tasks": tasks} if tasks else {}),
    )
    full = tmp_path / "full"
    train(s, full, quiet=True)
    ckpts = sorted((full / "checkpoints").glob("step_*"))
    assert len(ckpts) >= 2
    mid = ckpts[0]
    part = tmp_path / "part"
    shutil.copytree(full, part, ignore=shutil.ignore_patterns("final_model.zip"))
    for c in sorted((part / "checkpoints").glob("step_*"))[1:]:
        shutil.rmtree(c)
    (part / "checkpoints" / "latest").write_text(mid.name + "\n")
    assert latest_checkpoint(part).name == mid.name
    if algo == "sac":
        assert (mid / "replay_buffer.pkl").is_file()
    if tasks:
        assert len(load_checkpoint_state(mid)["env"]["tasks"]) == 2
    res = train(s, part, resume=part, quiet=True)
    assert res.num_timesteps == total and res.status == "completed"
    _assert_same_params(full / "final_model.zip", part / "final_model.zip")
    if algo == "sac":
        last = sorted((full / "checkpoints").glob("step_*"))[-1].name
        with open(full / "checkpoints" / last / "replay_buffer.pkl", "rb") as f:
            ra = pickle.load(f)
        with open(part / "checkpoints" / last / "replay_buffer.pkl", "rb") as f:
            rb = pickle.load(f)
        assert ra.pos == rb.pos and ra.full == rb.full and ra.pos > 0
        np.testing.assert_array_equal(ra.observations[: ra.pos], rb.observations[: rb.pos])
    assert (part / f"run_resumed_{int(mid.name.split('_')[1]):012d}.json").is_file()


def test_ctrl_c_saves_a_checkpoint_and_exits_cleanly(tmp_path):
    out = tmp_path / "run"
    p = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "train",
            *TINY,
            "--total-steps",
            "1e9",
            "--eval-every",
            "0",
            "--eval-baselines",
            "--out",
            str(out),
            "--quiet",
        ],
        cwd=ROOT,
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.time() + 90
        while time.time() < deadline and not list((out / "logs").glob("progress_*.csv")):
            time.sleep(0.5)
        time.sleep(3.0)  # let it learn for a moment
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, err[-2000:]
    assert "Traceback" not in err and "interrupted" in err
    rec = json.loads((out / "run.json").read_text())
    assert rec["status"].startswith("interrupted") and rec["num_timesteps"] > 0
    assert (out / "final_model.zip").is_file()

    ck = latest_checkpoint(out)
    assert json.loads((ck / "checkpoint.json").read_text())["num_timesteps"] == rec["num_timesteps"]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--set", "n_uav=20"], "Did you mean 'n_uavs'"),
        (["--hp", "learning_rat=1e-3"], "Did you mean 'learning_rate'"),
        (["--set", "pair_accel_limit=-5"], "pair_accel_limit=-5"),
        (["--interface-param", "w_error=-1"], "w_error=-1"),
        (["--eval-baselines", "smcc"], "eval_baselines entry 'smcc'"),
        (["--hp", "seed=3"], "set by the CLI"),
        (["--hp", "learning_rate=lin_x"], "learning_rate='lin_x' is invalid"),
        (["--hp", "clip_range=lin_-0.2"], "the start must be > 0"),
    ],
)
def test_bad_settings_are_named(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as e:
        main([*args, "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert e.value.code == 2 and message in err, err
    assert not (tmp_path / "x").exists()


def test_resume_refuses_changes_and_out_is_protected(tmp_path, capsys):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "something").write_text("x")
    for argv, message in [
        ([*TINY, "--total-steps", "64", "--out", str(tmp_path / "full")], "--overwrite"),
        (["--resume", str(tmp_path / "nothing")], "no checkpoint"),
        (["--resume", str(tmp_path / "full"), "--algo", "sac"], "cannot change"),
        (["--total-steps", "64"], "--out is required"),
    ]:
        with pytest.raises(SystemExit) as e:
            main(argv)
        err = capsys.readouterr().err
        assert e.value.code == 2 and message in err, err


def test_throughput_script_trains_on_both_routes(tmp_path):
    """Both routes of ``python benchmarks/bench_training.py`` build, seed and train (SB3 seeds
    the env in its constructor, which SuperSuit's ConcatVecEnv no longer supports on its own)."""
    pytest.importorskip("supersuit")
    main = load_script("bench_training").main

    out = tmp_path / "throughput.json"
    assert (
        main(
            [
                "--steps",
                "64",
                "--env-steps",
                "64",
                "--repeats",
                "1",
                "--num-swarms",
                "2",
                "--n-uavs",
                "6",
                "--hp",
                "n_steps=16",
                "--hp",
                "batch_size=32",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    rec = json.loads(out.read_text())
    for route in ("native", "supersuit"):
        assert all(v > 0 for v in rec["median"][route].values()), route
    assert rec["rows"] == 4 and rec["ratio"]["learn"] > 0


def test_linear_schedules_decay_to_zero():
    hp = resolve_schedules({"learning_rate": "lin_3e-4", "clip_range": 0.2, "n_steps": 8})
    assert hp["learning_rate"](1.0) == 3e-4 and hp["learning_rate"](0.0) == 0.0
    assert hp["learning_rate"](0.5) == pytest.approx(1.5e-4) and hp["clip_range"] == 0.2


def _tree(run: Path) -> dict[str, tuple[bytes, int]]:
    """Every file under ``run``: its bytes and modification time (ns)."""
    return {
        str(p.relative_to(run)): (p.read_bytes(), p.stat().st_mtime_ns)
        for p in sorted(run.rglob("*"))
        if p.is_file()
    }


def test_resume_of_a_finished_run_says_so_and_changes_nothing(tmp_path, capsys):
    run = tmp_path / "done"
    res = train(_settings(total_steps=64, eval_every=0, checkpoint_every=0), run, quiet=True)
    assert res.status == "completed"
    before = _tree(run)
    assert main(["--resume", str(run)]) == 0
    out = capsys.readouterr().out
    assert "is complete" in out and "nothing changed" in out and "64" in out
    assert _tree(run) == before  # no file written, rewritten or added
    # a higher target continues the same run
    assert main(["--resume", str(run), "--total-steps", "128", "--quiet"]) == 0
    assert json.loads((run / "run_resumed_000000000064.json").read_text())["num_timesteps"] == 128


def test_ctrl_c_mid_rollout_resumes_to_the_uninterrupted_end(tmp_path, monkeypatch):
    """SIGINT in the middle of a rollout: the run stops at the next rollout boundary, and the
    resumed run ends at the same step, with the same parameters, as an uninterrupted one."""
    s = _settings(seed=5, total_steps=512, eval_every=128, checkpoint_every=0)
    full = run_mod.train(s, tmp_path / "full", quiet=True)
    rollout_steps = 16 * 4  # n_steps x rows (2 swarms x 2 paired UAVs)

    make = run_mod.make_vec_env

    def make_interrupting(settings, seed_offset=0):
        venv = make(settings, seed_offset)
        step_wait, calls = venv.step_wait, [0]

        def interrupting_step_wait():
            calls[0] += 1
            if calls[0] == 40:  # vector step 40: the middle of the third rollout (16 each)
                os.kill(os.getpid(), signal.SIGINT)
            return step_wait()

        venv.step_wait = interrupting_step_wait
        return venv

    monkeypatch.setattr(run_mod, "make_vec_env", make_interrupting)
    part = tmp_path / "part"
    stopped = run_mod.train(s, part, quiet=True)
    assert stopped.interrupted and stopped.num_timesteps == 3 * rollout_steps
    monkeypatch.setattr(run_mod, "make_vec_env", make)
    resumed = run_mod.train(s, part, resume=part, quiet=True)
    assert resumed.num_timesteps == full.num_timesteps == 512
    _assert_same_params(tmp_path / "full" / "final_model.zip", part / "final_model.zip")
    ea = (tmp_path / "full" / "eval.csv").read_text().splitlines()
    eb = (part / "eval.csv").read_text().splitlines()
    strip = lambda lines: [",".join(x for i, x in enumerate(r.split(",")) if i != 1) for r in lines]  # noqa: E731
    assert strip(ea) == strip(eb)  # the same evaluations at the same steps (wall time aside)


@pytest.mark.parametrize("first_end", ["interrupted", "killed"])
def test_run_json_says_how_a_resumed_run_ended(tmp_path, first_end):
    """After a successful --resume, run.json says the run completed: the first session was
    stopped (Ctrl-C: its run.json says interrupted) or killed (SIGKILL: its run.json still
    says running, as written when learning started)."""
    s = _settings(total_steps=128, eval_every=0, checkpoint_every=0)
    out = tmp_path / "run"
    stopped = train(s, out, quiet=True, interrupt=SimpleNamespace(requested=True))
    assert stopped.interrupted
    record = json.loads((out / "run.json").read_text())
    assert record["status"].startswith("interrupted")
    if first_end == "killed":  # what a session killed while learning leaves behind
        (out / "run.json").write_text(json.dumps({**record, "status": "running"}))
    resumed = train(s, out, resume=out, quiet=True)
    assert resumed.status == "completed" and resumed.num_timesteps == 128
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "completed" and record["num_timesteps"] == 128
    session = json.loads((out / record["resumed_sessions"][-1]).read_text())
    assert session["status"] == "completed" and session["resumed_from"]


def test_values_are_read_as_written_by_the_train_cli(tmp_path):
    """``1e-3``/``5e1`` are numbers on the command line and in settings files (YAML 1.1
    alone reads them as text); one parser serves train, benchmark, quadrotor, evaluate."""
    parser = build_parser()
    args = parser.parse_args(
        [
            *TINY,
            "--set",
            "dt=1e-2",
            "--set",
            "pair_accel_limit=5e1",
            "--interface-param",
            "w_band=1e-1",
            "--hp",
            "learning_rate=1e-3",
            "--hp",
            "policy_kwargs={net_arch: [8, 8]}",
            "--out",
            str(tmp_path / "x"),
        ]
    )
    s = _new_settings(args, parser)
    assert s.env["dt"] == 0.01 and s.env["pair_accel_limit"] == 50.0
    assert s.interface_params["w_band"] == 0.1 and s.hyperparameters["learning_rate"] == 1e-3
    assert s.hyperparameters["policy_kwargs"] == {"net_arch": [8, 8]}
    cfg = tmp_path / "c.yaml"
    cfg.write_text("hyperparameters: {learning_rate: 1e-3}\nenv: {pair_accel_limit: 5e1}\n")

    assert load_yaml(cfg) == {
        "hyperparameters": {"learning_rate": 1e-3},
        "env": {"pair_accel_limit": 50.0},
    }
    assert [parse_value(t) for t in ("1e-3", "5e1", "20", ".5", "1_000", "lin_3e-4", "none")] == [
        1e-3,
        50.0,
        20,
        0.5,
        1000,
        "lin_3e-4",
        None,
    ]
    # ... and the SB3 model gets a float learning rate (this crashed as the text '1e-3')

    flags = {"hyperparameters": {**s.hyperparameters, "policy_kwargs": {"net_arch": [8]}}}
    small = _settings(total_steps=64, eval_every=0, checkpoint_every=0, **flags)
    assert train(small, tmp_path / "lr", quiet=True).status == "completed"


def test_only_stored_settings_keep_the_old_interface_names(tmp_path):
    """``frame``/``frame_params``, the old names of ``interface``/``interface_params``, load
    from stored data only (the committed models' metadata, through pairflock_env.compat);
    settings files, keywords and flags take the current names."""
    old = tmp_path / "old.yaml"
    old.write_text("frame: pair\nframe_params: {w_band: 0.2}\nenv: {n_uavs: 8}\n")
    with pytest.raises(ValueError, match="unknown key 'frame'"):
        load_yaml(old)
    with pytest.raises(TypeError, match="'frame'"):
        RunSettings(frame="world")
    stored = RunSettings.from_dict({"frame": "world", "frame_params": {}, "eval_baselines": []})
    assert stored.interface == "world" and "frame" not in stored.to_dict()
    with pytest.raises(ValueError, match="both 'frame'"):
        RunSettings.from_dict({"frame": "pair", "interface": "world"})
    preset, over = _task_overrides(ROOT / "models" / "pair_n20_a50.zip")
    assert preset == "paper" and over["pair_accel_limit"] == 50.0


def test_evaluate_baselines_take_gains_and_limits(capsys):
    """``train.evaluate --baselines NAME[:GAINS][@LIMIT]``: accepted as the benchmark's
    specs, and a bad name, gain or limit stops the CLI naming the entry."""
    parser = evaluate.build_parser()
    good = ["braking:detour=80", "smc@1000", "braking:k=10,detour=60@40"]
    args = parser.parse_args(["pair_n20_a50", "--baselines", *good])
    evaluate._check_args(args, parser)
    rows = evaluate.run_job(str(args.model), good[2], 12, "corners", [0], {"horizon": 0.05})
    assert rows[0]["pair_accel_limit"] == 40.0 and rows[0]["policy"] == good[2]
    for bad, why in (
        ("smcc", "analytic controllers are"),
        ("braking:detour=-1", "detour=-1"),
        ("braking:kk=1", "unknown gain"),
        ("smc@0", "LIMIT after @"),
    ):
        args = parser.parse_args(["pair_n20_a50", "--baselines", bad])
        with pytest.raises(SystemExit):
            evaluate._check_args(args, parser)
        err = capsys.readouterr().err
        assert f"--baselines {bad!r} is invalid" in err and why in err, err
