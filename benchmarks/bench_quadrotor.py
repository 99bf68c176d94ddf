"""Speed of the quadrotor env: the paper-quadrotor scenario (10 UAVs, 50 Hz protocol, 500 Hz
physics) through the public PettingZoo API at B = 1 and through the batched core at B = 64.

    python benchmarks/bench_quadrotor.py            # 7 repeats of >= 0.5 s per figure
    python benchmarks/bench_quadrotor.py --quick    # 3 repeats of >= 0.2 s
    python benchmarks/bench_quadrotor.py --large    # 1,000 quadrotors: real-time factor
    python benchmarks/bench_quadrotor.py --smoke    # every part once, tiny (checks the script)

Reports simulated seconds per wall second (B = 1; targets >= 20, i.e. 20 x real time) and
swarm-seconds per wall second (B swarms x simulated seconds; target >= 300 at B = 64), as
medians over repeats, and where the time of one control step goes. Everything runs on one
thread: numba kernels are single-threaded and OMP/MKL/NUMBA threads are pinned to 1 before
numpy is imported (nothing here imports torch).
"""

from __future__ import annotations

from baselines.runtime.threads import pin_threads

pin_threads()  # one thread for OpenMP/MKL/OpenBLAS/numba, before numpy loads

import argparse  # noqa: E402
import os  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from _timing import median_rate, print_breakdown  # noqa: E402

from baselines import make_pair_policy  # noqa: E402
from baselines.runtime.cli import ArgumentParser, at_least  # noqa: E402
from pairflock_env import PairFlockCore, make_config, parallel_env  # noqa: E402
from pairflock_env.dynamics.quadrotor import QuadrotorModel  # noqa: E402
from pairflock_env.swarm.flocking import flocking_params, flocking_pass  # noqa: E402
from pairflock_env.swarm.pair_pass import pair_pass  # noqa: E402
from pairflock_env.swarm.passes import NeighborPass  # noqa: E402

PRESET = "paper-quadrotor"
TARGET_B1 = 20.0  # simulated s per wall s at B = 1 through PettingZoo
TARGET_B64 = 300.0  # swarm-s per wall s at B = 64 through the core


def _config(**overrides):
    # long enough that no episode ends inside a timing loop
    return make_config(PRESET, max_cycles=10**9, **overrides)


def bench_pettingzoo(repeats: int, min_time: float, with_policy: bool) -> float:
    """Simulated seconds per wall second of ``parallel_env.step`` (optionally with the
    sliding-mode controller's ``predict`` for both agents in the loop)."""
    env = parallel_env(preset=PRESET, max_cycles=10**9)
    obs, _ = env.reset(seed=0)
    dt = env.config.dt
    state = {"obs": obs}
    if with_policy:
        pol = make_pair_policy("smc", env)

        def step():
            act = {a: pol.predict(o)[0] for a, o in state["obs"].items()}
            state["obs"] = env.step(act)[0]
    else:
        act = {a: np.full(3, 0.05, np.float32) for a in env.agents}

        def step():
            env.step(act)

    return median_rate(step, dt, repeats, min_time)


def bench_core(B: int, repeats: int, min_time: float, dynamics: str = "quadrotor") -> float:
    """Swarm-seconds per wall second of ``PairFlockCore.step`` with B swarms."""
    cfg = _config(dynamics=dynamics)
    core = PairFlockCore(cfg, num_swarms=B)
    core.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-0.2, 0.2, (B, core.n_agents, 3))
    return median_rate(lambda: core.step(actions), B * cfg.dt, repeats, min_time)


def bench_bare_model(B: int, repeats: int, min_time: float) -> float:
    """Swarm-seconds per wall second of the quadrotor kernel alone under a held command."""
    cfg = _config()
    model = QuadrotorModel(cfg, B)
    q = np.zeros((B, cfg.n_uavs, 3))
    q[..., 0] = 3.0 * np.arange(cfg.n_uavs)
    q[..., 2] = 20.0
    p = np.zeros_like(q)
    model.reset_rows(np.arange(B), q, p)
    a = np.random.default_rng(0).uniform(-1.0, 1.0, q.shape)
    return median_rate(lambda: model.advance(q, p, a), B * cfg.dt, repeats, min_time)


def large_config(N: int):
    """The quadrotor scenario with N UAVs at the preset's start density: the box
    (6, 6, 1.5) m for 10 UAVs scaled by (N / 10)^(1/3) on each axis."""
    scale = (N / 10) ** (1 / 3)
    return _config(n_uavs=N, swarm_half_width=(6.0 * scale, 6.0 * scale, 1.5 * scale))


