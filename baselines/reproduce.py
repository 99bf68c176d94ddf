"""Reproduce Sec. VI-A of the paper: sliding mode vs the proportional method vs no pair term.

    python -m baselines.reproduce                  # N = 20, 50, 100 x 10 seeds x 3 policies
    python -m baselines.reproduce --check          # also verify the acceptance criteria

Runs the "paper" preset (docs/paper-notes.md) for every (N, policy), all seeds of one
combination batched in one core, the combinations spread over worker processes. Writes
``results.csv`` (one row per run), ``summary.md`` (median and range per N and policy),
``run.json`` (config, seeds, versions, commit, timing) and PNG figures in the paper's style.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["main", "run_job", "summarize", "check_paper_claims"]

SUMMARY_METRICS = (
    ("s_settle_time", "s settle (s)", "{:.2f}"),
    ("band_time", "0.5 m band (s)", "{:.2f}"),
    ("ss_mean_error", "steady mean err (m)", "{:.3f}"),
    ("ss_max_error", "steady max err (m)", "{:.3f}"),
    ("min_pair_separation", "min pair-other dist (m)", "{:.2f}"),
    ("final_largest_component", "largest component", "{:.0f}"),
    ("final_velocity_mismatch", "velocity mismatch (m/s)", "{:.3f}"),
    ("peak_accel", "peak pair accel (m/s^2)", "{:.0f}"),
)


def _pin_threads() -> None:
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("MKL_NUM_THREADS", "1")


def run_job(
    n_uavs: int,
    policy: str,
    seeds: Sequence[int],
    overrides: dict[str, Any],
    record: bool,
    preset: str = "paper",
) -> dict[str, Any]:
    """One (N, policy) combination over all seeds; returns metrics and the series to plot."""
    _pin_threads()
    from pairflock_env import make_config

    from . import make_pair_policy
    from .rollout import rollout, trace_metrics

    cfg = make_config(preset, n_uavs=n_uavs, **overrides)
    pol = make_pair_policy(policy, cfg)
    t0 = time.perf_counter()
    tr = rollout(cfg, pol, seeds, record_rows=(0,) if record else ())
    wall = time.perf_counter() - t0
    rows = [{"n_uavs": n_uavs, "policy": policy, **m} for m in trace_metrics(tr)]
    out = {
        "n_uavs": n_uavs,
        "policy": policy,
        "rows": rows,
        "wall_s": wall,
        "t": tr.t,
        "pair_error": tr.pair_error[:, 0],
        "surface": tr.surface[:, 0],
        "config": cfg,
    }
    if record:
        out["positions"] = tr.positions[0]
        out["velocities"] = tr.velocities[0]
        out["leader_positions"] = tr.leader_positions[0]
    return out


def _stat(values: list[float], fmt: str) -> str:
    v = np.asarray(values, dtype=float)
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return "never"
    rng = f"{fmt.format(finite.min())}-{fmt.format(finite.max())}"
    if finite.size < v.size:
        return f"never in {v.size - finite.size}/{v.size}; others {rng}"
    return f"{fmt.format(np.median(v))} [{rng}]"


def summarize(rows: list[dict[str, Any]]) -> str:
    """Markdown table: median [min-max] over seeds per (N, policy)."""
    header = "| N | policy | " + " | ".join(h for _, h, _ in SUMMARY_METRICS) + " |"
    lines = [header, "|" + "---|" * (len(SUMMARY_METRICS) + 2)]
    keys = sorted({(r["n_uavs"], r["policy"]) for r in rows}, key=lambda x: (x[0], _order(x[1])))
    for n, pol in keys:
        sel = [r for r in rows if r["n_uavs"] == n and r["policy"] == pol]
        cells = [_stat([r[k] for r in sel], fmt) for k, _, fmt in SUMMARY_METRICS]
        lines.append(f"| {n} | {pol} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _order(policy: str) -> int:
    return {"smc": 0, "proportional": 1, "zero": 2}.get(policy, 3)


def check_paper_claims(rows: list[dict[str, Any]]) -> list[tuple[str, bool, str]]:
    """The acceptance criteria of the reproduction (every seed and every N)."""
    out = []
    ns = sorted({r["n_uavs"] for r in rows})
    for n in ns:
        smc = [r for r in rows if r["n_uavs"] == n and r["policy"] == "smc"]
        prop = [r for r in rows if r["n_uavs"] == n and r["policy"] == "proportional"]
        zero = [r for r in rows if r["n_uavs"] == n and r["policy"] == "zero"]
        if smc:
            s = np.array([r["s_settle_time"] for r in smc])
            b = np.array([r["band_time"] for r in smc])
            e = np.array([r["ss_mean_error"] for r in smc])
            out.append((f"N={n} smc: s settles in 1.5-3.0 s on every seed",
                        bool(np.all((s >= 1.5) & (s <= 3.0))), f"{np.nanmin(s):.2f}-{np.nanmax(s):.2f} s"))
            out.append((f"N={n} smc: 0.5 m band in 3.0-5.0 s on every seed",
                        bool(np.all((b >= 3.0) & (b <= 5.0))), f"{np.nanmin(b):.2f}-{np.nanmax(b):.2f} s"))
            out.append((f"N={n} smc: steady mean error <= 0.20 m on every seed",
                        bool(np.all(e <= 0.20)), f"max {np.max(e):.3f} m"))
            if prop:
                pm = float(np.median([r["ss_mean_error"] for r in prop]))
                sm = float(np.median(e))
                out.append((f"N={n} proportional median error >= 5x smc median",
                            pm >= 5 * sm, f"{pm:.3f} m vs {sm:.3f} m ({pm / sm:.1f}x)"))
        if zero:
            z = np.array([r["ss_mean_error"] for r in zero])
            out.append((f"N={n} zero: steady mean error >= 10 m on every seed",
                        bool(np.all(z >= 10.0)), f"min {np.min(z):.1f} m"))  # fmt: skip
    return out


def _figures(jobs: dict[tuple[int, str], dict[str, Any]], out_dir: Path) -> list[Path]:
    from .figures import error_figure, save_figure, snapshot_figure, surface_figure

    paths = []
    ns = sorted({n for n, _ in jobs})
    for (n, pol), j in sorted(jobs.items()):
        if "positions" not in j or pol == "zero":
            continue
        cfg = j["config"]
        horizon = j["t"][-1]
        times = [0.0, 2.0, 4.0, horizon]
        fig = snapshot_figure(
            j["t"], j["positions"], j["velocities"], j["leader_positions"], cfg.pairs, cfg.d_m,
            times, f"{n} UAVs, {pol}: positions and headings (seed {j['rows'][0]['seed']})",
        )  # fmt: skip
        paths.append(save_figure(fig, out_dir / f"snapshots_n{n}_{pol}.png", dpi=80))
    surf = {f"N = {n}": (jobs[n, "smc"]["t"], jobs[n, "smc"]["surface"][0])
            for n in ns if (n, "smc") in jobs}  # fmt: skip
    if surf:
        paths.append(save_figure(
            surface_figure(surf, 6.0, "Sliding surface s(t), sliding mode (seed 0)"),
            out_dir / "sliding_surface.png"))  # fmt: skip
    panels = {}
    for n in ns:
        curves = {p: (jobs[n, p]["t"], jobs[n, p]["pair_error"][0])
                  for p in ("smc", "proportional") if (n, p) in jobs}  # fmt: skip
        if curves:
            panels[f"N = {n}"] = curves
    if panels:
        paths.append(save_figure(
            error_figure(panels, "Pair distance error: normal method vs sliding mode (seed 0)"),
            out_dir / "pair_error.png"))  # fmt: skip
    return paths


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m baselines.reproduce",
        description=__doc__.split("\n\n")[0] + " Writes CSV, markdown and PNG figures.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--n-uavs", type=int, nargs="+", default=[20, 50, 100], help="swarm sizes N")
    p.add_argument("--seeds", type=int, default=10, help="number of seeds per (N, policy)")
    p.add_argument("--first-seed", type=int, default=0, help="seeds are first-seed, first-seed+1, ...")
    p.add_argument("--policies", nargs="+", default=["smc", "proportional", "zero"],
                   help="pair controllers (names for baselines.make_pair_policy)")
    p.add_argument("--horizon", type=float, default=None, help="episode length in s (preset: 50)")
    p.add_argument("--out", type=Path, default=Path("results/reproduce"), help="output folder")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                   help="worker processes (1 runs in this process)")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--check", action="store_true",
                   help="verify the paper's claims (exit status 1 if any fails)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    _pin_threads()
    from tqdm import tqdm

    from . import POLICIES
    from .io import atomic_write_text, run_record, write_csv, write_json

    if args.seeds < 1:
        raise SystemExit(f"--seeds={args.seeds} is invalid: must be >= 1")
    for n in args.n_uavs:
        if n < 2:
            raise SystemExit(f"--n-uavs {n} is invalid: must be >= 2")
    for pol in args.policies:
        if pol not in POLICIES and ":" not in pol:
            raise SystemExit(f"--policies {pol!r} is invalid: valid are {', '.join(POLICIES)}")
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    overrides = {} if args.horizon is None else {"horizon": args.horizon}
    combos = [(n, pol) for n in args.n_uavs for pol in args.policies]
    # the slowest jobs first so the pool stays busy
    combos.sort(key=lambda c: -c[0])
    record = not args.no_figures
    t0 = time.perf_counter()
    results: dict[tuple[int, str], dict[str, Any]] = {}
    bar = tqdm(total=len(combos), unit="job", desc="reproduce", disable=args.quiet)
    if args.workers <= 1:
        for n, pol in combos:
            results[n, pol] = run_job(n, pol, seeds, overrides, record)
            bar.update()
    else:
        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            futs = {pool.submit(run_job, n, pol, seeds, overrides, record): (n, pol)
                    for n, pol in combos}  # fmt: skip
            for f in as_completed(futs):
                results[futs[f]] = f.result()
                bar.update()
    bar.close()
    sim_wall = time.perf_counter() - t0

    rows = [r for c in sorted(results, key=lambda c: (c[0], _order(c[1]))) for r in results[c]["rows"]]
    out = args.out
    columns = list(rows[0])
    write_csv(out / "results.csv", rows, columns)
    table = summarize(rows)
    checks = check_paper_claims(rows)
    md = [
        "# Reproduction of Sec. VI-A",
        "",
        f"Preset `paper`, {len(seeds)} seeds ({seeds[0]}-{seeds[-1]}) per row, "
        f"horizon {results[combos[0]]['t'][-1]:.0f} s; median [min-max] over seeds.",
        "",
        table,
        "",
    ]
    if checks:
        md += ["## Acceptance criteria", "", "| criterion | result | measured |", "|---|---|---|"]
        md += [f"| {c} | {'pass' if ok else 'FAIL'} | {d} |" for c, ok, d in checks]
    atomic_write_text(out / "summary.md", "\n".join(md) + "\n")
    fig_paths = _figures(results, out) if record else []
    total = time.perf_counter() - t0
    write_json(out / "run.json", run_record(
        preset="paper", seeds=seeds, n_uavs=args.n_uavs, policies=args.policies,
        overrides=overrides, config={f"{n}": results[n, args.policies[0]]["config"].to_dict()
                                     for n in args.n_uavs},
        timing={"simulation_s": round(sim_wall, 2), "total_s": round(total, 2),
                "workers": args.workers},
    ))  # fmt: skip
    print(table)
    if checks:
        print()
        for c, ok, d in checks:
            print(f"[{'pass' if ok else 'FAIL'}] {c}: {d}")
    print(f"\nwrote {out / 'results.csv'}, {out / 'summary.md'}, {len(fig_paths)} figures "
          f"in {total:.1f} s (simulation {sim_wall:.1f} s, {args.workers} workers)")  # fmt: skip
    if args.check and not all(ok for _, ok, _ in checks):
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
