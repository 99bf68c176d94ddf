"""Speed of the particle core, of the neighbour kernels and of the PettingZoo API.

    python benchmarks/bench_core.py            # everything, prints markdown tables
    python benchmarks/bench_core.py --quick    # fewer repeats
    python benchmarks/bench_core.py --sections kernels   # only the neighbour kernels
    python benchmarks/bench_core.py --sections large     # full core step, N up to 10,000
    python benchmarks/bench_core.py --sections threshold # where "auto" switches to the grid

Reports UAV-steps/s (simulated UAVs x control steps per wall second) of
``PairFlockCore.step`` for N in {20, 50, 100} x B in {1, 64, 256} (medians over repeats),
env steps/s of the PettingZoo ``step()`` at B = 1, where the time of one core step goes, and
the neighbour kernels alone (flocking and pair passs, plus the grid build on the grid path)
with all pairs and with the grid, for N up to 10,000; the full core step of large swarms with
each ``neighbor_search`` (``large``) and the crossover that sets "auto" (``threshold``).
Everything runs on one thread (numba kernels are single-threaded; OMP/MKL pinned to 1).
"""

from __future__ import annotations

from baselines.runtime.threads import pin_threads

pin_threads()  # one thread for OpenMP/MKL/OpenBLAS/numba, before numpy loads

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import os  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from _timing import median_rate, print_breakdown  # noqa: E402

from baselines.runtime.cli import ArgumentParser, at_least  # noqa: E402
from pairflock_env import PairFlockCore, make_config, parallel_env  # noqa: E402
from pairflock_env.swarm.flocking import flocking_params, flocking_pass  # noqa: E402
from pairflock_env.swarm.grid import NeighborGrid  # noqa: E402
from pairflock_env.swarm.pair_pass import pair_pass  # noqa: E402
from pairflock_env.swarm.spacing import place  # noqa: E402

SECTIONS = ("core", "pettingzoo", "breakdown", "kernels", "large", "threshold")
_CLOCK = {"clock": time.perf_counter}  # --cpu-time switches to time.process_time


def rate(fn, work: float, repeats: int, min_time: float) -> float:
    """:func:`median_rate` with the clock chosen on the command line."""
    return median_rate(fn, work, repeats, min_time, clock=_CLOCK["clock"])


def _search(search: str | None) -> dict:
    # keyword only when asked, so that the core section runs against checkouts without it
    return {} if search is None else {"neighbor_search": search}


def bench_core(N: int, B: int, repeats: int, min_time: float, search: str | None = None) -> float:
    """UAV-steps/s of ``PairFlockCore.step`` from the reset state of the paper preset with
    N UAVs (start box grown with N), under small random pair actions."""
    cfg = make_config("paper", n_uavs=N, max_cycles=10**9, **_search(search))
    core = PairFlockCore(cfg, num_swarms=B)
    core.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-0.2, 0.2, (B, core.n_agents, cfg.dim))
    return rate(lambda: core.step(actions), B * N, repeats, min_time)


def bench_pettingzoo(N: int, repeats: int, min_time: float) -> float:
    env = parallel_env(preset="paper", n_uavs=N, max_cycles=10**9)  # "auto" search
    env.reset(seed=0)
    act = {a: np.full(2, 0.1, np.float32) for a in env.agents}
    return rate(lambda: env.step(act), 1, repeats, min_time)


def breakdown(N: int, B: int, repeats: int, search: str | None = None) -> dict[str, float]:
    """Microseconds per control step spent in each part of ``PairFlockCore.step``."""
    cfg = make_config("paper", n_uavs=N, max_cycles=10**9, **_search(search))
    core = PairFlockCore(cfg, num_swarms=B)
    core.reset(seed=0)
    lq, lp = core.leader_state()
    params = flocking_params(cfg)
    fl_out, pp_out = {}, {}
    grid = core.neighbor_grid

    def build():
        grid.build(core.q)

    def flock():
        args = (core.q, core.p, lq, lp, core.pinned, core.partner_of)
        fl_out.update(flocking_pass(params, *args, out=fl_out or None, grid=grid))

    def pairs():
        args = (core.q, core.p, core.agent_uavs, core.partner_uavs, cfg.radius)
        pp_out.update(pair_pass(*args, cfg.obs_neighbors, out=pp_out or None, grid=grid))

    def integrate():
        core.vehicle.advance(core.q.copy(), core.p.copy(), core.flock_accel)

    parts = {
        # rollouts from the reset state, the state the parts below are timed on
        "total core.step": 1e6 * B * N / bench_rollout(N, B, search, "start", repeats),
    }
    if grid is not None:
        parts["grid build (numba)"] = 1e6 / rate(build, 1, repeats, 0.2)
    parts |= {
        "flocking pass (numba)": 1e6 / rate(flock, 1, repeats, 0.2),
        "pair/neighbour pass (numba)": 1e6 / rate(pairs, 1, repeats, 0.2),
        "integration (numpy)": 1e6 / rate(integrate, 1, repeats, 0.2),
    }
    # the rest of the step, by difference: parts timed alone can add up to a little more than
    # the whole (cache effects, timing noise), so the difference is floored at 0
    parts["the rest: observations, rewards, infos (numpy)"] = max(
        0.0, parts["total core.step"] - sum(v for k, v in parts.items() if k != "total core.step")
    )
    return parts


