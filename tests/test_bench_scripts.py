"""Every speed script of ``benchmarks/`` runs in its quick mode (each part once, tiny:
seconds), so that a change of the API breaks a test here rather than a user's command."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from bench_scripts import BENCHMARKS, SCRIPTS

#: the quick mode of the scripts that have no --smoke (default: --smoke)
QUICK = {
    "bench_crazyflie": ["--quick", "--sizes", "4"],
    "bench_recording": ["--quick"],
    "bench_replay": ["--quick"],  # without a browser (playwright) it says so and stops
    "bench_export": ["--quick"],
}


def test_the_scripts_are_found():
    assert {"bench_core", "bench_views", "bench_safety", "bench_quadrotor"} <= set(SCRIPTS)
    assert "bench_training" in SCRIPTS


@pytest.mark.parametrize("name", SCRIPTS)
def test_each_script_runs_its_quick_mode(name, tmp_path):
    if name == "bench_training":
        pytest.importorskip("supersuit")
    env = dict(os.environ, OMP_NUM_THREADS="1", MPLBACKEND="Agg")
    args = QUICK.get(name, ["--smoke"])
    if name == "bench_training":
        args = [*args, "--out", str(tmp_path / "out.json")]
    r = subprocess.run(
        [sys.executable, str(BENCHMARKS / f"{name}.py"), *args],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr[-3000:]
