"""Per-step speed of the views (PettingZoo parallel and AEC, Gymnasium single and vector, SB3)
at B = 1 (the vector and SB3 views at ``--num-swarms``), optionally alternating with another
checkout of the project.

    python benchmarks/bench_views.py --cpu-time                         # this checkout
    python benchmarks/bench_views.py --cpu-time --compare ../old        # alternate old/new
    python benchmarks/bench_views.py --cpu-time --cases vector-pair sb3-pair --num-swarms 64

Each measurement runs in a fresh subprocess whose ``PYTHONPATH`` is the checkout measured
(so an editable install of another checkout does not interfere); with ``--compare`` the two
checkouts alternate ``--rounds`` times and the table gives the median over rounds of each
round's median rate. Figures are view steps per second: one ``step()`` call of the view (the
AEC env: one cycle, an action of every agent; ``interface="pair"``: one policy decision of
``decision_period`` control steps). Only the public API is used, so an older checkout can be
measured with the same script: the script imports only ``pairflock_env`` (of the checkout
measured, first on the worker's path), the SB3 view when its case runs. ``--smoke`` runs every
case once, tiny (a check of the script, not a measurement).
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import json
import os
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from _timing import median_rate

import pairflock_env as pf
from pairflock_env import envs

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CASES = ("parallel", "aec", "gym", "gym-pair", "vector-pair", "sb3-pair")
THREADS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")


def _with_interface(cls, name: str, **kw):
    """``cls(interface=name)``, or ``frame=name`` for checkouts older than that keyword."""
    key = "interface" if "interface" in inspect.signature(cls).parameters else "frame"
    return cls(**{key: name}, **kw)


def make_stepper(case: str, N: int, B: int = 1):
    """A zero-argument function doing one view step of ``case`` (reset when episodes end);
    the vector and SB3 views step ``B`` swarms at once, the others one."""
    kw = {"preset": "paper", "n_uavs": N, "max_cycles": 10**9}
    if case in ("parallel", "aec"):
        env = pf.parallel_env(**kw) if case == "parallel" else pf.env(**kw)
        env.reset(seed=0)
        agents = list(env.agents) if case == "parallel" else list(env.possible_agents)
        act = {a: np.full(env.action_space(a).shape, 0.1, np.float32) for a in agents}
        if case == "parallel":
            return lambda: env.step(act)

        def cycle():
            for a in agents:
                env.step(act[a])

        return cycle
    if case in ("gym", "gym-pair"):
        env = _with_interface(envs.PairFlockGymEnv, "world" if case == "gym" else "pair", **kw)
        env.reset(seed=0)
        act = np.full(env.action_space.shape, 0.1, np.float32)
        return lambda: env.step(act)
    if case == "vector-pair":
        vector = importlib.import_module("pairflock_env.envs.vector")
        cls = getattr(vector, "PairFlockGymVectorEnv", None) or vector.PairFlockVectorEnv
        env = _with_interface(cls, "pair", num_envs=B, **kw)
        env.reset(seed=0)
        act = np.full(env.action_space.shape, 0.1, np.float32)
        return lambda: env.step(act)
    if case == "sb3-pair":
        sb3 = importlib.import_module("pairflock_env.envs.sb3")  # SB3: an optional dependency
        cls = getattr(sb3, "PairFlockSB3VecEnv", None) or sb3.PairFlockVecEnv
        env = _with_interface(cls, "pair", num_swarms=B, **kw)
        env.reset()
        act = np.full((env.num_envs, *env.action_space.shape), 0.1, np.float32)
        return lambda: env.step(act)
    raise ValueError(f"unknown case {case!r}; cases are {CASES}")


def worker(case: str, N: int, B: int, repeats: int, min_time: float, cpu_time: bool) -> float:
    """The median rate of ``case`` at N UAVs, in this process (the worker of a measurement)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fn = make_stepper(case, N, B)
    clock = time.process_time if cpu_time else time.perf_counter
    return median_rate(fn, 1.0, repeats, min_time, clock=clock)


def measure(tree: Path, case: str, N: int, args) -> float:
    """One subprocess measurement of ``case`` with checkout ``tree`` first on sys.path."""
    env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
    env.update(dict.fromkeys(THREADS, "1"))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", case, str(N)]
    cmd += ["--repeats", str(args.repeats), "--min-time", str(args.min_time)]
    cmd += ["--num-swarms", str(args.num_swarms)]
    cmd += ["--cpu-time"] if args.cpu_time else []
    out = subprocess.run(cmd, env=env, cwd=tree, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])["rate"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python benchmarks/bench_views.py", description=__doc__)
    ap.add_argument("--cases", nargs="+", choices=CASES, default=list(CASES))
    ap.add_argument("--n-uavs", type=int, nargs="+", default=[20, 100])
    ap.add_argument("--compare", type=Path, help="another checkout to alternate with")
    ap.add_argument(
        "--num-swarms", type=int, default=1, help="swarms per step of the vector and SB3 views"
    )
    ap.add_argument("--rounds", type=int, default=3, help="alternations (with --compare)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--min-time", type=float, default=0.2)
    ap.add_argument("--cpu-time", action="store_true", help="this process's CPU time")
    ap.add_argument("--worker", nargs=2, metavar=("CASE", "N"), help=argparse.SUPPRESS)
    ap.add_argument("--smoke", action="store_true", help="every case once, tiny (N = 8)")
    args = ap.parse_args(argv)
    if args.smoke:
        args.n_uavs, args.repeats, args.min_time, args.compare = [8], 1, 0.0, None
    if args.worker:
        case, N = args.worker[0], int(args.worker[1])
        rate = worker(case, N, args.num_swarms, args.repeats, args.min_time, args.cpu_time)
        print(json.dumps({"rate": rate}))
        return 0
    trees = {"this": ROOT} if args.compare is None else {"old": args.compare, "new": ROOT}
    rounds = args.rounds if args.compare is not None else 1
    clock = "CPU" if args.cpu_time else "wall"
    B = args.num_swarms
    print(f"# view steps/s, vector and SB3 views at B = {B}, the others at B = 1 ", end="")
    print(f"({clock} time, median of {rounds} round(s))\n")
    head = " | ".join(f"{t}" for t in trees)
    ratio = " | new/old" if args.compare is not None else ""
    print(f"| view | N | {head}{ratio} |\n|---|---|" + "---|" * (len(trees) + bool(ratio)))
    for case in args.cases:
        for N in args.n_uavs:
            got = {t: [] for t in trees}
            for _ in range(rounds):
                for t, tree in trees.items():
                    got[t].append(measure(tree, case, N, args))
            med = {t: statistics.median(v) for t, v in got.items()}
            cells = " | ".join(f"{med[t]:,.0f}" for t in trees)
            extra = f" | {med['new'] / med['old']:.2f}" if ratio else ""
            print(f"| {case} | {N} | {cells}{extra} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