def bench_large(N: int, repeats: int, min_time: float, clock=time.perf_counter):
    """Real-time factor (simulated s per wall s, or per CPU s with ``clock=process_time``) of
    N quadrotors at B = 1: the core step and the PettingZoo ``step()``."""
    cfg = large_config(N)
    core = PairFlockCore(cfg)
    core.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-0.2, 0.2, (1, core.n_agents, 3))
    r_core = median_rate(lambda: core.step(actions), cfg.dt, repeats, min_time, clock)
    env = parallel_env(config=cfg)
    env.reset(seed=0)
    act = {a: np.full(3, 0.05, np.float32) for a in env.agents}
    r_env = median_rate(lambda: env.step(act), cfg.dt, repeats, min_time, clock)
    return r_core, r_env


def large_breakdown(N: int, repeats: int, min_time: float, clock) -> dict[str, float]:
    """Microseconds per control step of N quadrotors at B = 1, by part (timed on the reset
    state, the core step over 20-step rollouts from it)."""
    cfg = large_config(N)
    core = PairFlockCore(cfg)
    core.reset(seed=0)
    q, p, a_des = core.q.copy(), core.p.copy(), core.flock_accel.copy()
    lq, lp = core.leader_state()
    acts = np.zeros((1, core.n_agents, 3))

    def us(fn):
        return 1e6 / median_rate(fn, 1.0, repeats, min_time, clock)

    steps = []
    for _ in range(repeats + 1):  # the first rollout warms up
        core.reset(seed=0)
        t0 = clock()
        for _ in range(20):
            core.step(acts)
        steps.append((clock() - t0) / 20)
    core.reset(seed=0)
    npass = NeighborPass(cfg, 1)
    parts = {"total core.step": 1e6 * statistics.median(steps[1:])}
    parts["quadrotor: substeps of controller + mixer + motors + rigid body (numba)"] = us(
        lambda: core.vehicle.advance(q.copy(), p.copy(), a_des)
    )
    parts["neighbour pass: grid build, flocking and pair passs (numba)"] = us(
        lambda: npass.run(core.q, core.p, lq, lp, core.pinned)
    )
    parts["rest: checks, observations, rewards, infos (numpy)"] = max(
        0.0, parts["total core.step"] - sum(v for k, v in parts.items() if k != "total core.step")
    )
    return parts


def large_report(sizes, repeats: int, min_time: float, cpu_time: bool) -> None:
    """``--large``: the real-time factor of each swarm size, then where its time goes."""
    clock = time.process_time if cpu_time else time.perf_counter
    print("| N | search | core x real time | PettingZoo x real time |\n|---|---|---|---|")
    for N in sizes:
        r_core, r_env = bench_large(N, repeats, min_time, clock)
        search = "grid" if large_config(N).uses_grid else "all pairs"
        print(f"| {N:,} | {search} | {r_core:.2f} | {r_env:.2f} |")
    for N in sizes:
        parts = large_breakdown(N, repeats, min_time, clock)
        print_breakdown(f"Where the time goes: {N:,} quadrotors, B = 1", parts)


def _pass_timers(core: PairFlockCore, cfg) -> tuple:
    """The flocking pass and the pair pass of ``core``'s state, as zero-argument functions."""
    lq, lp = core.leader_state()
    params = flocking_params(cfg)
    fl_out, pp_out = {}, {}

    def flock():
        args = (core.q, core.p, lq, lp, core.pinned, core.partner_of)
        fl_out.update(flocking_pass(params, *args, out=fl_out or None))

    def pairs():
        args = (core.q, core.p, core.agent_uavs, core.partner_uavs, cfg.radius)
        pp_out.update(pair_pass(*args, cfg.obs_neighbors, out=pp_out or None))

    return flock, pairs


