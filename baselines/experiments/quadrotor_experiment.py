"""The paper's 10-quadrotor experiment (Sec. VI-B), with the particle model side by side.

    python -m baselines.quadrotor_experiment                # 10 seeds, smc/proportional/zero
    python -m baselines.quadrotor_experiment --check        # also verify the issue's criteria

Runs the ``paper-quadrotor`` preset (docs/quadrotor.md): 10 quadrotors, one pair starting
28 m apart, the virtual leader at 5 m/s climbing for 20 s and turning left by 90 degrees
during 20-22 s and 50-52 s, 65 s. Every (vehicle model, policy) combination runs all seeds
in one batched core (``baselines.rollout``), the combinations spread over worker processes;
the particle model flies the same scenario, seeds and gains (without the quadrotor's
acceleration limit and tilt cone, which belong to the vehicle).

Per seed it measures what the issue asks for (times in s, distances in m):

* ``band_entry_time``: first time |pair error| < 0.5 m;
* ``straight_max_error``: max |pair error| in straight flight, [15, 20], [27, 50], [57, 65];
* ``turn_peak_error``: max |pair error| in and after the turns, [20, 27] and [50, 57];
* ``min_distance``: smallest distance between any two UAVs (partners included) at any time;
* ``velocity_mismatch``: max ||p_i - p_leader|| of the unpaired UAVs in [35, 50] and [60, 65];
* ``pair_offset``: mean distance of the pair's midpoint from the virtual leader in straight
  flight (where the pair flies relative to its flock, which stays centred on the leader);

plus the general episode metrics of ``pairflock_env.metrics`` and, for the quadrotor, how
often the paired UAVs fly at the acceleration/tilt limit or saturate a motor.

Writes ``results.csv`` (one row per run), ``summary.md`` (median [min-max] per vehicle and
policy, and the criteria), ``run.json`` (config, seeds, versions, commit, timing) and PNG
figures in the style of Figs. 15-20: ``snapshots.png`` (positions and headings at several
times), ``trajectories_3d.png``, ``sliding_surface.png``, ``pair_error.png`` and
``euler_angles.png`` (commanded vs actual attitude of paired UAV No. 1).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from baselines.evaluation.parallel import imap_unordered, pin_threads
from baselines.reporting.tables import stat_cell

__all__ = [
    "CRITERIA",
    "PRESET",
    "check_criteria",
    "main",
    "run_job",
    "scenario_metrics",
    "summarize",
]

PRESET = "paper-quadrotor"
#: straight flight, and the turns with the recovery after them, in s
STRAIGHT_WINDOWS = ((15.0, 20.0), (27.0, 50.0), (57.0, 65.0))
TURN_WINDOWS = ((20.0, 27.0), (50.0, 57.0))
VELOCITY_WINDOWS = ((35.0, 50.0), (60.0, 65.0))
#: the issue's acceptance thresholds for sliding mode on the quadrotor
CRITERIA = {
    "band": 0.5,  # m
    "band_entry_by": 10.0,  # s
    "straight_max": 0.5,  # m
    "turn_peak_max": 0.6,  # m
    "min_distance": 0.5,  # m
    "velocity_tolerance": 0.6,  # m/s
    "attitude_cost": 0.35,  # m, quadrotor minus particle straight-flight max error
}

SUMMARY_COLUMNS = (
    ("band_entry_time", "into 0.5 m band (s)", "{:.2f}"),
    ("straight_max_error", "straight max err (m)", "{:.3f}"),
    ("straight_mean_error", "straight mean err (m)", "{:.3f}"),
    ("turn_peak_error", "turn peak err (m)", "{:.3f}"),
    ("min_distance", "min UAV distance (m)", "{:.2f}"),
    ("velocity_mismatch", "unpaired vel. mismatch (m/s)", "{:.3f}"),
    ("pair_offset", "pair midpoint to leader (m)", "{:.2f}"),
    ("peak_accel", "peak pair accel (m/s^2)", "{:.1f}"),
    ("pair_accel_limited_frac", "pair at accel/tilt limit (%)", "{:.0f}"),
    ("crashed", "crashes", "{:.0f}"),
)


def _window_mask(t: np.ndarray, windows) -> np.ndarray:
    m = np.zeros(t.shape, bool)
    for a, b in windows:
        m |= (t >= a - 1e-9) & (t <= b + 1e-9)
    return m


def scenario_metrics(
    t: np.ndarray,
    pair_error: np.ndarray,
    min_distance: np.ndarray,
    velocity_mismatch_max: np.ndarray,
    pair_offset: np.ndarray,
    band: float = CRITERIA["band"],
) -> dict[str, float]:
    """The Sec. VI-B figures of one run from its series (each (T,), sampled at times t)."""
    err = np.abs(pair_error)
    inside = np.flatnonzero(err < band)
    straight = _window_mask(t, STRAIGHT_WINDOWS)
    turns = _window_mask(t, TURN_WINDOWS)
    vel = _window_mask(t, VELOCITY_WINDOWS)
    nan = float("nan")
    return {
        "band_entry_time": float(t[inside[0]]) if inside.size else nan,
        "straight_max_error": float(err[straight].max()) if straight.any() else nan,
        "straight_mean_error": float(err[straight].mean()) if straight.any() else nan,
        "turn_peak_error": float(err[turns].max()) if turns.any() else nan,
        "min_distance": float(min_distance.min()),
        "velocity_mismatch": float(velocity_mismatch_max[vel].max()) if vel.any() else nan,
        "pair_offset": float(pair_offset[straight].mean()) if straight.any() else nan,
    }


class _Recorder:
    """``rollout`` hook: what the trace does not keep (all-UAV distance, unpaired velocity
    mismatch, quadrotor limits, and the attitude of one paired UAV of one swarm)."""

    def __init__(
        self, B: int, T: int, pair: tuple[int, int], attitude_of: tuple[int, int] | None
    ) -> None:
        self.pair = pair
        self.pair_offset = np.full((B, T + 1), np.nan)
        self.min_distance = np.full((B, T + 1), np.nan)
        self.velocity_mismatch = np.full((B, T + 1), np.nan)
        self.limited_steps = np.zeros(B, np.int64)
        self.saturated_steps = np.zeros(B, np.int64)
        self.crashed = np.zeros(B, bool)
        self.attitude_of = attitude_of
        self.R = np.full((T + 1, 3, 3), np.nan) if attitude_of else None
        self.R_des = np.full((T + 1, 3, 3), np.nan) if attitude_of else None

    def __call__(self, k: int, core, res, live: np.ndarray) -> None:
        q = core.q
        d2 = np.sum((q[:, :, None, :] - q[:, None, :, :]) ** 2, axis=-1)
        N = q.shape[1]
        d2[:, np.arange(N), np.arange(N)] = np.inf
        self.min_distance[live, k] = np.sqrt(d2.min(axis=(1, 2)))[live]
        self.velocity_mismatch[live, k] = res.info["velocity_mismatch_max"][live]
        lq, _ = core.leader_state()
        mid = 0.5 * (q[:, self.pair[0]] + q[:, self.pair[1]])
        self.pair_offset[live, k] = np.linalg.norm(mid - lq, axis=-1)[live]
        if "accel_limited" in res.info and k > 0:
            self.limited_steps[live] += res.info["accel_limited"][live].any(axis=1)
            self.saturated_steps[live] += res.info["motor_saturated"][live].any(axis=1)
            self.crashed |= res.info["vehicle_terminated"] & live
        if self.attitude_of is not None and hasattr(core.vehicle, "R_des"):
            b, i = self.attitude_of
            if live[b]:
                self.R[k] = core.vehicle.R[b, i]
                self.R_des[k] = core.vehicle.R_des[b, i]

    def finish(self, ended: np.ndarray) -> None:
        """Hold each swarm's series at its last value after its episode ended."""
        for b, e in enumerate(ended):
            for arr in (self.min_distance, self.velocity_mismatch, self.pair_offset):
                arr[b, e + 1 :] = arr[b, e]


