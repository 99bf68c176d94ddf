"""Recording benchmarks: a full ``large``-preset episode of 10,000 UAVs recorded (peak memory,
bytes per UAV-step), the recording's overhead on stepping at N = 100, and the writer's cost
per recorded step.

    python benchmarks/bench_recording.py                  # every part (about 4 minutes)
    python benchmarks/bench_recording.py --part overhead  # one part: large, overhead, append
    python benchmarks/bench_recording.py --quick          # every part, small, in seconds

* ``large``: ``make_config("large", n_uavs=10_000)``, zero pair actions, one full episode
  (5,000 steps) through the PettingZoo view, once plain and once wrapped in
  ``RecordEpisode`` (every step), each in a fresh process so that each peak RSS is its own;
  reports wall time, peak RSS and the recording's size per UAV-step.
* ``overhead``: the paper preset at N = 100, a bare core and the PettingZoo view, each
  stepped with and without recording (every step; the view also one step in 10), batches
  interleaved in one process, timed in CPU time; the ratio is the median over rounds of each
  round's recorded / plain time.
* ``append``: ``RecordingWriter.append`` alone (every array, safety per UAV, 3 infos) at
  N = 100 and 10,000, sizes interleaved: the median time per recorded step.
"""

from __future__ import annotations

import os

# one thread (set before numpy and numba load)
os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import pairflock_env as pf
from pairflock_env import PairFlockCore
from pairflock_env.envs.record import RecordEpisode
from pairflock_env.recording import RecordingWriter, open_recording, record_core

PARTS = ("large", "overhead", "append")


