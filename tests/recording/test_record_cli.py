"""``--record`` on the benchmark, the evaluation and the quadrotor experiment: every run's
recording lands in ``<out>/recordings/<run>/seed<k>.pfrec``, written by the worker that ran
it, readable by the reader and the replay; ``--record-every`` and ``--record-seeds``; a
command run again into the same folder replaces its recordings; bad options end in one line
naming them."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from baselines.experiments.benchmark.run import main as benchmark
from baselines.experiments.quadrotor.experiment import main as quadrotor
from baselines.runtime.cli import UsageError
from pairflock_env.recording import open_recording
from train.evaluate.cli import main as evaluate

ROOT = Path(__file__).resolve().parents[2]
#: 8 UAVs for 2 s (200 control steps), 2 seeds: a fraction of a second per run
BENCH = "--suite quick --n-uavs 8 --horizon 2 --seeds 2 --quiet"


def _run(module: str, args: str, *paths: Path, cwd: Path) -> str:
    """``python -m module`` with ``args`` (split at spaces) and ``paths``; its stdout."""
    env = dict(os.environ, OMP_NUM_THREADS="1", NUMBA_NUM_THREADS="1", MPLBACKEND="Agg")
    r = subprocess.run(
        [sys.executable, "-m", module, *args.split(), *map(str, paths)],
        cwd=cwd,
        env=dict(env, PYTHONPATH=str(ROOT)),
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    return r.stdout


def _check(out: Path, run: str, seed: int, n: int, controller: str, steps: int, every: int = 1):
    """The recording of ``run`` and ``seed`` in ``out``: complete, as the command ran it."""
    r = open_recording(out / f"recordings/{run}/seed{seed}.pfrec")
    assert r.complete and r.manifest["metadata"]["ended_by"] == "truncated"
    assert (r.num_uavs, r.seed, r.controller, r.every) == (n, seed, controller, every)
    assert r.steps == steps and r["positions"].shape == (steps, n, r.dim)
    assert np.asarray(r["step"]).tolist() == [*range(0, (steps - 1) * every + 1, every)]
    assert r.metadata["run"] == run
    return r


def test_benchmark_records_every_run_from_two_workers_and_a_rerun_replaces_them(tmp_path):
    out = tmp_path / "bench"
    args = f"{BENCH} --no-figures --record --out"
    stdout = _run("baselines.benchmark", f"--workers 2 --batch-size 1 {args}", out, cwd=tmp_path)
    runs = ["nominal_smc", "nominal_proportional"]
    paths = [f"recordings/{run}/seed{s}.pfrec" for run in runs for s in (0, 1)]
    assert json.loads((out / "run.json").read_text())["recordings"] == paths
    assert f"wrote 4 recordings in {out / 'recordings'}" in stdout
    for run in runs:
        policy = run.split("_")[1]
        for seed in (0, 1):
            r = _check(out, run, seed, n=8, controller=policy, steps=201)
            assert r.metadata["scenario"] == "nominal" and r.metadata["policy"] == policy
            assert r.manifest["config"]["n_uavs"] == 8
    # the recording holds the run: over 2 s the steady window is the whole run
    rows = json.loads((out / "results.json").read_text())["runs"]
    row = next(r for r in rows if r["policy"] == "smc" and r["seed"] == 1)
    err = open_recording(out / "recordings/nominal_smc/seed1.pfrec")["pair_error"][:, 0]
    assert np.abs(err).max() == pytest.approx(row["ss_max_error"], rel=1e-5)

    # again into the same folder, one step in 10 of seed 1: seed 1 is replaced, seed 0 kept
    before = (out / "recordings/nominal_smc/seed0.pfrec/manifest.json").read_text()
    again = f"--workers 1 --record-every 10 --record-seeds 1 {args}"
    _run("baselines.benchmark", again, out, cwd=tmp_path)
    recorded = json.loads((out / "run.json").read_text())["recordings"]
    assert recorded == [f"recordings/{run}/seed1.pfrec" for run in runs]
    _check(out, "nominal_smc", 1, n=8, controller="smc", steps=21, every=10)
    assert (out / "recordings/nominal_smc/seed0.pfrec/manifest.json").read_text() == before


def test_quadrotor_experiment_records_each_vehicle_and_policy(tmp_path):
    out = tmp_path / "quad"
    args = "--seeds 2 --first-seed 5 --horizon 1 --policies smc zero --dynamics quadrotor"
    args += " --no-figures --quiet --workers 2 --record --record-every 5 --out"
    _run("baselines.quadrotor_experiment", args, out, cwd=tmp_path)
    for policy in ("smc", "zero"):
        for seed in (5, 6):
            r = _check(out, f"quadrotor_{policy}", seed, 10, policy, steps=11, every=5)
            assert r.dim == 3 and r.manifest["config"]["dynamics"] == "quadrotor"
            assert r.metadata["dynamics"] == "quadrotor"


def test_evaluation_records_the_learned_policy_and_the_baselines(tmp_path):
    out = tmp_path / "eval"
    args = "pair_n20_a50 --n-uavs 6 --seeds 2 --baselines smc@1000 --set horizon=1"
    args += " --workers 1 --quiet --record --record-seeds 10001 --out"
    _run("train.evaluate", args, out, cwd=tmp_path)
    runs = sorted(p.name for p in (out / "recordings").iterdir())
    assert runs == ["n6_corners_learned", "n6_corners_smc-1000"]
    r = _check(out, runs[0], 10001, n=6, controller="sb3:pair_n20_a50", steps=101)
    assert r.metadata["policy"] == "learned" and r.metadata["model"].endswith("pair_n20_a50.zip")
    r = _check(out, runs[1], 10001, n=6, controller="smc@1000", steps=101)
    assert r.manifest["config"]["pair_accel_limit"] == 1000
    assert not (out / "recordings/n6_corners_learned/seed10000.pfrec").exists()
    # and the replay reads it
    html = tmp_path / "replay.html"
    recording = out / "recordings/n6_corners_learned/seed10001.pfrec"
    _run("pairflock_env.replay", "", recording, "-o", html, cwd=tmp_path)
    assert html.stat().st_size > 10_000


@pytest.mark.parametrize(
    ("main", "args", "message"),
    [
        (benchmark, [*BENCH.split(), "--record-every", "2"], "--record-every is invalid without"),
        (benchmark, [*BENCH.split(), "--record", "--record-seeds", "7"], "--record-seeds 7 is"),
        (quadrotor, ["--record", "--record-seeds", "10"], "must be one of the seeds run (0-9)"),
        (evaluate, ["pair_n20_a50", "--record", "--record-every", "0"], "--record-every: 0"),
        (evaluate, ["pair_n20_a50", "--record-seeds", "1"], "--record-seeds is invalid without"),
    ],
)
def test_bad_record_options_name_the_option(main, args, message, tmp_path, capsys):
    with pytest.raises(UsageError) as e:
        main([*args, "--out", str(tmp_path / "never")])
    assert message in str(e.value)
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not (tmp_path / "never").exists()
