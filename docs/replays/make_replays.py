"""Write the replays embedded in docs/replay.md: the paper's Sec. VI-A run and the quadrotor
experiment's scenario, each flown by sliding mode and recorded through ``RecordEpisode``,
then turned into a replay page and two screenshots of it (an overview, the closest pass).

    python docs/replays/make_replays.py [--out docs/replays] [--max-mb 4.5]

Each page is kept under ``--max-mb`` MB (the smallest replay stride that fits); the
screenshots need the browser (``pairflock_env.replay.headless``) and are skipped without it.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

import pairflock_env as pf
from baselines import make_pair_policy
from pairflock_env.envs.record import RecordEpisode
from pairflock_env.recording import open_recording
from pairflock_env.replay import build_replay, headless

HERE = Path(__file__).resolve().parent

#: name -> (title, env keywords, time of the overview screenshot in s): both flown by
#: sliding mode from seed 0
RUNS = {
    "paper_n50_smc": (
        "Sec. VI-A: 50 UAVs, one pair from opposite corners, sliding mode, seed 0",
        dict(preset="paper", n_uavs=50, init="corners"),
        3.0,
    ),
    "quadrotor_smc": (
        "Sec. VI-B scenario: 10 quadrotors, one pair, climb and two turns, sliding mode, seed 0",
        dict(preset="paper-quadrotor"),
        30.0,
    ),
}


def record(folder: Path, env_kwargs: dict) -> Path:
    """One full episode of ``env_kwargs`` under sliding mode, recorded in ``folder``."""
    inner = pf.parallel_env(**env_kwargs)
    smc = make_pair_policy("smc", inner)
    with RecordEpisode(inner, folder, controller="smc") as env:
        obs, _ = env.reset(seed=0)
        while env.agents:
            actions = {a: smc.predict(obs[a])[0] for a in env.agents}
            obs, *_ = env.step(actions)
    return Path(env.recorder.paths[0])


def page_under(rec: Path, html: Path, title: str, max_mb: float) -> dict:
    """The replay page with the smallest stride whose file fits ``max_mb`` MB."""
    stride = 1
    while True:
        info = build_replay(rec, html, stride=stride, title=title)
        if info["bytes"] <= max_mb * 1e6:
            return info
        stride = max(stride + 1, int(np.ceil(stride * info["bytes"] / (max_mb * 1e6))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=HERE)
    ap.add_argument("--max-mb", type=float, default=4.5)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="docs-replays-"))
    try:
        for name, (title, kwargs, shot_time) in RUNS.items():
            t0 = time.perf_counter()
            rec = record(work / name, kwargs)
            r = open_recording(rec)
            html = args.out / f"{name}.html"
            info = page_under(rec, html, title, args.max_mb)
            print(
                f"{html}: {r.steps} steps recorded ({r.num_uavs} UAVs, complete={r.complete}), "
                f"{info['steps']} replayed (stride {info['stride']}), "
                f"{info['bytes'] / 1e6:.2f} MB, {time.perf_counter() - t0:.1f} s"
            )
            if headless.missing() is None:
                index = round(shot_time / r.dt / r.every / info["stride"])
                headless.screenshot(html, args.out / f"{name}.png", step=index)
                headless.screenshot(html, args.out / f"{name}_closest.png")  # the closest pass
                print(f"  screenshots {name}.png (t = {shot_time:g} s), {name}_closest.png")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
