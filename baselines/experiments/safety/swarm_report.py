"""The swarm layer's tables (docs/swarm-safety-results.md) from benchmark runs of the
``swarm-safety`` suites: every UAV's separation, and what the layer changes for the flock
and for the pairs, runs paired by seed.

    python -m baselines.experiments.safety.swarm_report RUN_DIR [RUN_DIR ...]

Each RUN_DIR is a finished benchmark folder whose runs carry the whole swarm's columns
(``--suite swarm-safety``, ``swarm-safety-large``, ``swarm-safety-10k``, or any run with
``--set safety_scope=swarm``); the rows of several folders are pooled. A run's layer is
``off`` (no filter), ``pairs`` (the pair filter) or ``swarm`` (the swarm layer). Printed:

* separation: per (N, start, policy), for each layer the runs with a step below
  safety_distance and the closest two UAVs over every run, and the swarm layer's infeasible
  UAV-steps (runs with any) and active UAV-steps;
* flock: per (N, start, policy), the median over seeds of swarm / off (and swarm / pairs)
  for the flock's quality (radius of gyration, velocity mismatch, leader tracking, lattice
  deviation, smallest largest component) and how many of those ratios lie within 10 %;
* pairs: per (N, start, policy), the median over (seed, pair) of swarm / pairs for the steady
  error and the band time, and the share of pairs in the 0.5 m band at the end per layer.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from baselines.runtime.cli import ArgumentParser, user_errors
from baselines.runtime.folders import load_results

__all__ = ["FLOCK_RATIOS", "flock_lines", "layer_of", "main", "pair_lines", "separation_lines"]

Row = Mapping[str, Any]
#: the flock's quality compared swarm / off (steady window)
FLOCK_RATIOS = (
    ("flock_gyration", "Rg"),
    ("flock_velocity_mismatch", "vel. mismatch"),
    ("flock_tracking", "tracking"),
    ("flock_lattice_deviation", "lattice dev."),
    ("flock_min_component", "largest comp."),
)
_WITHIN = 0.10


def layer_of(row: Row) -> str:
    """off, pairs or swarm."""
    if row.get("safety_filter", "none") in ("none", ""):
        return "off"
    return row.get("safety_scope") or "pairs"


def _num(v: Any) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _case(row: Row) -> tuple[str, str, str]:
    return (row.get("n_uavs", "?"), row.get("init", ""), row["policy"])


def _groups(rows: Sequence[Row], swarm_only: bool) -> dict[tuple, list[Row]]:
    out: dict[tuple, list[Row]] = defaultdict(list)
    for r in rows:
        if not swarm_only or r["pair"] in ("0", 0):
            out[(*_case(r), layer_of(r))].append(r)
    return out


def separation_lines(rows: Sequence[Row]) -> list[str]:
    """The separation table (one row per swarm run), the layers side by side."""
    groups = _groups(rows, True)
    lines = [
        "| N | start | policy | runs | runs with two UAVs < D_s: off / pairs / swarm | "
        "closest two UAVs (m): off / pairs / swarm | infeasible UAV-steps (swarm) | "
        "active UAV-steps per run, median (swarm) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    cases = dict.fromkeys(key[:3] for key in groups)
    for n, init, pol in cases:
        by = {lay: groups.get((n, init, pol, lay), []) for lay in ("off", "pairs", "swarm")}
        below = " / ".join(
            str(sum(_num(r["swarm_steps_below"]) > 0 for r in g)) if g else "-" for g in by.values()
        )
        closest = " / ".join(
            f"{min(_num(r['swarm_closest']) for r in g):.3f}" if g else "-" for g in by.values()
        )
        sw = by["swarm"]
        inf = np.array([_num(r["swarm_infeasible_uav_steps"]) for r in sw])
        infc = f"{int(inf.sum())} ({int(np.count_nonzero(inf))} runs)" if inf.any() else "0"
        act = f"{np.median([_num(r['swarm_active_uav_steps']) for r in sw]):.0f}" if sw else "-"
        lines.append(
            f"| {n} | {init or '-'} | {pol} | {len(sw)} | {below} | {closest} | {infc} | {act} |"
        )
    return lines


def _median(v: np.ndarray) -> str:
    """The median of the finite values (ratios of runs that never entered the band are NaN)."""
    f = v[np.isfinite(v)]
    return f"{np.median(f):.3f}" if f.size else "-"


def _paired_ratio(a: Sequence[Row], b: Sequence[Row], metric: str, key) -> np.ndarray:
    base = {key(r): _num(r[metric]) for r in b}
    out = [_num(r[metric]) / base[key(r)] for r in a if key(r) in base]
    return np.asarray(out, float)


def flock_lines(rows: Sequence[Row], base: str = "off") -> list[str]:
    """swarm / ``base`` (off or pairs), paired by seed: median ratio [share within 10 %]
    per flock metric."""
    groups = _groups(rows, True)
    head = " | ".join(f"{h} swarm/{base}" for _, h in FLOCK_RATIOS)
    lines = [f"| N | start | policy | seeds | {head} |", "|---|---|---|---|" + "---|" * 5]
    for (n, init, pol, layer), g in groups.items():
        other = groups.get((n, init, pol, base))
        if layer != "swarm" or not other:
            continue
        cells = []
        for metric, _ in FLOCK_RATIOS:
            r = _paired_ratio(g, other, metric, lambda x: x["seed"])
            ok = np.count_nonzero(np.abs(r - 1) <= _WITHIN)
            cells.append(f"{np.nanmedian(r):.3f} [{ok}/{r.size}]")
        lines.append(f"| {n} | {init} | {pol} | {len(g)} | " + " | ".join(cells) + " |")
    return lines


def pair_lines(rows: Sequence[Row]) -> list[str]:
    """Steady error and band time, swarm / pairs paired by (seed, pair); pairs in the band."""
    groups = _groups(rows, False)
    lines = [
        "| N | start | policy | pair runs | steady error swarm/pairs | band time swarm/pairs "
        "| in band at the end: off / pairs / swarm |",
        "|---|---|---|---|---|---|---|",
    ]
    key = lambda x: (x["seed"], x["pair"])  # noqa: E731
    for (n, init, pol, layer), g in groups.items():
        if layer != "swarm":
            continue
        pairs = groups.get((n, init, pol, "pairs"), [])
        err = _paired_ratio(g, pairs, "ss_mean_error", key) if pairs else np.array([np.nan])
        band = _paired_ratio(g, pairs, "band_time", key) if pairs else np.array([np.nan])
        reached = []
        for lay in ("off", "pairs", "swarm"):
            sel = groups.get((n, init, pol, lay), [])
            hit = sum(math.isfinite(_num(r["band_time"])) for r in sel)
            reached.append(f"{hit}/{len(sel)}" if sel else "-")
        lines.append(
            f"| {n} | {init} | {pol} | {len(g)} | {_median(err)} | {_median(band)} | "
            f"{' / '.join(reached)} |"
        )
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    p = ArgumentParser(
        prog="python -m baselines.experiments.safety.swarm_report",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("folders", type=Path, nargs="+", help="benchmark result folders")
    args = p.parse_args(argv)
    with user_errors(p):
        rows = load_results(args.folders, "RUN_DIR")
        if not rows or "swarm_closest" not in rows[0]:
            raise ValueError(
                "the runs have no swarm_closest column: run the benchmark with "
                "--suite swarm-safety (or --set safety_scope=swarm)"
            )
        for title, lines in (
            ("Separation of every two UAVs", separation_lines(rows)),
            ("The flock: swarm layer / no filter, paired by seed", flock_lines(rows)),
            ("The flock: swarm layer / pair filter, paired by seed", flock_lines(rows, "pairs")),
            ("The pairs: swarm layer / pair filter, paired by seed and pair", pair_lines(rows)),
        ):
            print(f"\n## {title}\n")
            print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