def kernel_state(kind: str, N: int, B: int, seed: int = 0):
    """Positions and velocities (B, N, 2) of the paper's swarm scaled to N UAVs.

    ``"start"``: the paper's start density (50 UAVs in a 100 m square) kept for every N, the
    box growing as sqrt(N), placed with the 2 m minimum spacing: sparse, most UAVs with 0-2
    neighbours. ``"flock"``: a hexagonal lattice at the spacing d = 7 m jittered by 0.3 m, the
    alpha-lattice the protocol converges to (about 6 neighbours each).
    """
    rng = np.random.default_rng(seed)
    qs = []
    for _ in range(B):
        if kind == "start":
            half = np.full((N, 1), 50.0 * np.sqrt(N / 50))
            q = place(rng, half, np.zeros((N, 2)), np.zeros(N, bool), 2.0, np.zeros(2))
        else:
            n = int(np.ceil(np.sqrt(N)))
            i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
            lattice = np.stack([i + 0.5 * (j % 2), j * np.sqrt(3) / 2], -1).reshape(-1, 2)
            q = 7.0 * lattice[:N] + rng.normal(0.0, 0.3, (N, 2))
        qs.append(q)
    return np.ascontiguousarray(qs), rng.normal(0.0, 1.0, (B, N, 2))


def bench_kernels(kind: str, N: int, B: int, grid: bool, repeats: int, min_time: float) -> float:
    """UAV-steps/s of the neighbour kernels of one step (all pairs, or grid build + passes)."""
    cfg = make_config("paper", n_uavs=N)
    prm = flocking_params(cfg)
    q, p = kernel_state(kind, N, B)
    lq, lp, pinned = np.zeros((B, 2)), np.zeros((B, 2)), np.ones((B, N))
    agents, partners = np.array([0, 1]), np.array([1, 0])
    partner = np.full(N, -1, np.int64)
    partner[agents] = partners
    g = NeighborGrid(B, N, 2, max(cfg.radius, cfg.collision_distance)) if grid else None
    fl = pp = None

    def step():
        nonlocal fl, pp
        if g is not None:
            g.build(q)
        fl = flocking_pass(prm, q, p, lq, lp, pinned, partner, out=fl, grid=g)
        pp = pair_pass(q, p, agents, partners, cfg.radius, cfg.obs_neighbors, out=pp, grid=g)

    return rate(step, B * N, repeats, min_time)


@dataclasses.dataclass(frozen=True)
class Sizes:
    """The swarm sizes (N, B) of the sections; :data:`SMOKE` runs every section tiny."""

    kernels: tuple[tuple[int, int], ...] = (
        (100, 1), (300, 1), (1000, 1), (3000, 1), (10000, 1), (1000, 16), (50, 256), (100, 256),
    )  # fmt: skip
    large: tuple[tuple[int, int], ...] = ((300, 1), (1000, 1), (3000, 1), (10000, 1), (1000, 16))
    #: per-UAV cost compared between these two (B = 1)
    small_big: tuple[int, int] = (300, 10000)
    auto: tuple[int, int] = (100, 256)  # auto vs all pairs, alternated
    threshold_n: tuple[int, ...] = (100, 150, 200, 250, 300, 500)
    threshold_b: tuple[int, ...] = (1, 64)
    breakdown: tuple[tuple[int, int], ...] = ((100, 256), (100, 1))


FULL = Sizes()
SMOKE = Sizes(
    kernels=((8, 1), (12, 1)),
    large=((8, 1), (12, 1)),
    small_big=(8, 12),
    auto=(8, 2),
    threshold_n=(8,),
    threshold_b=(1,),
    breakdown=((8, 1),),
)