def run_job(
    dynamics: str,
    policy: str,
    seeds: Sequence[int],
    overrides: dict[str, Any],
    gains: dict[str, Any],
    record: bool,
) -> dict[str, Any]:
    """One (vehicle model, policy) combination over all seeds, batched in one core."""
    pin_threads()
    from baselines.controllers import make_pair_policy
    from baselines.evaluation.rollout import rollout, trace_metrics
    from pairflock_env import make_config

    cfg = make_config(PRESET, dynamics=dynamics, **overrides)
    pol = make_pair_policy(policy, cfg, **gains.get(policy, {}))
    T = cfg.episode_steps
    rec = _Recorder(len(seeds), T, cfg.pairs[0], (0, cfg.pairs[0][0]) if record else None)
    t0 = time.perf_counter()
    tr = rollout(cfg, pol, seeds, record_rows=(0,) if record else (), on_step=rec)
    wall = time.perf_counter() - t0
    rec.finish(tr.ended)
    general = trace_metrics(tr)
    rows = []
    for b, g in enumerate(general):  # one pair: one row per swarm
        sm = scenario_metrics(
            tr.t,
            tr.pair_error[b, 0],
            rec.min_distance[b],
            rec.velocity_mismatch[b],
            rec.pair_offset[b],
        )
        steps = max(int(tr.ended[b]), 1)
        rows.append(
            {
                "dynamics": dynamics,
                "policy": policy,
                "seed": g["seed"],
                **sm,
                "pair_accel_limited_frac": 100.0 * rec.limited_steps[b] / steps,
                "pair_motor_saturated_frac": 100.0 * rec.saturated_steps[b] / steps,
                "crashed": int(rec.crashed[b]),
                **{k: v for k, v in g.items() if k not in ("seed", "pair")},
            }
        )
    out: dict[str, Any] = {
        "dynamics": dynamics,
        "policy": policy,
        "rows": rows,
        "wall_s": wall,
        "sim_s": float(len(seeds) * T * cfg.dt),
        "t": tr.t,
        "pair_error": tr.pair_error[:, 0],
        "surface": tr.surface[:, 0],
        "config": cfg,
    }
    if record:
        out["positions"] = tr.positions[0]
        out["velocities"] = tr.velocities[0]
        out["leader_positions"] = tr.leader_positions[0]
        if rec.R is not None and np.isfinite(rec.R).all():
            out["R"], out["R_des"] = rec.R, rec.R_des
    return out


