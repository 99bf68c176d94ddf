"""How close the core step comes to this machine's limits: a roofline at N = 100, B = 256.

    python benchmarks/bench_roofline.py            # a few seconds of each measurement
    python benchmarks/bench_roofline.py --quick    # smaller and shorter
    python benchmarks/bench_roofline.py --smoke    # every part once, tiny

Prints the floating-point operations and the memory traffic of one UAV-step, counted from the
step's equations on the state it is timed on (the mean number of neighbours measured there),
this machine's peaks measured on one thread (FP64: a dense matrix product through numpy's
BLAS; memory: a triad over arrays far larger than the caches), the core's UAV-steps/s, and
the fraction of each peak it reaches. Only the public API is used, so another checkout can be
measured the same way (``PYTHONPATH=<checkout>``).

Counting (2-D, per UAV-step): each unordered pair of UAVs once for its squared distance
(2 subtractions, 2 multiplications, 1 addition: 5 flops), so (N - 1) / 2 pairs per UAV; per
neighbour (each UAV of a neighbour pair): the force w (q_j - q_i) + b (p_j - p_i) and its
accumulation (12 flops), and half a weight w = a - b_r exp(-d^2 / sigma^2) (3 flops and one
exponential, counted as 20 flops); the pinning term (10), the velocity mismatch (7), the
semi-implicit integration (8). Compares, the union-find and integer work are not counted.
Bytes: positions and velocities read and written (64), the flocking command written and read
back (32), separation and pinning flag (16): 112 bytes a UAV-step that a step must move; the
rest of a step's data (scratch, per-agent results) stays in the caches.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # before numpy and numba load

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from pairflock_env import PairFlockCore, make_config  # noqa: E402

#: bytes of one UAV-step a step must move (module docstring)
BYTES_PER_UAV_STEP = 112
#: an exponential, counted as this many flops (a polynomial and a table lookup)
EXP_FLOPS = 20


def flops_per_uav_step(n_uavs: int, neighbors: float) -> float:
    """Flops of one UAV-step of the 2-D particle core (module docstring)."""
    pairs = 5.0 * (n_uavs - 1) / 2
    per_neighbor = 12.0 + (3.0 + EXP_FLOPS) / 2
    return pairs + neighbors * per_neighbor + 10.0 + 7.0 + 8.0


def core_rate(N: int, B: int, steps: int, repeats: int) -> tuple[float, float]:
    """Median UAV-steps/s of ``steps`` core steps from the paper preset's reset (seed 0,
    small random pair actions; CPU time), and the mean neighbours per UAV over those steps."""
    cfg = make_config("paper", n_uavs=N, max_cycles=10**9)
    core = PairFlockCore(cfg, B)
    actions = np.random.default_rng(0).uniform(-0.2, 0.2, (B, core.n_agents, cfg.dim))
    rates, counts = [], []
    for r in range(repeats + 1):
        core.reset(seed=0)
        t0 = time.process_time()
        for _ in range(steps):
            core.step(actions)
        if r:
            rates.append(B * N * steps / (time.process_time() - t0))
    core.reset(seed=0)
    for _ in range(steps):
        core.step(actions)
        d2 = ((core.q[:, :, None] - core.q[:, None]) ** 2).sum(-1)
        counts.append(((d2 < cfg.radius**2).sum(-1) - 1).mean())
    return statistics.median(rates), float(np.mean(counts))


def peak_flops(n: int, repeats: int) -> float:
    """FP64 flop/s of a dense n x n matrix product (numpy's BLAS, one thread)."""
    a = np.random.default_rng(0).normal(size=(n, n))
    b = a.T.copy()
    a @ b
    best = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        a @ b
        best.append(2.0 * n**3 / (time.perf_counter() - t0))
    return max(best)


def peak_bandwidth(mbytes: int, repeats: int) -> float:
    """Bytes/s of the triad c = a + s b over arrays of ``mbytes`` MB each (24 bytes moved per
    element, write-allocate not counted)."""
    n = mbytes * 2**20 // 8
    a, b, c = np.ones(n), np.ones(n), np.empty(n)
    best = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        np.multiply(b, 3.0, out=c)
        np.add(a, c, out=c)
        dt = time.perf_counter() - t0
        best.append(5 * 8 * n / dt)  # two passes: read b, write c; read a and c, write c
    return max(best)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python benchmarks/bench_roofline.py", description=__doc__.split("\n\n")[0]
    )
    ap.add_argument("--quick", action="store_true", help="smaller and shorter (seconds)")
    ap.add_argument("--smoke", action="store_true", help="every part once, tiny (the suite)")
    args = ap.parse_args(argv)
    N, B, steps, repeats, gemm, mb = 100, 256, 20, 5, 2000, 400
    if args.quick or args.smoke:
        B, steps, repeats, gemm, mb = 16, 5, 1, 400, 32
    if args.smoke:
        B, steps, gemm, mb = 2, 2, 100, 8
    rate, neighbors = core_rate(N, B, steps, repeats)
    flops = flops_per_uav_step(N, neighbors)
    fpeak, bpeak = peak_flops(gemm, 3), peak_bandwidth(mb, 3)
    print(
        f"# Roofline of the core step, N = {N}, B = {B} (one thread)\n\n"
        "| quantity | value |\n|---|---|\n"
        f"| neighbours per UAV (mean over the timed steps) | {neighbors:.2f} |\n"
        f"| flops per UAV-step | {flops:.0f} |\n"
        f"| bytes per UAV-step (compulsory) | {BYTES_PER_UAV_STEP} |\n"
        f"| peak FP64, dense matrix product | {fpeak / 1e9:.1f} GFLOP/s |\n"
        f"| peak memory bandwidth, triad | {bpeak / 1e9:.1f} GB/s |\n"
        f"| bound: min(peak flops / flops, bandwidth / bytes) | "
        f"{min(fpeak / flops, bpeak / BYTES_PER_UAV_STEP) / 1e6:.0f}M UAV-steps/s |\n"
        f"| core step (CPU time, median of {repeats}) | {rate / 1e6:.2f}M UAV-steps/s |\n"
        f"| fraction of the flop peak | {100 * rate * flops / fpeak:.1f} % |\n"
        f"| fraction of the bandwidth | {100 * rate * BYTES_PER_UAV_STEP / bpeak:.1f} % |"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