def kernel_tables(repeats: int, min_time: float, sizes: Sizes = FULL) -> None:
    small, big = sizes.small_big
    for kind in ("start", "flock"):
        print(
            f"\n## Neighbour kernels alone, {kind} state: UAV-steps/s (median)\n\n"
            "| N | B | all pairs | grid | grid / all pairs |\n|---|---|---|---|---|"
        )
        rates = {}
        for N, B in sizes.kernels:
            a = bench_kernels(kind, N, B, False, repeats, min_time)
            g = rates[N, B] = bench_kernels(kind, N, B, True, repeats, min_time)
            print(f"| {N:,} | {B} | {a:,.0f} | {g:,.0f} | {g / a:.1f}x |")
        ratio = rates[small, 1] / rates[big, 1]
        print(f"\nGrid: per-UAV cost at N = {big:,} / at N = {small} (B = 1): {ratio:.2f}")


#: the all-pairs core at N = 100, B = 256 before the grid was integrated (UAV-steps/s,
#: bench_core.py --sections core at commit f107d5b, this machine)
ALL_PAIRS_N100_B256 = 3_071_349
#: control steps of one timed rollout: 0.2 s of flight, so the state timed is the one asked
#: for (a swarm pinned to one leader contracts: after 8 s of flight 10,000 UAVs are packed
#: far denser than the lattice, and every step costs more)
ROLLOUT_STEPS = 20


def start_options(kind: str, N: int, B: int) -> dict | None:
    """Reset options of a large-swarm state: ``"start"`` (None: the config's random start,
    sparse) or ``"flock"`` (the jittered alpha-lattice of :func:`kernel_state`, centred)."""
    if kind == "start":
        return None
    q, _ = kernel_state("flock", N, B)
    return {"positions": q - q.mean(axis=1, keepdims=True)}


def bench_rollout(
    N: int, B: int, search: str | None, kind: str, repeats: int, steps: int = ROLLOUT_STEPS
) -> float:
    """UAV-steps/s of ``steps`` core steps from state ``kind`` (reset untimed), the median
    over ``repeats`` rollouts (after one untimed rollout that compiles and warms up)."""
    cfg = make_config("paper", n_uavs=N, max_cycles=10**9, **_search(search))
    core = PairFlockCore(cfg, num_swarms=B)
    actions = np.random.default_rng(0).uniform(-0.2, 0.2, (B, core.n_agents, cfg.dim))
    options = start_options(kind, N, B)
    rates = []
    for _ in range(repeats + 1):
        core.reset(seed=0, options=options)
        t0 = _CLOCK["clock"]()
        for _ in range(steps):
            core.step(actions)
        rates.append(B * N * steps / (_CLOCK["clock"]() - t0))
    return statistics.median(rates[1:])


def pettingzoo_rollout(N: int, repeats: int, steps: int = ROLLOUT_STEPS) -> float:
    """Env steps/s of ``parallel_env.step()`` (defaults, N UAVs) over rollouts from reset."""
    env = parallel_env(preset="paper", n_uavs=N, max_cycles=10**9)
    rates = []
    for _ in range(repeats + 1):
        env.reset(seed=0)
        act = {a: np.full(2, 0.1, np.float32) for a in env.agents}
        t0 = _CLOCK["clock"]()
        for _ in range(steps):
            env.step(act)
        rates.append(steps / (_CLOCK["clock"]() - t0))
    return statistics.median(rates[1:])


def large_tables(repeats: int, min_time: float, sizes: Sizes = FULL) -> None:
    """The full core step of large swarms with both searches; ratios from this one run."""
    small, big = sizes.small_big
    for kind in ("start", "flock"):
        print(
            f"\n## Core `PairFlockCore.step` of large swarms, {kind} state: UAV-steps/s "
            f"(median of {repeats} rollouts of {ROLLOUT_STEPS} steps)\n\n"
            "| N | B | all pairs | grid | grid / all pairs |\n|---|---|---|---|---|"
        )
        grid = {}
        for N, B in sizes.large:
            slow = N * N * B > 2e7  # all pairs at N = 10,000: ~0.1 s a step, one rollout
            a = bench_rollout(N, B, "all_pairs", kind, 1 if slow else repeats)
            g = grid[N, B] = bench_rollout(N, B, "grid", kind, repeats)
            print(f"| {N:,} | {B} | {a:,.0f} | {g:,.0f} | {g / a:.1f}x |")
        ratio = grid[small, 1] / grid[big, 1]
        print(
            f"\nGrid, {kind} state: per-UAV cost at N = {big:,} / at N = {small} (B = 1): "
            f"{ratio:.2f}"
        )
    # the same code path (auto is all pairs at N = 100): alternate them, so that a change of
    # load on a shared machine hits both alike
    N, B = sizes.auto
    runs = [bench_core(N, B, repeats, min_time, s) for s in ("auto", "all_pairs") * 3]
    auto, pairs = statistics.median(runs[0::2]), statistics.median(runs[1::2])
    print(
        f"\nN = {N}, B = {B}: auto {auto:,.0f}, all pairs {pairs:,.0f} UAV-steps/s "
        f"(all pairs before the grid, N = 100, B = 256: {ALL_PAIRS_N100_B256:,})"
    )
    r = pettingzoo_rollout(big, repeats)
    print(f"PettingZoo step() at N = {big:,}: {r:,.1f} steps/s ({r * big:,.0f} UAV-steps/s)")
    title = f"Where the time goes: N = {big:,}, B = 1, grid"
    print_breakdown(title, breakdown(big, 1, repeats))


