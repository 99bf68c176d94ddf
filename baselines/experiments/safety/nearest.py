"""The nearest-neighbour figure of the swarm layer: percentiles of every unpaired UAV's
distance to its nearest other UAV over time, for N = 100, 1,000 and 10,000 UAVs of the
``large`` preset with the pair term off (zero actions), under the paper's law without a
filter and with the swarm layer (``safety_scope="swarm"``, docs/swarm-safety.md): why the
paper's flock collides at scale, and what the layer changes.

    python -m baselines.experiments.safety.nearest --out docs/img/swarm-nearest.png
    python -m baselines.experiments.safety.nearest --n 1000 --layers barrier --out nn.png
    python -m baselines.experiments.safety.nearest --replot nn.json --out nn.png

Writes the figure and, beside it, the series as JSON (the figure's name with ``.json``):
per case the sample times, the minimum and the 1st, 10th and 50th percentiles, the closest
two UAVs over the whole flight, the infeasible and active UAV-steps, and the CPU seconds.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from baselines.reporting.figures import save_figure
from baselines.runtime.cli import ArgumentParser, user_errors
from pairflock_env import PairFlockCore, make_config

__all__ = ["LAYERS", "main", "nearest_figure", "nearest_series"]

#: the cases: the paper's law, the swarm layer (with its floor), the layer without the floor
LAYERS = {
    "off": {},
    "swarm": {"safety_filter": "cbf", "safety_scope": "swarm"},
    "barrier": {"safety_filter": "cbf", "safety_scope": "swarm", "swarm_repulsion_floor": False},
}
_PCT = (1, 10, 50)
_STYLE = {
    "off": ("#c44e52", "no filter (eqs. 13-16)"),
    "swarm": ("#4c72b0", "swarm layer"),
    "barrier": ("#55a868", "layer without the floor"),
}


def nearest_series(
    n: int, layer: str, seed: int, every: float = 0.5, horizon: float | None = None
) -> dict[str, Any]:
    """One flight of ``n`` UAVs (preset ``large``, zero pair actions; ``horizon`` s, default
    the preset's) under ``layer`` (a key of :data:`LAYERS`): the nearest-neighbour
    percentiles every ``every`` s."""
    kw = {} if horizon is None else {"horizon": horizon}
    cfg = make_config("large", n_uavs=n, **kw, **LAYERS[layer])
    core = PairFlockCore(cfg, num_swarms=1)
    res = core.reset(seed=[seed])
    unpaired = np.ones(n, bool)
    unpaired[core.agent_uavs] = False
    stride = max(1, round(every / cfg.dt))
    zero = np.zeros((1, core.n_agents, cfg.dim))
    out: dict[str, Any] = {"n": n, "layer": layer, "seed": seed, "t": [], "min": []}
    out.update({f"p{q}": [] for q in _PCT})
    closest, infeasible, active = np.inf, 0, 0
    cpu0 = time.process_time()
    for k in range(cfg.episode_steps + 1):
        if k:
            res = core.step(zero)
            infeasible += int(res.info["swarm_filter_infeasible"][0])
            active += int(res.info["swarm_filter_active"][0])
        closest = min(closest, float(res.info["swarm_min_separation"][0]))
        if k % stride == 0:
            nn = core.closest_distance[0, unpaired]
            out["t"].append(k * cfg.dt)
            out["min"].append(float(nn.min()))
            for q, v in zip(_PCT, np.percentile(nn, _PCT), strict=True):
                out[f"p{q}"].append(float(v))
    out.update(
        closest=closest,
        infeasible_uav_steps=infeasible,
        active_uav_steps=active,
        cpu_s=time.process_time() - cpu0,
    )
    return out


def nearest_figure(series: Sequence[dict[str, Any]], path: Path, dpi: int = 110) -> Path:
    """One panel per swarm size: the minimum (dotted) and the 1st, 10th and 50th percentiles
    (thin to thick) of the nearest-neighbour distance, each layer in its colour, the safety
    distance dashed; log scale. Returns ``path``."""
    sizes = sorted({s["n"] for s in series})
    fig = Figure(figsize=(4.3 * len(sizes), 3.9))
    axes = fig.subplots(1, len(sizes), sharey=True, squeeze=False)[0]
    for ax, n in zip(axes, sizes, strict=True):
        for s in (s for s in series if s["n"] == n):
            color, label = _STYLE[s["layer"]]
            t = np.asarray(s["t"])
            floor = 1e-3  # coincident UAVs (0 m) drawn at 1 mm on the log axis
            ax.plot(t, np.maximum(s["min"], floor), ":", color=color, lw=1)
            for q, lw in zip(_PCT, (0.8, 1.4, 2.4), strict=True):
                ax.plot(t, np.maximum(s[f"p{q}"], floor), color=color, lw=lw)
            ax.plot([], [], color=color, lw=2, label=f"{label}: closest {s['closest']:.3f} m")
        ax.axhline(1.0, color="k", ls="--", lw=0.8)
        ax.set_yscale("log")
        ax.set_title(f"{n:,} UAVs")
        ax.set_xlabel("time (s)")
        ax.legend(fontsize=7, loc="lower left")
    axes[0].set_ylabel("nearest-neighbour distance (m)\nmin, 1st, 10th, 50th percentile")
    fig.tight_layout()
    return save_figure(fig, path, dpi)


def build_parser() -> ArgumentParser:
    p = ArgumentParser(
        prog="python -m baselines.experiments.safety.nearest",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("--n", type=int, nargs="+", default=[100, 1000, 10000], help="swarm sizes")
    p.add_argument("--seed", type=int, default=72000, help="the seed of every flight")
    p.add_argument("--every", type=float, default=0.5, help="sample period (s)")
    p.add_argument("--horizon", type=float, default=None, help="flight time (default 50 s)")
    p.add_argument("--layers", nargs="+", default=["off", "swarm"], choices=list(LAYERS))
    p.add_argument("--out", type=Path, required=True, help="the figure (.png)")
    p.add_argument("--replot", type=Path, help="redraw from this JSON instead of flying")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    with user_errors(parser):
        if args.replot is not None:
            series = json.loads(args.replot.read_text())
        else:
            if min(args.n) < 2 or not args.every > 0:
                raise ValueError("--n must be >= 2 and --every > 0")
            series = [
                nearest_series(n, lay, args.seed, args.every, args.horizon)
                for n in args.n
                for lay in args.layers
            ]
            args.out.with_suffix(".json").write_text(json.dumps(series, indent=1) + "\n")
        for s in series:
            print(
                f"N={s['n']:>6} {s['layer']:>5}: closest {s['closest']:.4f} m, 10th pct at the "
                f"end {s['p10'][-1]:.3f} m, infeasible UAV-steps {s['infeasible_uav_steps']}, "
                f"active {s['active_uav_steps']}, {s['cpu_s']:.0f} s CPU"
            )
        print(f"wrote {nearest_figure(series, args.out)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