def peak_mb() -> float:
    """This process's peak resident memory so far, MB (Linux reports kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def folder_bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


# ---------------------------------------------------------------------------- large
def large_episode(n_uavs: int, steps: int | None, record: str | None) -> dict:
    """One episode of the large preset with zero pair actions (recorded into ``record``)."""
    kw = dict(preset="large", n_uavs=n_uavs) | ({} if steps is None else {"max_cycles": steps})
    env = pf.parallel_env(**kw)
    if record:
        env = RecordEpisode(env, record, controller="zero")
    env.reset(seed=0)
    zero = {a: np.zeros(2) for a in env.agents}
    rss_reset = peak_mb()
    t0, c0 = time.perf_counter(), time.process_time()
    n = 0
    while env.agents:
        env.step(zero)
        n += 1
    env.close()
    took, cpu = time.perf_counter() - t0, time.process_time() - c0
    out = dict(uavs=n_uavs, steps=n, seconds=took, cpu_seconds=cpu)
    out.update(rss_reset_mb=rss_reset, rss_peak_mb=peak_mb())
    if record:
        rec = open_recording(env.recorder.paths[0])
        size = folder_bytes(Path(record))
        out.update(recorded=rec.steps, complete=rec.complete, bytes=size)
        out["bytes_per_uav_step"] = size / (n_uavs * rec.steps)
    return out


def run_large(args: argparse.Namespace) -> None:
    n, steps = (1000, 50) if args.quick else (10_000, None)
    work = Path(tempfile.mkdtemp(prefix="bench-rec-large-"))
    rows = {}
    try:
        for case in ("plain", "recorded"):  # a fresh process each: its own peak RSS
            cmd = [sys.executable, __file__, "--child-large", str(n), str(steps or 0)]
            if case == "recorded":
                cmd.append(str(work / "rec"))
            done = subprocess.run(cmd, capture_output=True, text=True, check=True)
            rows[case] = json.loads(done.stdout.splitlines()[-1])
    finally:
        shutil.rmtree(work, ignore_errors=True)
    r, p = rows["recorded"], rows["plain"]
    print(f"\n## large preset, {n:,} UAVs, {r['steps']:,} steps, zero pair actions\n")
    print("| case | wall s | CPU ms per step | peak RSS MB (after reset) | recording |")
    print("|---|---:|---:|---:|---|")
    for case, row in rows.items():
        rec = "-"
        if case == "recorded":
            rec = (
                f"{row['bytes'] / 1e9:.3f} GB, {row['recorded']:,} steps, "
                f"{row['bytes_per_uav_step']:.2f} bytes per UAV-step, complete={row['complete']}"
            )
        print(
            f"| {case} | {row['seconds']:.1f} | {1e3 * row['cpu_seconds'] / row['steps']:.2f} "
            f"| {row['rss_peak_mb']:.0f} ({row['rss_reset_mb']:.0f}) | {rec} |"
        )
    print(
        f"\nrecording's peak RSS over the plain run: {r['rss_peak_mb'] - p['rss_peak_mb']:+.0f} MB"
    )


# ---------------------------------------------------------------------------- overhead
def steppers(n: int, folder: Path, recorders: list) -> dict:
    """name -> zero-argument step function: a core and a PettingZoo env, plain and recorded
    (what must be closed goes into ``recorders``)."""
    out = {}
    for name in ("core", "core + record_core"):
        core = PairFlockCore(preset="paper", n_uavs=n, max_cycles=10**9)
        if name != "core":
            recorders.append(record_core(core, folder / "core", controller="zero"))
        core.reset(seed=0)
        zero = np.zeros((1, core.n_agents, core.config.dim))
        out[name] = lambda core=core, zero=zero: core.step(zero)
    for name, every in (
        ("parallel env", 0),
        ("parallel env + RecordEpisode", 1),
        ("parallel env + RecordEpisode(every=10)", 10),
    ):
        env = pf.parallel_env(preset="paper", n_uavs=n, max_cycles=10**9)
        if every:
            env = RecordEpisode(env, folder / f"env{every}", controller="zero", every=every)
            recorders.append(env)
        env.reset(seed=0)
        act = {a: np.zeros(2, np.float32) for a in env.agents}
        out[name] = lambda env=env, act=act: env.step(act)
    return out


def run_overhead(args: argparse.Namespace) -> None:
    n, batch, rounds = 100, (50 if args.quick else 400), (3 if args.quick else 25)
    work = Path(tempfile.mkdtemp(prefix="bench-rec-overhead-"))
    recorders: list = []
    try:
        fns = steppers(n, work, recorders)
        times = {k: [] for k in fns}
        for fn in fns.values():
            for _ in range(batch // 4):  # warm up (JIT, first flushes)
                fn()
        for r in range(rounds):
            order = list(fns) if r % 2 == 0 else list(fns)[::-1]
            for k in order:
                t0 = time.process_time()  # this process's CPU time: steadier on a shared machine
                for _ in range(batch):
                    fns[k]()
                times[k].append((time.process_time() - t0) / batch)
    finally:
        for r in recorders:
            r.close()
        shutil.rmtree(work, ignore_errors=True)
    print(f"\n## recording overhead at N = {n} (paper preset, every step recorded)\n")
    print(f"{rounds} rounds of {batch} steps per case, interleaved; CPU time, medians\n")
    print("| stepping | us per step | recorded / plain (median of per-round ratios) |")
    print("|---|---:|---:|")
    for k, plain in (
        ("core", None),
        ("core + record_core", "core"),
        ("parallel env", None),
        ("parallel env + RecordEpisode", "parallel env"),
        ("parallel env + RecordEpisode(every=10)", "parallel env"),
    ):
        cell = ""
        if plain is not None:
            pairs = zip(times[k], times[plain], strict=True)
            cell = f"{statistics.median(a / b for a, b in pairs):.3f}"
        print(f"| {k} | {1e6 * statistics.median(times[k]):.1f} | {cell} |")


# ---------------------------------------------------------------------------- append
def append_run(folder: Path, n: int, steps: int) -> tuple[float, int]:
    m = n // 2
    q = np.random.default_rng(0).normal(size=(n, 3))
    pairs = np.arange(2 * m).reshape(m, 2)
    per_pair = np.ones(m)
    w = RecordingWriter(
        folder, num_uavs=n, dim=3, dt=0.01, pairs=pairs, pair_target=1.0, safety_scope="uav"
    )
    t0 = time.perf_counter()
    for t in range(steps):
        w.append(
            t,
            time=0.01 * t,
            positions=q,
            velocities=q,
            leader_position=q[0],
            leader_velocity=q[0],
            pair_distance=per_pair,
            pair_error=per_pair,
            safety_active=q[:, 0] > 0,
            safety_correction=q[:, 1],
            closest_distance=q[:, 2],
            infos={"sim_time": 0.01 * t, "collisions": 0, "largest_component": n},
        )
    w.close()
    took = (time.perf_counter() - t0) / steps
    size = folder_bytes(folder)
    shutil.rmtree(folder)
    return took, size


def run_append(args: argparse.Namespace) -> None:
    sizes = {100: 200 if args.quick else 2000, 10_000: 20 if args.quick else 300}
    repeats = 1 if args.quick else 5
    work = Path(tempfile.mkdtemp(prefix="bench-rec-append-"))
    runs = {n: [] for n in sizes}
    try:
        for r in range(repeats):
            for n, steps in sizes.items():
                runs[n].append(append_run(work / f"n{n}-{r}", n, steps))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"\n## RecordingWriter.append (3-D, every array), median of {repeats}\n")
    print("| UAVs | steps | us per recorded step | bytes per UAV-step |\n|---:|---:|---:|---:|")
    for n, rows in runs.items():
        per_step = statistics.median(t for t, _ in rows)
        print(
            f"| {n:,} | {sizes[n]:,} | {1e6 * per_step:,.1f} | {rows[0][1] / (n * sizes[n]):.2f} |"
        )


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--child-large":
        n, steps = int(sys.argv[2]), int(sys.argv[3]) or None
        record = sys.argv[4] if len(sys.argv) > 4 else None
        print(json.dumps(large_episode(n, steps, record)))
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--part", nargs="+", choices=PARTS, default=list(PARTS))
    ap.add_argument("--quick", action="store_true", help="small sizes: a check that runs")
    args = ap.parse_args()
    print(f"pairflock_env {pf.__version__}, Python {sys.version.split()[0]}, one thread")
    for part in args.part:
        {"large": run_large, "overhead": run_overhead, "append": run_append}[part](args)


if __name__ == "__main__":
    main()