# --------------------------------------------------------------------------- report
def _order(key: tuple[str, str]) -> tuple[int, int]:
    dyn, pol = key
    return (
        {"quadrotor": 0, "particle": 1}.get(dyn, 2),
        {"smc": 0, "proportional": 1, "zero": 2}.get(pol, 3),
    )


def summarize(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown table: median [min-max] over seeds per (vehicle model, policy)."""
    head = "| vehicle | policy | " + " | ".join(h for _, h, _ in SUMMARY_COLUMNS) + " |"
    lines = [head, "|" + "---|" * (len(SUMMARY_COLUMNS) + 2)]
    for dyn, pol in sorted({(r["dynamics"], r["policy"]) for r in rows}, key=_order):
        sel = [r for r in rows if r["dynamics"] == dyn and r["policy"] == pol]
        cells = []
        for key, _, fmt in SUMMARY_COLUMNS:
            if dyn == "particle" and key in ("pair_accel_limited_frac", "crashed"):
                cells.append("-")  # no such limit on a particle
            elif key == "crashed":
                cells.append(f"{sum(int(r[key]) for r in sel)}/{len(sel)}")
            else:
                cells.append(stat_cell([r[key] for r in sel], fmt))
        lines.append(f"| {dyn} | {pol} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def check_criteria(rows: Sequence[dict[str, Any]]) -> list[tuple[str, bool, str]]:
    """The issue's criteria for sliding mode on the quadrotor, every seed."""
    c = CRITERIA
    smc = sorted(
        (r for r in rows if r["dynamics"] == "quadrotor" and r["policy"] == "smc"),
        key=lambda r: r["seed"],
    )
    if not smc:
        return []

    def arr(key, sel=smc):
        return np.array([float(r[key]) for r in sel])

    out = []
    entry = arr("band_entry_time")
    out.append(
        (
            f"smc: into the {c['band']} m band within {c['band_entry_by']:g} s",
            bool(np.all(entry <= c["band_entry_by"])),
            f"{np.nanmin(entry):.2f}-{np.nanmax(entry):.2f} s"
            if np.isfinite(entry).any()
            else "never",
        )
    )
    s = arr("straight_max_error")
    out.append(
        (
            f"smc: max abs pair error <= {c['straight_max']} m in [15,20], [27,50], [57,65] s",
            bool(np.all(s <= c["straight_max"])),
            f"max {np.max(s):.3f} m",
        )
    )
    tp = arr("turn_peak_error")
    out.append(
        (
            f"smc: peak abs pair error in the turns <= {c['turn_peak_max']} m",
            bool(np.all(tp <= c["turn_peak_max"])),
            f"max {np.max(tp):.3f} m",
        )
    )
    md = arr("min_distance")
    out.append(
        (
            f"smc: no two UAVs closer than {c['min_distance']} m",
            bool(np.all(md >= c["min_distance"])),
            f"min {np.min(md):.2f} m",
        )
    )
    vm = arr("velocity_mismatch")
    out.append(
        (
            (
                f"smc: unpaired velocity within {c['velocity_tolerance']} m/s of the leader "
                "in [35,50], [60,65] s"
            ),
            bool(np.all(vm <= c["velocity_tolerance"])),
            f"max {np.max(vm):.3f} m/s",
        )
    )
    crashed = arr("crashed")
    out.append(
        (
            "smc: no crash, every episode runs 65 s",
            bool(np.all(crashed == 0) and np.all(arr("steps_run") == smc[0]["steps_run"])),
            f"{int(crashed.sum())} crashes",
        )
    )
    part = {r["seed"]: r for r in rows if r["dynamics"] == "particle" and r["policy"] == "smc"}
    if part and all(r["seed"] in part for r in smc):
        cost = s - np.array([float(part[r["seed"]]["straight_max_error"]) for r in smc])
        out.append(
            (
                (
                    f"smc: attitude loop costs <= {c['attitude_cost']} m over the particle "
                    "(straight-flight max error, same seed)"
                ),
                bool(np.all(cost <= c["attitude_cost"])),
                f"{np.min(cost):+.3f} to {np.max(cost):+.3f} m",
            )
        )
    return out


# --------------------------------------------------------------------------- figures
def _figures(jobs: dict[tuple[str, str], dict[str, Any]], out: Path, dpi: int) -> list[Path]:
    from baselines.reporting import quadrotor_figures as qf
    from baselines.reporting.figures import (
        save_figure,
        surface_panels_figure,
        trajectories_3d_figure,
    )

    paths: list[Path] = []
    main_key = ("quadrotor", "smc") if ("quadrotor", "smc") in jobs else next(iter(jobs))
    j = jobs[main_key]
    cfg = j["config"]
    seed = j["rows"][0]["seed"]
    if "positions" in j:
        times = [0.0, 4.0, 8.0, 20.0, 21.0, 35.0, 51.0, float(j["t"][-1])]
        fig = qf.snapshots_figure(
            j["t"],
            j["positions"],
            j["velocities"],
            j["leader_positions"],
            cfg.pairs,
            cfg.d_m,
            times,
            f"10 quadrotors, sliding mode: positions and headings (seed {seed})",
        )
        paths.append(save_figure(fig, out / "snapshots.png", dpi=dpi))
        fig = trajectories_3d_figure(
            j["positions"],
            j["leader_positions"],
            cfg.pairs,
            f"3-D trajectories, {main_key[0]}, sliding mode (seed {seed})",
            t=j["t"],
            marks=(0.0, 20.0, 35.0, 50.0),
        )
        paths.append(save_figure(fig, out / "trajectories_3d.png", dpi=dpi))
    surf = {
        f"{dyn}, {pol}": (v["t"], v["surface"][0]) for (dyn, pol), v in jobs.items() if pol == "smc"
    }
    if surf:
        fig = surface_panels_figure(
            {k: {k: v} for k, v in surf.items()},
            np.inf,
            f"Sliding surface s(t), sliding mode (seed {seed})",
            ncols=1,
            linthresh=1.0,
            sharey=True,
        )
        paths.append(save_figure(fig, out / "sliding_surface.png", dpi=dpi))
    curves = {(dyn, pol): (v["t"], v["pair_error"][0]) for (dyn, pol), v in jobs.items()}
    fig = qf.pair_error_figure(
        curves, STRAIGHT_WINDOWS, CRITERIA["band"], f"Pair distance error ||y|| - d_m (seed {seed})"
    )
    paths.append(save_figure(fig, out / "pair_error.png", dpi=dpi))
    if "R" in j:
        fig = qf.euler_figure(
            j["t"],
            j["R_des"],
            j["R"],
            f"Paired UAV No. 1, sliding mode: attitude commands (Fig. 19) "
            f"and response (Fig. 20), seed {seed}",
        )
        paths.append(save_figure(fig, out / "euler_angles.png", dpi=dpi))
    return paths


# --------------------------------------------------------------------------- CLI
def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m baselines.quadrotor_experiment",
        description=__doc__.split("\n\n")[0] + " Writes CSV, markdown and PNG figures.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--seeds", type=int, default=10, help="number of seeds per combination")
    p.add_argument(
        "--first-seed", type=int, default=0, help="seeds are first-seed, first-seed+1, ..."
    )
    p.add_argument(
        "--policies",
        nargs="+",
        default=["smc", "proportional", "zero"],
        help="pair controllers (names for baselines.make_pair_policy)",
    )
    p.add_argument(
        "--dynamics",
        nargs="+",
        default=["quadrotor", "particle"],
        choices=["quadrotor", "particle"],
        help="vehicle models to compare",
    )
    p.add_argument(
        "--smc-k",
        type=float,
        default=None,
        help="switching gain k of sliding mode (default: the preset's, 10 m/s^2)",
    )
    p.add_argument(
        "--smc-c",
        type=float,
        default=None,
        help="surface slope c of sliding mode (default: the preset's, 1 1/s)",
    )
    p.add_argument("--kp", type=float, default=None, help="gain k_p of proportional (default 1)")
    p.add_argument("--horizon", type=float, default=None, help="episode length in s (preset: 65)")
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="override a PairFlockConfig field for every run (repeatable), e.g. "
        "--set quad_motor_time_constant=0.05 (values are Python literals)",
    )
    p.add_argument("--out", type=Path, default=Path("results/quadrotor"), help="output folder")
    p.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="worker processes (1 runs in this process)",
    )
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--dpi", type=int, default=100, help="resolution of the PNG figures")
    p.add_argument(
        "--check",
        action="store_true",
        help="verify the issue's criteria (exit status 1 if any fails)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def _parse_overrides(items: Sequence[str]) -> dict[str, Any]:
    import ast

    out: dict[str, Any] = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"--set {item!r} is invalid: expected FIELD=VALUE")
        key, text = item.split("=", 1)
        try:
            out[key.strip()] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            out[key.strip()] = text  # a bare word such as a leader name
    return out


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    pin_threads()
    from tqdm import tqdm

    from baselines.controllers import POLICIES
    from baselines.evaluation.io import atomic_write_text, run_record, write_csv, write_json
    from pairflock_env import make_config

    if args.seeds < 1:
        raise SystemExit(f"--seeds={args.seeds} is invalid: must be >= 1")
    if args.workers < 1:
        raise SystemExit(f"--workers={args.workers} is invalid: must be >= 1")
    for pol in args.policies:
        if pol not in POLICIES and ":" not in pol:
            raise SystemExit(f"--policies {pol!r} is invalid: valid are {', '.join(POLICIES)}")
    overrides = _parse_overrides(args.overrides)
    if args.horizon is not None:
        overrides["horizon"] = args.horizon
    for dyn in args.dynamics:  # fail early, in this process, on a bad override
        try:
            make_config(PRESET, dynamics=dyn, **overrides)
        except (TypeError, ValueError) as exc:
            raise SystemExit(f"invalid configuration: {exc}") from None
    gains: dict[str, dict[str, float]] = {"smc": {}, "proportional": {}}
    if args.smc_k is not None:
        gains["smc"]["k"] = args.smc_k
    if args.smc_c is not None:
        gains["smc"]["c"] = args.smc_c
    if args.kp is not None:
        gains["proportional"]["k_p"] = args.kp
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    combos = [(d, p) for d in args.dynamics for p in args.policies]
    combos.sort(key=lambda c: c[0] != "quadrotor")  # the slower model first
    record = not args.no_figures
    t0 = time.perf_counter()
    results: dict[tuple[str, str], dict[str, Any]] = {}
    bar = tqdm(total=len(combos), unit="job", desc="quadrotor experiment", disable=args.quiet)
    job_args = {c: (c[0], c[1], seeds, overrides, gains, record and c[1] != "zero") for c in combos}
    for i, res in imap_unordered(run_job, [job_args[c] for c in combos], args.workers):
        results[combos[i]] = res
        bar.update()
    bar.close()
    sim_wall = time.perf_counter() - t0

    keys = sorted(results, key=_order)
    rows = [r for k in keys for r in results[k]["rows"]]
    out = args.out
    write_csv(out / "results.csv", rows, list(rows[0]))
    table = summarize(rows)
    checks = check_criteria(rows)
    cfg = results[keys[0]]["config"]
    intro = (
        f"Preset `{PRESET}` (docs/quadrotor.md), {len(seeds)} seeds ({seeds[0]}-{seeds[-1]}) "
        f"per row, {cfg.episode_steps * cfg.dt:g} s, protocol every {cfg.dt:g} s, physics "
        f"every {cfg.physics_dt:g} s; median [min-max] over seeds. Straight flight = "
        "[15,20], [27,50], [57,65] s; turns = [20,27], [50,57] s; velocity mismatch over "
        "[35,50], [60,65] s. The particle model flies the same scenario, seeds and gains "
        "without the quadrotor's acceleration limit and tilt cone."
    )
    md = [
        "# Sec. VI-B: 10 quadrotors, pairwise control",
        "",
        intro,
        "",
        table,
        "",
    ]
    if overrides or any(gains.values()):
        md += [f"Overrides: `{overrides}`; gains: `{gains}`.", ""]
    if checks:
        md += [
            "## Criteria (sliding mode on the quadrotor, every seed)",
            "",
            "| criterion | result | measured |",
            "|---|---|---|",
        ]
        md += [f"| {c} | {'pass' if ok else 'FAIL'} | {d} |" for c, ok, d in checks]
    atomic_write_text(out / "summary.md", "\n".join(md) + "\n")
    fig_paths = _figures(results, out, args.dpi) if record else []
    total = time.perf_counter() - t0
    write_json(
        out / "run.json",
        run_record(
            preset=PRESET,
            seeds=seeds,
            policies=args.policies,
            dynamics=args.dynamics,
            overrides=overrides,
            gains=gains,
            config={d: results[d, args.policies[0]]["config"].to_dict() for d in args.dynamics},
            timing={
                "simulation_s": round(sim_wall, 2),
                "total_s": round(total, 2),
                "workers": args.workers,
                "sim_seconds_per_wall_second": {
                    f"{d}/{p}": round(v["sim_s"] / v["wall_s"], 1) for (d, p), v in results.items()
                },
            },
        ),
    )
    print(table)
    if checks:
        print()
        for c, ok, d in checks:
            print(f"[{'pass' if ok else 'FAIL'}] {c}: {d}")
    print(
        f"\nwrote {out / 'results.csv'}, {out / 'summary.md'}, {len(fig_paths)} figures in "
        f"{total:.1f} s (simulation {sim_wall:.1f} s, {args.workers} workers)"
    )
    if args.check and not (checks and all(ok for _, ok, _ in checks)):
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
