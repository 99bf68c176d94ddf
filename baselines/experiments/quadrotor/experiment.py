"""The paper's 10-quadrotor experiment (Sec. VI-B), with the particle model side by side.

    python -m baselines.quadrotor_experiment                # 10 seeds, smc/proportional/zero
    python -m baselines.quadrotor_experiment --check        # also verify the Sec. VI-B criteria
    python -m baselines.quadrotor_experiment --policies smc sb3:pair_quad3d   # a learned policy
    python -m baselines.quadrotor_experiment --preset crazyflie --check  # the scaled scenario

Runs the ``paper-quadrotor`` preset (docs/quadrotor.md): 10 quadrotors, one pair starting
28 m apart, the virtual leader at 5 m/s climbing for 20 s and turning left by 90 degrees
during 20-22 s and 50-52 s, 65 s. Every (vehicle model, policy) combination runs all seeds
in one batched core (``baselines.evaluation.rollout``), the combinations spread over worker
processes; the particle model flies the same scenario, seeds and gains (without the quadrotor's
acceleration limit and tilt cone, which belong to the vehicle).

Per seed it measures the Sec. VI-B figures listed in :mod:`baselines.experiments.quadrotor.runs`
(band entry, straight-flight and turn errors, closest approach, velocity mismatch), next to
the general episode metrics.

Writes ``results.csv`` (one row per run), ``summary.md`` (median [min-max] per vehicle and
policy, and the criteria), ``run.json`` (config, seeds, versions, commit, timing) and PNG
figures in the style of Figs. 15-20: ``snapshots.png`` (positions and headings at several
times), ``trajectories_3d.png``, ``sliding_surface.png``, ``pair_error.png`` and
``euler_angles.png`` (commanded vs actual attitude of paired UAV No. 1).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from baselines.controllers import POLICIES, make_pair_policy
from baselines.evaluation.recording import (
    RecordOptions,
    add_record_options,
    check_run_names,
    record_options,
    report_line,
    run_name,
    written,
)
from baselines.evaluation.specs import parse_assignment
from baselines.experiments.quadrotor.criteria import (
    QUADROTOR,
    SCENARIO_WINDOWS,
    check_quadrotor,
    criteria_for,
    windows_text,
)
from baselines.experiments.quadrotor.figures import figure_set
from baselines.experiments.quadrotor.runs import PRESET, run_job, scenario_metrics
from baselines.reporting.criteria import all_passed, criteria_lines, criteria_table
from baselines.reporting.tables import stat_cell, summary_table
from baselines.runtime.cli import ArgumentParser, at_least, user_errors
from baselines.runtime.files import atomic_write_text, write_csv, write_json
from baselines.runtime.folders import result_folder
from baselines.runtime.pool import imap_unordered
from baselines.runtime.record import run_record
from pairflock_env import make_config

__all__ = [
    "CRITERIA",
    "ELLIPSOID_COLUMNS",
    "PRESET",
    "SUMMARY_COLUMNS",
    "build_parser",
    "check_criteria",
    "criteria_policies",
    "main",
    "run_job",
    "scenario_metrics",
    "summarize",
]

#: the Sec. VI-B thresholds (defined in :mod:`baselines.reporting.criteria`), as a dict
CRITERIA = dataclasses.asdict(QUADROTOR)
#: the Sec. VI-B criteria on the quadrotor, every seed (sliding mode unless told otherwise)
check_criteria = check_quadrotor
PROG = "python -m baselines.quadrotor_experiment"


def _limited_cell(values: list[Any], rows: list[dict[str, Any]]) -> str:
    return "-" if rows[0]["dynamics"] == "particle" else stat_cell(values, "{:.0f}")


def _crashes_cell(values: list[Any], rows: list[dict[str, Any]]) -> str:
    if rows[0]["dynamics"] == "particle":
        return "-"  # no such limit on a particle
    return f"{sum(int(v) for v in values)}/{len(values)}"


SUMMARY_COLUMNS = (
    ("band_entry_time", "first in the band (s)", "{:.2f}"),
    ("straight_max_error", "straight max err (m)", "{:.3f}"),
    ("straight_mean_error", "straight mean err (m)", "{:.3f}"),
    ("turn_peak_error", "turn peak err (m)", "{:.3f}"),
    ("min_distance", "min UAV distance (m)", "{:.2f}"),
    ("velocity_mismatch", "unpaired vel. mismatch (m/s)", "{:.3f}"),
    ("pair_offset", "pair midpoint to leader (m)", "{:.2f}"),
    ("peak_accel", "peak pair accel (m/s^2)", "{:.1f}"),
    ("pair_accel_limited_frac", "pair at accel/tilt limit (%)", _limited_cell),
    ("crashed", "crashes", _crashes_cell),
)


def _order(key: tuple[str, str]) -> tuple[int, int]:
    dyn, pol = key
    return (
        {"quadrotor": 0, "crazyflie": 0, "particle": 1}.get(dyn, 2),
        {"smc": 0, "proportional": 1, "zero": 2}.get(pol, 3),
    )


#: with the collision ellipsoid (``collision_height``), after ``min_distance``
ELLIPSOID_COLUMNS = (
    ("min_ellipsoid_separation", "min ellipsoid separation (1)", "{:.2f}"),
    ("ellipsoid_contact_steps", "ellipsoid contact steps", "{:.0f}"),
)


def summarize(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown table: median [min-max] over seeds per (vehicle model, policy); the
    ellipsoid's columns (:data:`ELLIPSOID_COLUMNS`) where the rows have them."""
    columns = SUMMARY_COLUMNS
    if rows and "min_ellipsoid_separation" in rows[0]:
        at = 1 + [c[0] for c in columns].index("min_distance")
        columns = (*columns[:at], *ELLIPSOID_COLUMNS, *columns[at:])
    return summary_table(
        rows,
        columns,
        lead=(("vehicle", "dynamics"), ("policy", "policy")),
        group=lambda r: (r["dynamics"], r["policy"]),
        sort=_order,
    )