def breakdown(B: int, repeats: int, min_time: float) -> dict[str, float]:
    """Microseconds per control step in each part of one step (B swarms); at B = 1 also the
    PettingZoo layer on top of the core."""
    cfg = _config()
    core = PairFlockCore(cfg, num_swarms=B)
    core.reset(seed=0)
    actions = np.zeros((B, core.n_agents, 3))
    q, p = core.q.copy(), core.p.copy()
    a_des = core.flock_accel.copy()
    flock, pairs = _pass_timers(core, cfg)

    def us(fn):
        return 1e6 / median_rate(fn, 1.0, repeats, min_time)

    parts = {"total core.step": us(lambda: core.step(actions))}
    if B == 1:
        env = parallel_env(preset=PRESET, max_cycles=10**9)
        env.reset(seed=0)
        act = {ag: np.zeros(3, np.float32) for ag in env.agents}
        parts["PettingZoo layer (dicts, checks, infos)"] = (
            us(lambda: env.step(act)) - parts["total core.step"]
        )
    parts["quadrotor: 10 substeps of controller + mixer + motors + rigid body (numba)"] = us(
        lambda: core.vehicle.advance(q, p, a_des)
    )
    parts["quadrotor info() (numpy)"] = us(core.vehicle.info)
    parts["flocking pass (numba)"] = us(flock)
    parts["pair/neighbour pass (numba)"] = us(pairs)
    parts["climb-and-turn leader state (numba)"] = us(lambda: core.leader_state())
    inner = [k for k in parts if k not in ("total core.step",) and not k.startswith("PettingZoo")]
    parts["rest of core.step: checks, observations, rewards, infos (numpy)"] = parts[
        "total core.step"
    ] - sum(parts[k] for k in inner)
    return parts


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python benchmarks/bench_quadrotor.py``."""
    ap = ArgumentParser(
        prog="python benchmarks/bench_quadrotor.py",
        description=__doc__.split("\n\n")[0] + " Prints medians over repeats.",
    )
    ap.add_argument(
        "--quick", action="store_true", help="3 repeats of >= 0.2 s instead of 7 x 0.5 s"
    )
    ap.add_argument(
        "--batch",
        type=at_least(1),
        nargs="+",
        default=[1, 16, 64, 256],
        help="numbers of swarms B for the core table",
    )
    ap.add_argument(
        "--large",
        type=at_least(2),
        nargs="*",
        metavar="N",
        help="only the real-time factor of N quadrotors (default N = 1,000) at B = 1",
    )
    ap.add_argument(
        "--cpu-time",
        action="store_true",
        help="with --large: per CPU second of this process (steadier on a shared machine)",
    )
    ap.add_argument(
        "--smoke",
        action="store_true",
        help="every part once, tiny (B = 1, 12 quadrotors for --large): checks the script",
    )
    return ap


def main(argv=None) -> int:
    """Print the tables (or ``--large``'s); returns the exit status."""
    args = build_parser().parse_args(argv)
    repeats, min_time = (3, 0.2) if args.quick else (7, 0.5)
    if args.smoke:
        repeats, min_time, args.batch = 1, 0.0, [1]
        large_report([12], repeats, min_time, args.cpu_time)
    elif args.large is not None:
        large_report(args.large or [1000], repeats, min_time, args.cpu_time)
        return 0
    cfg = _config()
    print(
        f"# pairflock_env quadrotor speed ({platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} cores visible, 1 thread used)\n"
    )
    print(
        f"Preset `{PRESET}`: N = {cfg.n_uavs}, protocol every {cfg.dt:g} s, physics every "
        f"{cfg.physics_dt:g} s ({1 / cfg.physics_dt:.0f} Hz, {cfg.substeps} substeps).\n"
    )
    pettingzoo_table(repeats, min_time)
    core_table(args.batch, repeats, min_time)
    for B in (1,) if args.smoke else (1, 64):
        print_breakdown(
            f"Where the time goes, B = {B}", breakdown(B, repeats, min_time), "share of core.step"
        )
    return 0


def pettingzoo_table(repeats: int, min_time: float) -> None:
    """B = 1 through the PettingZoo API, with and without the controller, and the bare model."""
    print("## B = 1 through the PettingZoo API (simulated s per wall s, median)\n")
    print("| loop | x real time | target |\n|---|---|---|")
    r_env = bench_pettingzoo(repeats, min_time, with_policy=False)
    r_pol = bench_pettingzoo(repeats, min_time, with_policy=True)
    ok = "met" if r_env >= TARGET_B1 else "NOT met"
    print(f"| `env.step` (fixed actions) | {r_env:.1f} | >= {TARGET_B1:g} ({ok}) |")
    print(f"| `env.step` + sliding-mode `predict` for both agents | {r_pol:.1f} | - |")
    bare = bench_bare_model(1, repeats, min_time)
    print(f"| quadrotor kernel alone (10 UAVs, no env) | {bare:.1f} | - |")


def core_table(batches, repeats: int, min_time: float) -> None:
    """The batched core, quadrotor and particle, for every B."""
    print("\n## Batched core `PairFlockCore.step` (swarm-seconds per wall s, median)\n")
    print("| B | quadrotor | particle (same scenario) |\n|---|---|---|")
    for B in batches:
        rq = bench_core(B, repeats, min_time)
        rp = bench_core(B, repeats, min_time, dynamics="particle")
        met = "met" if rq >= TARGET_B64 else "NOT met"
        mark = f" (target >= {TARGET_B64:g}: {met})" if B == 64 else ""
        print(f"| {B} | {rq:,.0f}{mark} | {rp:,.0f} |")


if __name__ == "__main__":
    raise SystemExit(main())