def threshold_table(repeats: int, min_time: float, sizes: Sizes = FULL) -> None:
    """Core step with each search around the crossover (B = 1 and B = 64, start and flock
    states): where "auto" switches to the grid."""
    print(
        f"\n## Crossover of the searches: core UAV-steps/s (median of {repeats} rollouts of "
        f"{ROLLOUT_STEPS} steps)\n\n"
        "| N | B | state | all pairs | grid | grid / all pairs |\n|---|---|---|---|---|---|"
    )
    for N in sizes.threshold_n:
        for B in sizes.threshold_b:
            for kind in ("start", "flock"):
                a = bench_rollout(N, B, "all_pairs", kind, repeats)
                g = bench_rollout(N, B, "grid", kind, repeats)
                print(f"| {N} | {B} | {kind} | {a:,.0f} | {g:,.0f} | {g / a:.2f}x |")


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python benchmarks/bench_core.py``."""
    ap = ArgumentParser(
        prog="python benchmarks/bench_core.py",
        description=__doc__.split("\n\n")[0] + " Prints medians over repeats.",
    )
    ap.add_argument(
        "--quick", action="store_true", help="3 repeats of >= 0.2 s instead of 7 x 0.5 s"
    )
    ap.add_argument("--n-uavs", type=at_least(2), nargs="+", default=[20, 50, 100])
    ap.add_argument("--batch", type=at_least(1), nargs="+", default=[1, 64, 256])
    ap.add_argument(
        "--sections",
        nargs="+",
        choices=SECTIONS,
        default=list(SECTIONS[:4]),
        help="what to run (default: the first four)",
    )
    ap.add_argument(
        "--cpu-time",
        action="store_true",
        help="time with this process's CPU time instead of wall time (steadier when shared)",
    )
    ap.add_argument(
        "--smoke",
        action="store_true",
        help="every section once, tiny (N <= 12): checks the script, measures nothing",
    )
    return ap


def main(argv=None) -> int:
    """Run the sections asked for and print their tables; returns the exit status."""
    args = build_parser().parse_args(argv)
    repeats, min_time = (3, 0.2) if args.quick else (7, 0.5)
    sizes = FULL
    if args.smoke:
        repeats, min_time, sizes = 1, 0.0, SMOKE
        args.n_uavs, args.batch, args.sections = [8], [1], list(SECTIONS)
    _CLOCK["clock"] = time.process_time if args.cpu_time else time.perf_counter
    print(
        f"# pairflock_env core speed ({platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} cores visible, 1 thread used, "
        f"{'CPU' if args.cpu_time else 'wall'} time)\n"
    )
    if "core" in args.sections:
        core_table(args.n_uavs, args.batch, repeats, min_time)
    if "pettingzoo" in args.sections:
        print("\n## PettingZoo `parallel_env.step()` at B = 1: env steps/s (median)\n")
        print("| N | steps/s | UAV-steps/s |\n|---|---|---|")
        for N in args.n_uavs:
            r = bench_pettingzoo(N, repeats, min_time)
            print(f"| {N} | {r:,.0f} | {r * N:,.0f} |")
    if "breakdown" in args.sections:
        for N, B in sizes.breakdown:
            print_breakdown(f"Where the time goes: N = {N}, B = {B}", breakdown(N, B, repeats))
    if "kernels" in args.sections:
        kernel_tables(repeats, min_time, sizes)
    if "threshold" in args.sections:
        threshold_table(repeats, min_time, sizes)
    if "large" in args.sections:
        large_tables(repeats, min_time, sizes)
    return 0


def core_table(sizes_n, sizes_b, repeats: int, min_time: float) -> None:
    """UAV-steps/s of ``PairFlockCore.step`` for every N (rows) and B (columns)."""
    print("## Core `PairFlockCore.step`: UAV-steps/s (median)\n")
    print("| N \\ B | " + " | ".join(str(b) for b in sizes_b) + " |")
    print("|---|" + "---|" * len(sizes_b))
    for N in sizes_n:
        cells = [f"{bench_core(N, B, repeats, min_time):,.0f}" for B in sizes_b]
        print(f"| {N} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    raise SystemExit(main())
