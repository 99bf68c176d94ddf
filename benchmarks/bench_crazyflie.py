"""Real-time factor of ``dynamics="crazyflie"`` on one thread, for 10 and 49 Crazyflies.

    python benchmarks/bench_crazyflie.py            # 10 s simulated x 9 repeats per figure
    python benchmarks/bench_crazyflie.py --quick    # 1 s x 3 repeats (seconds)
    python benchmarks/bench_crazyflie.py --cpu-time # this process's CPU time, not wall time

Per swarm size, interleaved (one repeat of every timer, then the next repeat) so that the
load of a shared machine hits all of them alike, medians over the repeats:

* the vehicle model alone (``advance`` under a held a_des), at the default 500 Hz plant and
  at 1 kHz, and the project's quadrotor model (500 Hz) for the ratio;
* the batched core (B = 1) with the sliding-mode controller's ``predict`` in the loop, with
  the Crazyflie and with the quadrotor;
* the PettingZoo ``parallel_env`` (B = 1) with the sliding-mode controller and the safety
  filter on, with the Crazyflie.

The real-time factor is simulated seconds per wall second (the issue asks >= 10 for 10
Crazyflies). Every thread count is pinned to 1 before numpy loads. On a shared machine
``--cpu-time`` (the process's CPU time) is steadier than the wall clock.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import numpy as np  # noqa: E402

from baselines.controllers import make_pair_policy  # noqa: E402
from pairflock_env import PairFlockCore, make_config, parallel_env  # noqa: E402
from pairflock_env.dynamics import make_vehicle  # noqa: E402

#: the clock of every timer (``--cpu-time``: time.process_time)
CLOCK = [time.perf_counter]
#: the scenario timed (its 10 UAVs; 49 with the start box grown at the same density)
PRESET = "crazyflie"


def config(n: int, dynamics: str, **kw):
    """The scenario with n UAVs flown by ``dynamics`` (the start box grows as n^(1/3))."""
    base = make_config(PRESET)
    grow = (n / base.n_uavs) ** (1.0 / 3.0)
    half = tuple(grow * np.asarray(base.swarm_half_width))
    kw = dict(n_uavs=n, dynamics=dynamics, swarm_half_width=half, max_cycles=10**9, **kw)
    if dynamics == "quadrotor":
        kw["quad_ground_altitude"] = None
    return make_config(PRESET, **kw)


def vehicle_timer(cfg, steps: int) -> Callable[[], float]:
    """Wall seconds of ``steps`` periods of the vehicle model alone under a held a_des."""
    m = make_vehicle(cfg, 1)
    N = cfg.n_uavs
    q = np.zeros((1, N, 3))
    q[..., 0], q[..., 2] = np.arange(N), 1.0
    p = np.zeros_like(q)
    m.reset_rows(np.arange(1), q, p)
    a = np.random.default_rng(0).normal(0.0, 0.5, (steps, 1, N, 3))

    def once() -> float:
        m.reset_rows(np.arange(1), q, p)
        t0 = CLOCK[0]()
        for k in range(steps):
            m.advance(q, p, a[k])
        return CLOCK[0]() - t0

    return once


def core_timer(cfg, steps: int) -> Callable[[], float]:
    """Wall seconds of ``steps`` core steps (B = 1) with the sliding-mode controller."""
    core = PairFlockCore(cfg, num_swarms=1)
    pol = make_pair_policy("smc", cfg)
    M = core.n_agents

    def once() -> float:
        res = core.reset(seed=[0])
        t0 = CLOCK[0]()
        for _ in range(steps):
            a, _ = pol.predict(res.obs.reshape(M, -1))
            res = core.step(a.reshape(1, M, -1))
        return CLOCK[0]() - t0

    return once


def pettingzoo_timer(cfg_kw: dict, steps: int) -> Callable[[], float]:
    """Wall seconds of ``steps`` parallel_env steps with the sliding-mode controller."""
    env = parallel_env(**cfg_kw)
    pol = make_pair_policy("smc", env)

    def once() -> float:
        obs, _ = env.reset(seed=0)
        t0 = CLOCK[0]()
        for _ in range(steps):
            obs = env.step({a: pol.predict(o)[0] for a, o in obs.items()})[0]
        return CLOCK[0]() - t0

    return once


def timers(n: int, steps: int) -> dict[str, Callable[[], float]]:
    cf, quad = config(n, "crazyflie"), config(n, "quadrotor")
    pz = dict(preset=PRESET, n_uavs=n, dynamics="crazyflie", safety_filter="cbf")
    pz.update(swarm_half_width=cf.swarm_half_width, max_cycles=10**9)
    return {
        "Crazyflie model alone (500 Hz plant)": vehicle_timer(cf, steps),
        "Crazyflie model alone (1 kHz plant)": vehicle_timer(cf.replace(substeps=20), steps),
        "quadrotor model alone (500 Hz)": vehicle_timer(quad, steps),
        "core + smc, Crazyflie": core_timer(cf, steps),
        "core + smc, quadrotor": core_timer(quad, steps),
        "parallel_env + smc + cbf filter, Crazyflie": pettingzoo_timer(pz, steps),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="1 s simulated x 3 repeats")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 49], help="swarm sizes")
    ap.add_argument("--cpu-time", action="store_true", help="time with this process's CPU time")
    args = ap.parse_args(argv)
    if args.cpu_time:
        CLOCK[0] = time.process_time
    sim, repeats = (1.0, 3) if args.quick else (10.0, 9)
    dt = make_config(PRESET).dt
    steps = round(sim / dt)
    clock = "CPU time" if args.cpu_time else "wall time"
    print(f"# Crazyflie speed ({platform.machine()}, one thread, {clock})\n")
    print(f"{steps} control steps of {dt} s ({sim:g} s simulated) x {repeats} repeats, medians\n")
    print("| N | what | ms per simulated s | real-time factor |\n|---|---|---|---|")
    for n in args.sizes:
        tm = timers(n, steps)
        for t in tm.values():  # compile and warm up
            t()
        times: dict[str, list[float]] = {k: [] for k in tm}
        for _ in range(repeats):
            for k, t in tm.items():
                times[k].append(t())
        for k, v in times.items():
            med = statistics.median(v)
            print(f"| {n} | {k} | {1000 * med / sim:.2f} | {sim / med:,.0f}x |")


if __name__ == "__main__":
    main()
