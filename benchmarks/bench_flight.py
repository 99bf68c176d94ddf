"""Speed over whole flights: UAV-steps/s averaged over an episode, not from a reset state.

    python benchmarks/bench_flight.py                  # every section (minutes)
    python benchmarks/bench_flight.py --quick          # small and short (seconds)
    python benchmarks/bench_flight.py --smoke          # every part once, tiny
    python benchmarks/bench_flight.py --sections large # 50 s of 10,000 UAVs
    python benchmarks/bench_flight.py --sections order # lattice vs shuffled indices

Sections:

* ``large``: one 50 s episode of the ``large`` preset with ``n_uavs=10_000`` (the grid
  search), zero pair actions, from the preset's random start: UAV-steps/s over the whole
  flight and over each fifth of it (an unpaired flock packs as it flies, and every step
  costs more as the neighbours per UAV grow);
* ``small``: whole 50 s episodes of the paper preset with N = 100 UAVs (all pairs) at
  B = 1 and B = 256;
* ``order``: the flocking lattice of 10,000 UAVs listed in lattice order and the same state
  with its UAV indices shuffled (rollouts of ``--order-steps`` steps): memory order should
  not matter.

One thread (numba, OpenMP and BLAS pinned), wall or CPU time (``--cpu-time``). Only the
public API is used (``make_config``, ``PairFlockCore``, ``reset``, ``step``), so another
checkout can be timed with the same script (``PYTHONPATH=<checkout>``).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # before numpy and numba load

import argparse  # noqa: E402
import itertools  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from pairflock_env import PairFlockCore, make_config  # noqa: E402

SECTIONS = ("large", "small", "order")
_CLOCK = {"clock": time.perf_counter}


def flight(
    preset: str, n_uavs: int, num_swarms: int, seconds: float, parts: int = 5, options=None
) -> tuple[float, list[float]]:
    """UAV-steps/s of one episode of ``seconds`` of flight (zero pair actions) after an
    untimed reset (seed 0): over the whole flight, and over each of ``parts`` equal parts."""
    cfg = make_config(preset, n_uavs=n_uavs, horizon=seconds)
    core = PairFlockCore(cfg, num_swarms)
    core.reset(seed=0, options=options)
    steps = round(seconds / cfg.dt)
    zeros = np.zeros((num_swarms, core.n_agents, cfg.dim))
    clock = _CLOCK["clock"]
    bounds = [round(k * steps / parts) for k in range(parts + 1)]
    times = []
    for a, b in itertools.pairwise(bounds):
        t0 = clock()
        for _ in range(b - a):
            core.step(zeros)
        times.append(clock() - t0)
    work = num_swarms * n_uavs
    rates = [
        work * (b - a) / t for (a, b), t in zip(itertools.pairwise(bounds), times, strict=True)
    ]
    return work * steps / sum(times), rates


def warm_up(preset: str, n_uavs: int, num_swarms: int) -> None:
    """Compile (or load from the cache) the kernels a flight uses, untimed."""
    flight(preset, n_uavs, num_swarms, 0.05, parts=1)


def lattice(n_uavs: int, spacing: float = 7.0, jitter: float = 0.3) -> np.ndarray:
    """A hexagonal lattice of ``n_uavs`` points at ``spacing`` (m), jittered, centred,
    listed row by row (lattice order), (N, 2)."""
    rng = np.random.default_rng(0)
    n = int(np.ceil(np.sqrt(n_uavs)))
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    pts = np.stack([i + 0.5 * (j % 2), j * np.sqrt(3) / 2], -1).reshape(-1, 2)[:n_uavs]
    q = spacing * pts + rng.normal(0.0, jitter, (n_uavs, 2))
    return q - q.mean(axis=0)


def rollout(n_uavs: int, positions: np.ndarray, steps: int, repeats: int) -> float:
    """Median UAV-steps/s of ``repeats`` rollouts of ``steps`` steps (large preset, zero
    actions) from the given positions (at rest), after one untimed rollout."""
    cfg = make_config("large", n_uavs=n_uavs, horizon=1e4)
    core = PairFlockCore(cfg, 1)
    zeros = np.zeros((1, core.n_agents, cfg.dim))
    options = {"positions": positions, "velocities": np.zeros_like(positions)}
    rates = []
    clock = _CLOCK["clock"]
    for _ in range(repeats + 1):
        core.reset(seed=0, options=options)
        t0 = clock()
        for _ in range(steps):
            core.step(zeros)
        rates.append(n_uavs * steps / (clock() - t0))
    return statistics.median(rates[1:])


def order_rates(n_uavs: int, steps: int, repeats: int) -> tuple[float, float]:
    """(lattice order, shuffled indices) rollout rates of the same lattice state, the two
    alternated so that a change of load hits both alike."""
    q = lattice(n_uavs)
    shuffled = q[np.random.default_rng(1).permutation(n_uavs)]
    a, b = [], []
    for _ in range(repeats):
        a.append(rollout(n_uavs, q, steps, 1))
        b.append(rollout(n_uavs, shuffled, steps, 1))
    return statistics.median(a), statistics.median(b)


def _fmt_parts(rates: list[float]) -> str:
    return " / ".join(f"{r / 1e6:.2f}" for r in rates)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python benchmarks/bench_flight.py", description=__doc__.split("\n\n")[0]
    )
    ap.add_argument("--quick", action="store_true", help="small swarms, short flights (seconds)")
    ap.add_argument("--smoke", action="store_true", help="every part once, tiny (the suite)")
    ap.add_argument("--sections", nargs="+", choices=SECTIONS, default=list(SECTIONS))
    ap.add_argument("--n-uavs", type=int, default=10_000, help="UAVs of the large flight")
    ap.add_argument("--seconds", type=float, default=50.0, help="flight time of an episode, s")
    ap.add_argument("--order-steps", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cpu-time", action="store_true", help="this process's CPU time")
    args = ap.parse_args(argv)
    _CLOCK["clock"] = time.process_time if args.cpu_time else time.perf_counter
    big, seconds, small_b = args.n_uavs, args.seconds, 256
    order_steps, repeats = args.order_steps, args.repeats
    if args.quick:
        big, seconds, small_b, order_steps, repeats = 1_000, 0.2, 4, 5, 1
    if args.smoke:
        big, seconds, small_b, order_steps, repeats = 300, 0.05, 2, 2, 1
    clock = "CPU" if args.cpu_time else "wall"
    print(
        f"# Whole flights ({platform.machine()}, 1 thread, {clock} time; UAV-steps/s, "
        f"millions, over the flight and over each fifth of it)\n"
    )
    print("| flight | UAV-steps/s | per fifth |\n|---|---|---|")
    if "large" in args.sections:
        warm_up("large", big, 1)
        rate, parts = flight("large", big, 1, seconds)
        name = f"`large`, {big:,} UAVs, {seconds:g} s"
        print(f"| {name} | {rate / 1e6:.3f}M | {_fmt_parts(parts)} |")
    if "small" in args.sections:
        for B in (1, small_b):
            warm_up("paper", 100, B)
            rate, parts = flight("paper", 100, B, seconds)
            name = f"`paper`, 100 UAVs, B = {B}, {seconds:g} s"
            print(f"| {name} | {rate / 1e6:.3f}M | {_fmt_parts(parts)} |")
    if "order" in args.sections:
        a, b = order_rates(big, order_steps, repeats)
        print(
            f"\nLattice of {big:,} UAVs, {order_steps} steps, median of {repeats}: lattice "
            f"order {a / 1e6:.3f}M, shuffled indices {b / 1e6:.3f}M UAV-steps/s "
            f"(shuffled / lattice {b / a:.2f})"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
