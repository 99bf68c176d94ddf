"""One error path for every command line: bad input - a malformed option, a value out of
range, a config override, a controller name or gain, a negative seed, no workers - ends the
command with one line on stderr, ``<prog>: error: <what is wrong>``, and exit status 2,
before anything is written (:mod:`baselines.runtime.cli`)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from baselines.runtime.cli import ArgumentParser, UsageError, at_least, int_like, user_errors

ROOT = Path(__file__).resolve().parents[1]
OUT = "never_written"  # every --out below; relative to the command's folder

#: (command, arguments): each is bad input
CASES = [
    ("train.evaluate", ["pair_n20_a50", "--set", "n_uavs=abc"]),
    ("train.evaluate", ["pair_n20_a50", "--baselines", "smc:k=abc"]),
    ("train.evaluate", ["pair_n20_a50", "--first-seed", "-1"]),
    ("train.evaluate", ["pair_n20_a50", "--workers", "0"]),
    ("train.imitate", ["--config", "pair_n20_a50", "--set", "n_uavs=abc"]),
    ("train.imitate", ["--config", "pair_n20_a50", "--teacher", "smcc"]),
    ("train.imitate", ["--config", "pair_n20_a50", "--gain", "k=abc"]),
    ("train.imitate", ["--config", "pair_n20_a50", "--gain", "no_such_gain=1"]),
    ("train.imitate", ["--config", "pair_n20_a50", "--seeds", "-1"]),
    ("train", ["--config", "pair_n20_a50", "--set", "n_uavs=abc"]),
    ("train", ["--config", "pair_n20_a50", "--seed", "-1"]),
    ("train.sweep", ["--config", "pair_n20_a50", "--seeds", "-1"]),
    ("train.sweep", ["--config", "pair_n20_a50", "--grid", "env.n_uavs=abc,8"]),
    ("baselines.benchmark", ["--set", "n_uavs=abc"]),
    ("baselines.benchmark", ["--first-seed", "-1"]),
    ("baselines.benchmark", ["--workers", "0"]),
    ("baselines.reproduce", ["--policies", "smcc"]),
    ("baselines.quadrotor_experiment", ["--set", "quad_mass=-1"]),
    ("baselines.quadrotor_experiment", ["--first-seed", "-1"]),
    ("baselines.quadrotor_experiment", ["--workers", "0"]),
    ("baselines.quadrotor_invariants", ["--seed", "-1"]),
    ("baselines.quadrotor_compare", ["nowhere", "--against", "nowhere"]),
    ("baselines.safety_compare", ["nowhere", "--seed", "-1"]),
    ("baselines.safety_compare", ["nowhere"]),
    ("baselines.experiments.safety.figure", ["nowhere"]),
]


def test_every_command_line_turns_bad_input_into_one_line_and_status_2(tmp_path):
    """All at once (each mostly waits for its imports): status 2, one line naming the
    problem, no traceback, nothing written."""
    env = dict(os.environ, OMP_NUM_THREADS="1", MPLBACKEND="Agg", PYTHONPATH=str(ROOT))
    procs = []
    for i, (module, args) in enumerate(CASES):
        cwd = tmp_path / str(i)
        cwd.mkdir()
        procs.append(
            subprocess.Popen(
                [sys.executable, "-m", module, *args, "--out", OUT],
                cwd=cwd,
                env=env,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
        )
    wrong = []
    for (module, args), proc, i in zip(CASES, procs, range(len(CASES)), strict=True):
        _, err = proc.communicate(timeout=300)
        lines = err.strip().splitlines()
        ok = (
            proc.returncode == 2
            and len(lines) == 1
            and lines[0].startswith(f"python -m {module}: error: ")
            and not (tmp_path / str(i) / OUT).exists()
        )
        if not ok:
            wrong.append((module, args, proc.returncode, err[-600:]))
    assert not wrong, "\n".join(map(str, wrong))


def test_the_error_path_itself(capsys):
    parser = ArgumentParser(prog="prog")
    parser.add_argument("--n", type=at_least(1))
    parser.add_argument("--steps", type=int_like)
    with pytest.raises(UsageError) as e:
        parser.parse_args(["--n", "0"])
    assert e.value.code == 2 and str(e.value) == "argument --n: 0 is invalid: must be >= 1"
    assert capsys.readouterr().err == "prog: error: argument --n: 0 is invalid: must be >= 1\n"
    assert parser.parse_args(["--steps", "2e7"]).steps == 20_000_000
    with pytest.raises(SystemExit) as e, user_errors(parser):
        raise ValueError("x=1 is invalid: must be 2")
    assert (
        e.value.code == 2 and capsys.readouterr().err == "prog: error: x=1 is invalid: must be 2\n"
    )
    with pytest.raises(RuntimeError), user_errors(parser):  # not bad input: a traceback
        raise RuntimeError("a bug")
