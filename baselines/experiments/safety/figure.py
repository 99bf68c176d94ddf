"""The closest-pass figure of the safety suite: per policy, the distribution over runs of
the closest distance from a paired UAV to any other UAV, filter off vs on, per scenario.

    python -m baselines.experiments.safety.figure RUN_DIR [RUN_DIR ...] --out FIGURE.png

Each RUN_DIR is a finished benchmark folder (its ``results.csv``) whose runs carry the
safety columns (``--suite safety``, or any run with ``--set safety_filter=none,cbf``); the
rows of several folders are pooled (e.g. a suite run in parts).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from baselines.reporting.figures import save_figure
from baselines.runtime.cli import ArgumentParser, user_errors
from baselines.runtime.folders import load_results

__all__ = ["closest_pass_figure", "main", "read_rows"]

_COLORS = {"none": "#c44e52", "cbf": "#4c72b0"}


def read_rows(folders: Sequence[Path]) -> list[dict[str, Any]]:
    """The rows of every ``results.csv``; ``FileNotFoundError`` for a folder without one,
    ``ValueError`` for one without the safety columns."""
    rows: list[dict[str, Any]] = []
    for d in folders:
        part = load_results([d], "runs")
        if not part or "closest_pass" not in part[0] or "safety_filter" not in part[0]:
            raise ValueError(
                f"{d}/results.csv has no closest_pass / safety_filter columns: run the "
                "benchmark with the filter off and on (--suite safety)"
            )
        rows += part
    return rows


def _group_label(r: Mapping[str, Any]) -> str:
    init = r.get("init", "")
    return f"N={r['n_uavs']}" + (f"\n{init}" if init else "")


def closest_pass_figure(rows: Sequence[Mapping[str, Any]], path: Path, dpi: int = 110) -> Path:
    """One panel per policy: boxes of closest_pass per scenario group, off and on side by
    side (runs as dots), the safety distance as a dashed line; log scale. Returns ``path``."""
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    groups = list(dict.fromkeys(_group_label(r) for r in rows))
    fig = Figure(figsize=(4.2 * len(policies), 3.8))
    axes = fig.subplots(1, len(policies), sharey=True, squeeze=False)
    ds = {float(r.get("safety_distance", 1.0) or 1.0) for r in rows}
    for ax, pol in zip(axes[0], policies, strict=True):
        for k, mode in enumerate(("none", "cbf")):
            data, pos = [], []
            for g, label in enumerate(groups):
                v = [
                    float(r["closest_pass"])
                    for r in rows
                    if r["policy"] == pol
                    and r["safety_filter"] == mode
                    and _group_label(r) == label
                ]
                if v:
                    data.append(v)
                    pos.append(g + (k - 0.5) * 0.36)
            if not data:
                continue
            bp = ax.boxplot(data, positions=pos, widths=0.3, patch_artist=True, showfliers=False)
            for box in bp["boxes"]:
                box.set(facecolor=_COLORS[mode], alpha=0.35)
            rng = np.random.default_rng(0)
            for x, v in zip(pos, data, strict=True):
                jitter = x + rng.uniform(-0.1, 0.1, len(v))
                ax.plot(jitter, v, ".", ms=2.5, color=_COLORS[mode], alpha=0.7)
            ax.plot([], [], "s", color=_COLORS[mode], alpha=0.6, label=f"filter {mode}")
        for d in sorted(ds):
            ax.axhline(d, ls="--", color="k", lw=0.8)
        ax.set_yscale("log")
        ax.set_xticks(range(len(groups)), groups, fontsize=8)
        ax.set_title(pol, fontsize=10)
        ax.grid(axis="y", alpha=0.3, which="both")
    axes[0][0].set_ylabel("closest pass to any other UAV (m)")
    axes[0][0].legend(fontsize=8, loc="best")
    fig.suptitle("Closest pass per run, safety filter off vs on (dashed: safety_distance)")
    fig.tight_layout()
    return save_figure(fig, path, dpi)


def main(argv: Sequence[str] | None = None) -> int:
    """Draw the figure of the folders on the command line; returns the exit status."""
    p = ArgumentParser(
        prog="python -m baselines.experiments.safety.figure", description=__doc__.splitlines()[0]
    )
    p.add_argument("runs", nargs="+", type=Path, help="benchmark result folders")
    p.add_argument("--out", type=Path, required=True, help="PNG to write")
    p.add_argument("--dpi", type=int, default=110)
    args = p.parse_args(argv)
    with user_errors(p, OSError):
        rows = read_rows(args.runs)
    print(f"wrote {closest_pass_figure(rows, args.out, args.dpi)} ({len(rows)} runs)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
