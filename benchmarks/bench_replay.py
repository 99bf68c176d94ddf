"""Frames per second of the replay page in headless Chromium (software WebGL), by swarm size.

    python benchmarks/bench_replay.py [--uavs 100 1000 10000] [--seconds 5] [--repeats 3]
    python benchmarks/bench_replay.py --quick   # 100 and 1,000 UAVs, 1 s, one round

Needs the browser (``pairflock_env.replay.headless``: the Python package playwright and the
Debian package chromium); without it the script says what is missing and exits (with status
1 when ``PAIRFLOCK_REQUIRE_BROWSER=1``, as in CI).

For each size: a demo recording (``pairflock_env.replay.write_demo``, 300 steps) and its page.
Then ``repeats`` rounds, the sizes interleaved and one page open at a time: open the page,
play 1 s to warm up, then count the frames drawn in ``seconds`` of playback at one new
recorded step per frame (every frame uploads new positions, colours and pair lines). Reports
the median fps and the page's JavaScript time per frame; for the largest size, the fps with
layers turned off and the time per frame of decoding versus drawing, to show where it goes.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

from pairflock_env.replay import build_replay, headless, write_demo

LAYERS = {  # each names every layer: setLayers keeps what it is not told
    "all layers": "{pairs: true, grid: true, uavs: true}",
    "no pair lines": "{pairs: false, grid: true, uavs: true}",
    "no pair lines, no grid": "{pairs: false, grid: false, uavs: true}",
    "nothing drawn (clear only)": "{pairs: false, grid: false, uavs: false}",
}


def measure(page, seconds: float, layers: str = LAYERS["all layers"], warmup: float = 1.0):
    """Play ``warmup`` s (shader compilation, the collection of the page's data text), then
    count the frames drawn in ``seconds``."""
    page.evaluate(
        f"(() => {{ const h = window.pairflockReplay; h.setLayers({layers}); "
        "h.play({stepsPerFrame: 1, loop: true}); })()"
    )
    page.wait_for_timeout(warmup * 1000)
    page.evaluate("window.pairflockReplay.resetStats()")
    page.wait_for_timeout(seconds * 1000)
    stats = page.evaluate("window.pairflockReplay.stats()")
    page.evaluate("window.pairflockReplay.pause()")
    return stats


def by_size(browser, pages: dict, args) -> list[str]:
    """The fps table, and the console errors seen."""
    runs = {n: [] for n in pages}
    errors = []
    for _ in range(args.repeats):
        for n, (html, _) in pages.items():
            t0 = time.perf_counter()
            page, errs = headless.open_replay(browser, html, tuple(args.size))
            load = time.perf_counter() - t0
            runs[n].append(measure(page, args.seconds, warmup=args.warmup) | {"load": load})
            errors += [f"N = {n}: {e}" for e in errs]
            page.close()
    print(
        f"headless Chromium {browser.version}, canvas {args.size[0]}x{args.size[1]}, "
        f"{args.seconds:g} s per run after {args.warmup:g} s of warm-up, median of {args.repeats}"
    )
    print("| UAVs | fps | JS ms/frame | page MB | page bytes per UAV-step | load s |")
    print("|---:|---:|---:|---:|---:|---:|")
    for n, (_, info) in pages.items():
        med = {k: statistics.median(r[k] for r in runs[n]) for k in ("fps", "jsMsMean", "load")}
        print(
            f"| {n:,} | {med['fps']:.1f} | {med['jsMsMean']:.2f} | {info['bytes'] / 1e6:.2f} "
            f"| {info['bytes_per_uav_step']:.2f} | {med['load']:.2f} |"
        )
    print("each run's fps:", {n: [round(r["fps"], 1) for r in runs[n]] for n in runs})
    return errors


def breakdown(browser, html: Path, n: int, args) -> list[str]:
    """fps with layers off (interleaved), and decode versus draw time per frame."""
    page, errors = headless.open_replay(browser, html, tuple(args.size))
    parts = {k: [] for k in LAYERS}
    for _ in range(args.repeats):
        for name, layers in LAYERS.items():
            parts[name].append(measure(page, args.seconds, layers, args.warmup)["fps"])
    page.evaluate(f"window.pairflockReplay.setLayers({LAYERS['all layers']})")
    prof = page.evaluate("window.pairflockReplay.profile(120)")
    print(f"\nwhere the time goes at N = {n:,} (fps, median of {args.repeats}, interleaved):")
    for name, values in parts.items():
        print(f"  {name:28s} {statistics.median(values):6.1f}   {[round(v, 1) for v in values]}")
    print(
        f"  per frame, drawn back to back: JS (decode a step, fill buffers) {prof['jsMs']:.2f} "
        f"ms, drawing until done (a pixel read waits for it) {prof['gpuMs']:.2f} ms"
    )
    page.close()
    return errors


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--uavs", type=int, nargs="+", default=[100, 1000, 10000])
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--size", type=int, nargs=2, default=[1280, 720])
    ap.add_argument("--quick", action="store_true", help="a check that runs: 2 sizes, 0.5 s")
    args = ap.parse_args()
    args.warmup = 1.0
    if args.quick:
        args.uavs, args.seconds, args.repeats, args.size = [100, 1000], 0.5, 1, [640, 360]
        args.warmup = 0.3
    why = headless.missing()
    if why:
        print(f"bench_replay: {why}")
        return 1 if os.environ.get("PAIRFLOCK_REQUIRE_BROWSER") == "1" else 0
    work = Path(tempfile.mkdtemp(prefix="replay-fps-"))
    try:
        pages = {}
        for n in args.uavs:
            rec = write_demo(work / f"n{n}.pfrec", num_uavs=n, steps=300)
            pages[n] = (work / f"n{n}.html", build_replay(rec, work / f"n{n}.html"))
        with headless.launch() as browser:
            errors = by_size(browser, pages, args)
            big = max(args.uavs)
            if not args.quick:
                errors += breakdown(browser, pages[big][0], big, args)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("console errors:", errors or "none")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
