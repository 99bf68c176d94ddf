"""Benchmark pair controllers: policies x scenarios x seeds, with tables, figures and video.

    python -m baselines.benchmark --suite paper             # Sec. VI-A: N = 20/50/100, 10 seeds
    python -m baselines.benchmark --suite robustness        # noise, delay, disturbance
    python -m baselines.benchmark -p smc smc:k=100 proportional:k_p=4 --n-uavs 50 --seeds 5
    python -m baselines.benchmark -p smc sb3:runs/ppo/model.zip --suite robustness
    python -m baselines.benchmark --suite paper --backend ray --ray-address auto
    python -m baselines.benchmark --suite quick --video     # + an mp4 of one episode

A suite supplies defaults (preset, policies, scenarios, seeds); every option overrides them.
Scenarios are the preset plus overrides: the grid product of the grid options (``--n-uavs 20
50 100``, ``--delay 0 5``, ``--set key=v1,v2``) times the listed ``--scenario`` entries.
Every policy runs the same seeds, hence the same initial states (and the same noise and
disturbance draws). Writes to ``--out``:

    results.csv    one row per (scenario, policy, seed, pair); byte-identical for the same
                   command (floats with 6 significant digits; NaN = never reached)
    results.json   the same rows at full precision (null = never) + scenarios, policies, seeds
    summary.md     median [min-max] tables per scenario and policy
    run.json       command, versions, git commit, configs, backend, timestamps and timing
    traces.npz     the recorded run (first seed) of each (scenario, policy), for the figures
    *.png          paper-style figures;  episode_*.mp4|gif with --video
"""

from baselines.experiments.benchmark.cli import PROG, Plan, build_parser, resolve
from baselines.experiments.benchmark.run import main, replot, simulate
from baselines.experiments.benchmark.suites import SHORTCUTS, SUITES, Suite

__all__ = [
    "PROG",
    "SHORTCUTS",
    "SUITES",
    "Plan",
    "Suite",
    "build_parser",
    "main",
    "replot",
    "resolve",
    "simulate",
]