# --------------------------------------------------------------------------- CLI
def _run_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--preset",
        default=PRESET,
        choices=list(SCENARIO_WINDOWS),
        help="the scenario: the paper's, or the crazyflie preset (10 Crazyflies in a lab), "
        "whose criteria are the paper's with every length scaled by its d_m / 2.5 m",
    )
    p.add_argument("--seeds", type=int, default=10, help="number of seeds per combination")
    p.add_argument(
        "--first-seed", type=at_least(0), default=0, help="seeds are first-seed, first-seed+1, ..."
    )
    p.add_argument(
        "--policies",
        nargs="+",
        default=["smc", "proportional", "zero"],
        help="pair controllers (names for baselines.make_pair_policy: smc, proportional, "
        "zero, sb3:<model path or packaged name>)",
    )
    p.add_argument(
        "--dynamics",
        nargs="+",
        default=None,
        choices=["quadrotor", "crazyflie", "particle"],
        help="vehicle models to compare (default: the preset's and the particle)",
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
    p.add_argument(
        "--smc-boundary-layer",
        type=float,
        default=None,
        metavar="PHI",
        help="boundary layer phi (m^2/s) of sliding mode: sat(s/phi) in place of the paper's "
        "sign(s) (default: sign)",
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
        "--set quad_motor_time_constant=0.05 (numbers as written, lists, words)",
    )


def build_parser() -> argparse.ArgumentParser:
    """The experiment's argument parser."""
    p = ArgumentParser(
        prog=PROG,
        description=__doc__.split("\n\n")[0] + " Writes CSV, markdown and PNG figures.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    _run_options(p)
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
        help="verify the Sec. VI-B criteria (exit status 1 if any fails or none applies)",
    )
    p.add_argument(
        "--criteria-for",
        nargs="+",
        default=None,
        metavar="POLICY",
        help="controllers the Sec. VI-B criteria are checked for (default: smc and every "
        "learned sb3: policy run)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_record_options(p)
    return p


def _settings(args: argparse.Namespace) -> tuple[dict[str, Any], dict[str, dict[str, float]]]:
    """Validated (config overrides, gains per policy); ``ValueError`` naming a bad one."""
    if args.seeds < 1:
        raise ValueError(f"--seeds={args.seeds} is invalid: must be >= 1")
    if args.workers < 1:
        raise ValueError(f"--workers={args.workers} is invalid: must be >= 1")
    if args.dynamics is None:  # the preset's vehicle, and the particle for the attitude cost
        args.dynamics = [criteria_for(args.preset).vehicle, "particle"]
    for pol in args.policies:
        if pol not in POLICIES and ":" not in pol:
            raise ValueError(f"--policies {pol!r} is invalid: valid are {', '.join(POLICIES)}")
    overrides = dict(parse_assignment(item, "--set") for item in args.overrides)
    if args.horizon is not None:
        overrides["horizon"] = args.horizon
    for dyn in args.dynamics:  # fail early, in this process, on a bad override
        try:
            make_config(args.preset, dynamics=dyn, **overrides)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"invalid configuration: {exc}") from None
    gains: dict[str, dict[str, float]] = {"smc": {}, "proportional": {}}
    for policy, gain, value in (
        ("smc", "k", args.smc_k),
        ("smc", "c", args.smc_c),
        ("smc", "boundary_layer", args.smc_boundary_layer),
    ):
        if value is not None:
            gains[policy][gain] = value
    if args.kp is not None:
        gains["proportional"]["k_p"] = args.kp
    _check_policies(args, overrides, gains)
    return overrides, gains


def _check_policies(args: argparse.Namespace, overrides, gains) -> None:
    """Build every controller once per vehicle model here, so that a missing model file or a
    model trained for another observation (e.g. a 2-D one) is named before any run."""
    for name in criteria_policies(args):
        if name not in args.policies:
            raise ValueError(
                f"--criteria-for {name!r} is invalid: not among --policies "
                f"({', '.join(args.policies)})"
            )
    for pol in (p for p in args.policies if ":" in p):
        for dyn in args.dynamics:
            try:
                make_pair_policy(pol, make_config(args.preset, dynamics=dyn, **overrides))
            except (TypeError, ValueError, FileNotFoundError) as exc:
                raise ValueError(f"--policies {pol!r} is invalid for {dyn}: {exc}") from None
    flags = {"k": "--smc-k", "c": "--smc-c", "boundary_layer": "--smc-boundary-layer"}
    for pol, given in gains.items():  # a bad gain exits here, naming its flag
        if not given or pol not in args.policies:
            continue
        try:
            make_pair_policy(
                pol, make_config(args.preset, dynamics=args.dynamics[0], **overrides), **given
            )
        except (TypeError, ValueError) as exc:
            names = ", ".join(flags.get(g, "--kp") for g in given)
            raise ValueError(f"{names}: {exc}") from None


def criteria_policies(args: argparse.Namespace) -> list[str]:
    """The controllers the criteria are checked for: ``--criteria-for``, else smc and every
    learned (``sb3:``) policy among ``--policies``."""
    if args.criteria_for is not None:
        return list(dict.fromkeys(args.criteria_for))
    return [p for p in args.policies if p == "smc" or p.startswith("sb3:")]


def _recordings(record: RecordOptions | None, args, gains) -> dict[tuple[str, str], Any]:
    """The recording options of every (vehicle model, policy) run (None without --record);
    ``ValueError`` when two runs would share a folder."""
    combos = [(d, p) for d in args.dynamics for p in args.policies]
    if record is None:
        return dict.fromkeys(combos)
    runs = {
        (d, p): record.run(run_name(d, p), p, dynamics=d, policy=p, gains=gains.get(p, {}))
        for d, p in combos
    }
    check_run_names(runs.values())
    return runs


def _run(args, seeds, overrides, gains, recordings) -> dict[tuple[str, str], dict[str, Any]]:
    combos = [(d, p) for d in args.dynamics for p in args.policies]
    combos.sort(key=lambda c: c[0] != "quadrotor")  # the slower model first
    record = not args.no_figures
    tasks = [
        (d, p, seeds, overrides, gains, record and p != "zero", recordings[d, p]) for d, p in combos
    ]
    results: dict[tuple[str, str], dict[str, Any]] = {}
    with tqdm(
        total=len(combos), unit="job", desc="quadrotor experiment", disable=args.quiet
    ) as bar:
        job = functools.partial(run_job, preset=args.preset)
        for i, res in imap_unordered(job, tasks, args.workers):
            results[combos[i]] = res
            bar.update()
    return results


def _summary(rows, results, keys, seeds, overrides, gains, checks, checked) -> str:
    cfg = results[keys[0]]["config"]
    c = criteria_for(cfg.preset)
    intro = (
        f"Preset `{cfg.preset}` (docs/quadrotor.md), {len(seeds)} seeds ({seeds[0]}-{seeds[-1]}) "
        f"per row, {cfg.episode_steps * cfg.dt:g} s, protocol every {cfg.dt:g} s, physics "
        f"every {cfg.physics_dt:g} s; median [min-max] over seeds. Band {c.band:g} m; "
        f"straight flight = {windows_text(c.straight_windows)} s; turns = "
        f"{windows_text(c.turn_windows)} s; velocity mismatch over "
        f"{windows_text(c.velocity_windows)} s. The particle model flies the same scenario, "
        f"seeds and gains without the {c.vehicle}'s limits."
    )
    md = ["# Sec. VI-B: 10 quadrotors, pairwise control", "", intro, "", summarize(rows), ""]
    if overrides or any(gains.values()):
        md += [f"Overrides: `{overrides}`; gains: `{gains}`.", ""]
    if checks:
        who = "sliding mode" if checked == ["smc"] else ", ".join(f"`{p}`" for p in checked)
        md += [f"## Criteria ({who} on the {c.vehicle}, every seed)", ""]
        md += criteria_table(checks)
    return "\n".join(md) + "\n"


def _run_json(args, seeds, overrides, gains, results, sim_wall, total) -> dict[str, Any]:
    return run_record(
        preset=args.preset,
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
    )


def main(argv: Sequence[str] | None = None) -> int:
    """The experiment CLI (``python -m baselines.quadrotor_experiment``); the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    with user_errors(parser):
        overrides, gains = _settings(args)
        recordings = _recordings(record_options(args, args.out, seeds), args, gains)
    t0 = time.perf_counter()
    results = _run(args, seeds, overrides, gains, recordings)
    sim_wall = time.perf_counter() - t0
    keys = sorted(results, key=_order)
    rows = [r for k in keys for r in results[k]["rows"]]
    out = args.out
    checked = criteria_policies(args)
    crit = criteria_for(args.preset)
    checks = check_quadrotor(rows, crit, policies=checked)
    with result_folder(out) as folder:  # complete and consistent, or marked INCOMPLETE
        write_csv(folder / "results.csv", rows, list(rows[0]))
        md = _summary(rows, results, keys, seeds, overrides, gains, checks, checked)
        atomic_write_text(folder / "summary.md", md)
        fig_paths = []
        if not args.no_figures:
            fig_paths = figure_set(results, folder, args.dpi, crit.straight_windows, crit.band)
        total = time.perf_counter() - t0
        record = _run_json(args, seeds, overrides, gains, results, sim_wall, total)
        names = ["results.csv", "summary.md", *(str(f.relative_to(folder)) for f in fig_paths)]
        recorded = written(recordings.values(), seeds, out)
        write_json(
            folder / "run.json", {**record, "outputs": sorted(names), "recordings": recorded}
        )
    print(summarize(rows))
    if checks:
        print("\n" + "\n".join(criteria_lines(checks)))
    print(
        f"\nwrote {out / 'results.csv'}, {out / 'summary.md'}, {len(fig_paths)} figures in "
        f"{total:.1f} s (simulation {sim_wall:.1f} s, {args.workers} workers)"
    )
    if recorded:
        print(report_line(recorded, out))
    return 1 if args.check and not all_passed(checks) else 0
