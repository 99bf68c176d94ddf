"""Speed of the particle core and of the PettingZoo API.

    python benchmarks/bench_core.py            # full grid, prints a markdown table
    python benchmarks/bench_core.py --quick    # fewer repeats

Reports UAV-steps/s (simulated UAVs x control steps per wall second) of
``PairFlockCore.step`` for N in {20, 50, 100} x B in {1, 64, 256} (medians over repeats),
env steps/s of the PettingZoo ``step()`` at B = 1, and where the time of one core step goes.
Everything runs on one thread (numba kernels are single-threaded; OMP/MKL pinned to 1).
"""

from __future__ import annotations

from baselines.evaluation.parallel import pin_threads

pin_threads()  # one thread for OpenMP/MKL/OpenBLAS/numba, before numpy loads

import argparse  # noqa: E402
import os  # noqa: E402
import platform  # noqa: E402

import numpy as np  # noqa: E402
from _timing import median_rate, print_breakdown  # noqa: E402

from pairflock_env import PairFlockCore, make_config, parallel_env  # noqa: E402
from pairflock_env.flocking import flocking_pass, pair_pass  # noqa: E402


def bench_core(N: int, B: int, repeats: int, min_time: float) -> float:
    cfg = make_config("paper", n_uavs=N, max_cycles=10**9)
    core = PairFlockCore(cfg, num_envs=B)
    core.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-0.2, 0.2, (B, core.n_agents, cfg.dim))
    return median_rate(lambda: core.step(actions), B * N, repeats, min_time)


def bench_pettingzoo(N: int, repeats: int, min_time: float) -> float:
    env = parallel_env(preset="paper", n_uavs=N, max_cycles=10**9)
    env.reset(seed=0)
    act = {a: np.full(2, 0.1, np.float32) for a in env.agents}
    return median_rate(lambda: env.step(act), 1, repeats, min_time)


def breakdown(N: int, B: int, repeats: int) -> dict[str, float]:
    """Microseconds per control step spent in each part of ``PairFlockCore.step``."""
    cfg = make_config("paper", n_uavs=N, max_cycles=10**9)
    core = PairFlockCore(cfg, num_envs=B)
    core.reset(seed=0)
    actions = np.zeros((B, core.n_agents, cfg.dim))
    lq, lp = core.leader_state()
    fl_out, pp_out = {}, {}

    def flock():
        fl_out.update(
            flocking_pass(
                core._params,
                core.q,
                core.p,
                lq,
                lp,
                core.pinned,
                core.partner_of,
                out=fl_out or None,
            )
        )

    def pairs():
        pp_out.update(
            pair_pass(
                core.q,
                core.p,
                core.agent_uavs,
                core.partner_uavs,
                cfg.radius,
                cfg.obs_neighbors,
                out=pp_out or None,
            )
        )

    def integrate():
        core.vehicle.advance(core.q.copy(), core.p.copy(), core.flock_accel)

    parts = {
        "total core.step": 1e6 / median_rate(lambda: core.step(actions), 1, repeats, 0.2),
        "flocking sweep (numba)": 1e6 / median_rate(flock, 1, repeats, 0.2),
        "pair/neighbour sweep (numba)": 1e6 / median_rate(pairs, 1, repeats, 0.2),
        "integration (numpy)": 1e6 / median_rate(integrate, 1, repeats, 0.2),
    }
    # the rest of the step, by difference: parts timed alone can add up to a little more than
    # the whole (cache effects, timing noise), so the difference is floored at 0
    parts["the rest: observations, rewards, infos (numpy)"] = max(
        0.0, parts["total core.step"] - sum(v for k, v in parts.items() if k != "total core.step")
    )
    return parts


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python benchmarks/bench_core.py",
        description=__doc__.split("\n\n")[0] + " Prints medians over repeats.",
    )
    ap.add_argument(
        "--quick", action="store_true", help="3 repeats of >= 0.2 s instead of 7 x 0.5 s"
    )
    ap.add_argument("--n-uavs", type=int, nargs="+", default=[20, 50, 100])
    ap.add_argument("--batch", type=int, nargs="+", default=[1, 64, 256])
    args = ap.parse_args(argv)
    repeats, min_time = (3, 0.2) if args.quick else (7, 0.5)

    print(
        f"# pairflock_env core speed ({platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} cores visible, 1 thread used)\n"
    )
    print("## Core `PairFlockCore.step`: UAV-steps/s (median)\n")
    print("| N \\ B | " + " | ".join(str(b) for b in args.batch) + " |")
    print("|---|" + "---|" * len(args.batch))
    for N in args.n_uavs:
        cells = [f"{bench_core(N, B, repeats, min_time):,.0f}" for B in args.batch]
        print(f"| {N} | " + " | ".join(cells) + " |")
    print("\n## PettingZoo `parallel_env.step()` at B = 1: env steps/s (median)\n")
    print("| N | steps/s | UAV-steps/s |\n|---|---|---|")
    for N in args.n_uavs:
        r = bench_pettingzoo(N, repeats, min_time)
        print(f"| {N} | {r:,.0f} | {r * N:,.0f} |")
    for N, B in ((100, 256), (100, 1)):
        print_breakdown(f"Where the time goes: N = {N}, B = {B}", breakdown(N, B, repeats))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
