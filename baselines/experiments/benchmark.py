"""Benchmark pair controllers: policies x scenarios x seeds, with tables, figures and video.

    python -m baselines.benchmark --suite paper             # Sec. VI-A: N = 20/50/100, 10 seeds
    python -m baselines.benchmark --suite robustness        # noise, delay, disturbance
    python -m baselines.benchmark -p smc smc:k=100 proportional:k_p=4 --n-uavs 50 --seeds 5
    python -m baselines.benchmark -p smc sb3:runs/ppo/model.zip --suite robustness
    python -m baselines.benchmark --suite paper --backend ray --ray-address auto
    python -m baselines.benchmark --suite quick --video     # + an mp4 of one episode

A suite supplies defaults (preset, policies, scenarios, seeds); every option overrides them.
Scenarios are the preset plus overrides: the grid product of the sweep options (``--n-uavs 20
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

from __future__ import annotations

import argparse
import dataclasses
import datetime as _dt
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from baselines.evaluation.jobs import BACKENDS
from baselines.evaluation.parallel import pin_threads

__all__ = ["SUITES", "Suite", "build_parser", "main"]


@dataclasses.dataclass(frozen=True)
class Suite:
    """Defaults of a named benchmark (every field can be overridden on the command line)."""

    description: str
    preset: str
    policies: tuple[str, ...]
    seeds: int
    base: tuple[tuple[str, Any], ...] = ()
    grid: tuple[tuple[str, tuple[Any, ...]], ...] = ()
    scenarios: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...] = ()
    check: bool = False
    snapshots: bool = True


SUITES: dict[str, Suite] = {
    "paper": Suite(
        "Sec. VI-A: sliding mode vs the normal method vs no pair term, N = 20/50/100, "
        "10 seeds, with the acceptance checks",
        preset="paper",
        policies=("smc", "proportional", "zero"),
        seeds=10,
        grid=(("n_uavs", (20, 50, 100)),),
        check=True,
    ),
    "robustness": Suite(
        "what the proofs assume away, N = 50, 10 seeds: sensor noise on y and y', partner "
        "delay, random acceleration disturbance",
        preset="paper",
        policies=("smc", "proportional"),
        seeds=10,
        base=(("n_uavs", 50),),
        scenarios=(
            ("nominal", ()),
            ("noise y 0.3 m", (("obs_noise_position", 0.3),)),
            ("noise y 1 m", (("obs_noise_position", 1.0),)),
            ("noise y 3 m", (("obs_noise_position", 3.0),)),
            ("noise y' 1 m/s", (("obs_noise_velocity", 1.0),)),
            ("noise y' 3 m/s", (("obs_noise_velocity", 3.0),)),
            ("noise y' 10 m/s", (("obs_noise_velocity", 10.0),)),
            ("delay 3 steps", (("partner_delay", 3),)),
            ("delay 10 steps", (("partner_delay", 10),)),
            ("delay 30 steps", (("partner_delay", 30),)),
            ("disturbance 3 m/s^2", (("disturbance_std", 3.0),)),
            ("disturbance 30 m/s^2", (("disturbance_std", 30.0),)),
            ("disturbance 100 m/s^2", (("disturbance_std", 100.0),)),
        ),
        snapshots=False,
    ),
    "quick": Suite(
        "a sanity run in seconds: N = 20, 15 s, 3 seeds, smc vs proportional",
        preset="paper",
        policies=("smc", "proportional"),
        seeds=3,
        base=(("n_uavs", 20), ("horizon", 15.0)),
    ),
    "quadrotor": Suite(
        "Sec. VI-B: 10 quadrotors (preset 'paper-quadrotor', issue 3), 5 seeds",
        preset="paper-quadrotor",
        policies=("smc", "proportional", "zero"),
        seeds=5,
    ),
}

#: sweep shortcuts: option -> (config field, type, help)
SHORTCUTS = (
    ("--n-uavs", "n_uavs", int, "swarm sizes N"),
    ("--dim", "dim", int, "spatial dimension (2 or 3)"),
    ("--d-m", "d_m", float, "desired pair distance d_m (m)"),
    (
        "--pairs",
        "pairs",
        int,
        "number of pairs K: UAVs (0, 1), (2, 3), ... (K > 2^(dim-1) needs --set init=random)",
    ),
    ("--dynamics", "dynamics", str, "vehicle model (see PairFlockConfig.dynamics)"),
    ("--dt", "dt", float, "control period (s)"),
    ("--horizon", "horizon", float, "episode length (s)"),
    ("--noise-position", "obs_noise_position", float, "std of the noise on the observed y (m)"),
    ("--noise-velocity", "obs_noise_velocity", float, "std of the noise on the observed y' (m/s)"),
    ("--delay", "partner_delay", int, "delay of the partner's state (control steps)"),
    (
        "--disturbance",
        "disturbance_std",
        float,
        "std of a random acceleration on every UAV (m/s^2)",
    ),
)


def _epilog() -> str:
    lines = ["suites:"]
    for name, s in SUITES.items():
        lines.append(f"  {name:<11} {s.description}")
    lines += [
        "",
        "policy specs: NAME or NAME:key=value,... (gains of baselines.make_pair_policy), e.g.",
        "  smc, smc:k=200,boundary_layer=0.5, proportional:k_p=2, zero, sb3:path/to/model.zip",
        "scenario specs (--scenario): [LABEL:]key=value,... over any PairFlockConfig field, e.g.",
        "  'delay 5:partner_delay=5'  or  obs_noise_position=0.5,obs_noise_velocity=0.5",
    ]
    return "\n".join(lines)


def build_parser(prog: str = "python -m baselines.benchmark") -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog=prog,
        description=(__doc__ or "").split("\n\n")[0],
        epilog=_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--suite", default="paper", choices=list(SUITES), help="named defaults (default: paper)"
    )
    p.add_argument("--preset", default=None, help="config preset (default: the suite's)")
    p.add_argument(
        "-p",
        "--policies",
        nargs="+",
        default=None,
        metavar="SPEC",
        help="policy specs (default: the suite's)",
    )
    sweep = p.add_argument_group("scenarios (each option with several values is a sweep axis)")
    for opt, field, typ, text in SHORTCUTS:
        sweep.add_argument(
            opt, nargs="+", type=typ, default=None, metavar="V", help=f"{text} [{field}]"
        )
    sweep.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=V1,V2",
        help="sweep any config field (repeatable)",
    )
    sweep.add_argument(
        "--scenario",
        action="append",
        default=None,
        metavar="[LABEL:]K=V,...",
        help="a named scenario (repeatable; replaces the suite's list)",
    )
    sd = p.add_argument_group("seeds and metrics")
    sd.add_argument("--seeds", type=int, default=None, help="seeds per (scenario, policy)")
    sd.add_argument(
        "--first-seed",
        type=int,
        default=0,
        help="seeds are first-seed, first-seed + 1, ... (default: 0)",
    )
    sd.add_argument(
        "--steady-window",
        type=float,
        default=None,
        help="steady state = the last this many seconds (default: metrics' 10 s)",
    )
    ex = p.add_argument_group("execution")
    ex.add_argument(
        "--backend",
        choices=BACKENDS,
        default="local",
        help="local processes or a Ray cluster (pip install 'pairflock-env[ray]')",
    )
    ex.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="local processes, or CPUs of a Ray instance started here (default: all cores)",
    )
    ex.add_argument(
        "--ray-address",
        default=None,
        help="Ray cluster to join, e.g. 'auto' (default: start a local one)",
    )
    ex.add_argument(
        "--batch-size",
        type=int,
        default=None,
        help="seeds per job (default: all seeds of a (scenario, policy) in one "
        "batched core); smaller spreads a sweep over more workers",
    )
    out = p.add_argument_group("output")
    out.add_argument(
        "--out", type=Path, default=None, help="output folder (default: results/benchmark/<suite>)"
    )
    out.add_argument("--no-figures", action="store_true", help="no PNGs and no traces.npz")
    out.add_argument("--no-snapshots", action="store_true", help="no swarm snapshot PNGs")
    out.add_argument(
        "--frame-dt",
        type=float,
        default=0.05,
        help="time between recorded frames for snapshots and video (s)",
    )
    out.add_argument(
        "--video",
        nargs="?",
        const="auto",
        default=None,
        metavar="PATH",
        help="write an episode video (.mp4 or .gif; default "
        "<out>/episode_<scenario>_<policy>_seed<k>.mp4)",
    )
    out.add_argument(
        "--video-policy",
        default=None,
        metavar="SPEC",
        help="policy of the video (default: the first)",
    )
    out.add_argument(
        "--video-scenario",
        default=None,
        metavar="LABEL",
        help="scenario of the video (default: the first)",
    )
    out.add_argument("--video-fps", type=int, default=25, help="video frames per second")
    out.add_argument(
        "--video-speed", type=float, default=5.0, help="simulated seconds per video second"
    )
    out.add_argument(
        "--check",
        action="store_true",
        help="paper preset: exit with status 1 if an acceptance check fails",
    )
    out.add_argument(
        "--replot",
        type=Path,
        default=None,
        metavar="DIR",
        help="only redraw the figures of a finished run in DIR",
    )
    out.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


# ---------------------------------------------------------------------------------------
def _grid(args: argparse.Namespace, suite: Suite, parser) -> dict[str, list[Any]]:
    from baselines.evaluation.specs import parse_value, split_top_level

    grid: dict[str, list[Any]] = {k: list(v) for k, v in suite.grid}
    given: dict[str, str] = {}
    for opt, field, _, _ in SHORTCUTS:
        vals = getattr(args, opt[2:].replace("-", "_"))
        if vals is None:
            continue
        if field == "pairs":
            for k in vals:
                if k < 1:
                    parser.error(f"--pairs {k} is invalid: must be >= 1")
            vals = [tuple((2 * i, 2 * i + 1) for i in range(k)) for k in vals]
        grid[field] = list(vals)
        given[field] = opt
    for item in args.set:
        key, eq, rhs = item.partition("=")
        key = key.strip()
        if not eq or not key or not rhs.strip():
            parser.error(f"--set {item!r} is invalid: expected KEY=V1[,V2,...]")
        if key in given:
            parser.error(f"--set {item!r}: {key} is already set by {given[key]}")
        grid[key] = [parse_value(v) for v in split_top_level(rhs)]
        given[key] = "--set"
    if "pairs" in grid:
        grid["pairs"] = [
            tuple(tuple(p) for p in v) if isinstance(v, list) else v for v in grid["pairs"]
        ]
    return grid


def _resolve(args: argparse.Namespace, parser):
    """Suite defaults + options -> (suite, preset, specs, scenarios, configs, seeds)."""
    from baselines.evaluation.specs import (
        SHORT_NAMES,
        expand_scenarios,
        parse_policy,
        parse_scenario,
    )
    from baselines.reporting import tables as report
    from pairflock_env import make_config, preset_names

    suite = SUITES[args.suite]
    preset = args.preset or suite.preset
    if preset not in preset_names():
        extra = ""
        if args.preset is None:
            extra = f" (suite {args.suite!r} needs it; it is not available in this install)"
        parser.error(
            f"--preset {preset!r} is invalid{extra}: valid presets are {', '.join(preset_names())}"
        )
    try:
        specs = [parse_policy(s) for s in (args.policies or suite.policies)]
    except ValueError as e:
        parser.error(f"--policies: {e}")
    labels = [s.label for s in specs]
    if len(set(labels)) != len(labels):
        parser.error(f"--policies {labels} names a policy twice")
    n_seeds = suite.seeds if args.seeds is None else args.seeds
    if n_seeds < 1:
        parser.error(f"--seeds {n_seeds} is invalid: must be >= 1")
    if args.first_seed < 0:
        parser.error(f"--first-seed {args.first_seed} is invalid: must be >= 0")
    seeds = list(range(args.first_seed, args.first_seed + n_seeds))
    grid = _grid(args, suite, parser)
    try:
        listed = (
            [parse_scenario(s) for s in args.scenario]
            if args.scenario is not None
            else [(lab, dict(ov)) for lab, ov in suite.scenarios]
        )
        scenarios = expand_scenarios(dict(suite.base), listed, grid)
    except ValueError as e:
        parser.error(str(e))
    configs = []
    for sc in scenarios:
        try:
            configs.append(make_config(preset, **sc.override_dict))
        except (ValueError, TypeError) as e:
            parser.error(f"scenario {sc.label!r}: {e}")
    reprs = {}
    for spec in specs:  # build every policy once per scenario: bad gains fail here, not later
        for sc, cfg in zip(scenarios, configs, strict=False):
            try:
                reprs[spec.label] = repr(spec.build(cfg))
            except (ValueError, TypeError, KeyError, FileNotFoundError) as e:
                parser.error(f"policy {spec.label!r} on scenario {sc.label!r}: {e}")
    # the tables lead with the sweep axes when the scenarios are a plain grid ("| N | ...")
    # (the suite's own axes, and any other axis with several values)
    axes = [k for k, v in grid.items() if k in dict(suite.grid) or len(v) > 1]
    keys = (
        tuple((SHORT_NAMES.get(k, k), "n_pairs" if k == "pairs" else k) for k in axes)
        if axes and not listed
        else report.SCENARIO_KEYS
    )
    return suite, preset, specs, scenarios, configs, seeds, reprs, keys


def _columns(scenarios, configs) -> list[str]:
    fixed = ["scenario", "preset", "dynamics", "dim", "n_uavs", "n_pairs"]
    extra = []
    for sc in scenarios:
        for k, _ in sc.overrides:
            if k not in fixed and k not in extra:
                extra.append(k)
    return fixed + extra


def _cell(v: Any) -> Any:
    if isinstance(v, (list, tuple)):
        import json

        return json.dumps(v, separators=(",", ":"))
    return v


def _video_target(args, specs, scenarios, parser) -> tuple[int, int] | None:
    if args.video is None:
        return None
    labels = [s.label for s in specs]
    j = 0
    if args.video_policy is not None:
        if args.video_policy not in labels:
            parser.error(
                f"--video-policy {args.video_policy!r} is invalid: must be one of "
                f"the policies {labels}"
            )
        j = labels.index(args.video_policy)
    slabels = [s.label for s in scenarios]
    i = 0
    if args.video_scenario is not None:
        if args.video_scenario not in slabels:
            parser.error(
                f"--video-scenario {args.video_scenario!r} is invalid: must be one of {slabels}"
            )
        i = slabels.index(args.video_scenario)
    if args.video != "auto" and Path(args.video).suffix.lower() not in (".mp4", ".gif"):
        parser.error(f"--video {args.video!r} is invalid: the file must end in .mp4 or .gif")
    if args.video_fps < 1 or not args.video_speed > 0:
        parser.error("--video-fps must be >= 1 and --video-speed > 0")
    return i, j


def _replot(args, parser) -> int:
    import json

    from baselines.reporting.tables import load_traces, make_figures

    d = args.replot
    try:
        res = json.loads((d / "results.json").read_text())
    except FileNotFoundError:
        parser.error(f"--replot {str(d)!r} is invalid: no results.json there")
    rows = [{k: (float("nan") if v is None else v) for k, v in r.items()} for r in res["runs"]]
    traces = load_traces(d / "traces.npz") if (d / "traces.npz").exists() else {}
    snapshots = bool(res["snapshots"]) and not args.no_snapshots
    paths = make_figures(
        d,
        rows,
        traces,
        res["scenarios"],
        [p["label"] for p in res["policies"]],
        snapshots=snapshots,
    )
    print(f"wrote {len(paths)} figures in {d}")
    return 0


def main(argv: Sequence[str] | None = None, prog: str = "python -m baselines.benchmark") -> int:
    parser = build_parser(prog)
    args = parser.parse_args(argv)
    pin_threads()
    if args.replot is not None:
        return _replot(args, parser)
    if args.workers < 1:
        parser.error(f"--workers {args.workers} is invalid: must be >= 1")
    if args.batch_size is not None and args.batch_size < 1:
        parser.error(f"--batch-size {args.batch_size} is invalid: must be >= 1")
    if not args.frame_dt > 0:
        parser.error(f"--frame-dt {args.frame_dt} is invalid: must be > 0")
    if args.steady_window is not None and not args.steady_window > 0:
        parser.error(f"--steady-window {args.steady_window} is invalid: must be > 0")
    if args.backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            parser.error("--backend ray needs Ray: pip install 'pairflock-env[ray]'")

    suite, preset, specs, scenarios, configs, seeds, reprs, keys = _resolve(args, parser)
    if args.check and preset != "paper":
        parser.error(
            f"--check verifies the paper's claims: it needs --preset paper, not {preset!r}"
        )
    video = _video_target(args, specs, scenarios, parser)
    out = args.out or Path("results") / "benchmark" / args.suite

    from tqdm import tqdm

    from baselines.evaluation.io import atomic_write_text, run_record, write_csv, write_json
    from baselines.evaluation.jobs import make_jobs, run_jobs
    from baselines.reporting import tables as report
    from pairflock_env.metrics import METRIC_DOCS

    figures = not args.no_figures
    snapshots = suite.snapshots and not args.no_snapshots
    metric_kwargs = {} if args.steady_window is None else {"steady_window": args.steady_window}
    jobs = make_jobs(
        configs,
        specs,
        seeds,
        batch_size=args.batch_size,
        record=lambda i, j: figures or video == (i, j),
        record_stride=lambda cfg: max(1, round(args.frame_dt / cfg.dt)),
        metric_kwargs=metric_kwargs,
    )
    started = _now()
    t0 = time.perf_counter()
    results: dict[tuple[int, int], list[dict[str, Any]]] = {}
    traces: dict[tuple[int, int], dict[str, Any]] = {}
    total = len(seeds) * len(specs) * len(scenarios)
    cpu_s = 0.0  # summed over jobs: a load-independent measure of the work
    with tqdm(
        total=total,
        unit="run",
        desc=f"benchmark {args.suite}",
        disable=args.quiet,
        dynamic_ncols=True,
    ) as bar:
        for job, res in run_jobs(
            jobs, backend=args.backend, workers=args.workers, ray_address=args.ray_address
        ):
            results.setdefault((job.scenario, job.policy), []).extend(res["rows"])
            if "trace" in res:
                traces[job.scenario, job.policy] = res["trace"]
            cpu_s += res["cpu_s"]
            bar.update(len(job.seeds))
    sim_wall = time.perf_counter() - t0

    # rows in a fixed order: scenario, policy (as given), seed, pair
    columns = _columns(scenarios, configs)
    rows = []
    for i, (sc, cfg) in enumerate(zip(scenarios, configs, strict=False)):
        d = {**cfg.to_dict(), "n_pairs": cfg.n_pairs}
        lead = {"scenario": sc.label, "preset": preset}
        lead.update({k: _cell(d[k]) for k in columns[2:]})
        for j, spec in enumerate(specs):
            for m in sorted(results[i, j], key=lambda r: (r["seed"], r["pair"])):
                rows.append({**lead, "policy": spec.label, **m})
    metric_cols = [k for k in rows[0] if k not in columns and k != "policy"]
    write_csv(out / "results.csv", rows, [*columns, "policy", *metric_cols])
    sc_records = [
        {"label": sc.label, "overrides": dict(sc.overrides), "config": cfg.to_dict()}
        for sc, cfg in zip(scenarios, configs, strict=False)
    ]
    pol_records = [
        {"label": s.label, "name": s.name, "gains": dict(s.gains), "resolved": reprs[s.label]}
        for s in specs
    ]
    atomic_write_text(
        out / "results.json",
        report.dumps_stable(
            {
                "suite": args.suite,
                "preset": preset,
                "seeds": seeds,
                "scenarios": sc_records,
                "policies": pol_records,
                "metrics": {k: list(v) for k, v in METRIC_DOCS.items()},
                "snapshots": snapshots,
                "runs": report.json_rows(rows),
            }
        ),
    )

    checks = []
    if (suite.check or args.check) and preset == "paper":
        checks = report.check_paper_claims(rows)
    fig_paths: list[Path] = []
    if figures:
        report.save_traces(out / "traces.npz", traces)
        fig_paths = report.make_figures(
            out,
            rows,
            traces,
            sc_records,
            [s.label for s in specs],
            snapshots=snapshots,
        )
    video_path = None
    if video is not None:
        from baselines.evaluation.specs import slug
        from baselines.reporting.video import write_episode_video

        i, j = video
        tr = traces[i, j]
        cfg = configs[i]
        name = f"episode_{slug(scenarios[i].label)}_{slug(specs[j].label)}_seed{tr['seed']}.mp4"
        video_path = out / name if args.video == "auto" else Path(args.video)
        write_episode_video(
            video_path,
            tr["frame_t"],
            tr["positions"],
            tr["velocities"],
            tr["leader_positions"],
            cfg.pairs,
            cfg.d_m,
            fps=args.video_fps,
            speed=args.video_speed,
            pair_error=tr["pair_error"][0],
            error_t=tr["t"],
            title=f"{cfg.n_uavs} UAVs, {specs[j].label}, {scenarios[i].label}",
        )

    md = _summary_markdown(
        args.suite,
        preset,
        specs,
        scenarios,
        configs,
        seeds,
        rows,
        checks,
        fig_paths,
        out,
        metric_kwargs,
        keys,
    )
    atomic_write_text(out / "summary.md", md)
    total_s = time.perf_counter() - t0
    write_json(
        out / "run.json",
        run_record(
            suite=args.suite,
            preset=preset,
            seeds=seeds,
            policies=pol_records,
            scenarios=sc_records,
            backend=args.backend,
            workers=args.workers,
            batch_size=args.batch_size,
            ray_address=args.ray_address,
            metric_options=metric_kwargs,
            outputs=sorted(
                str(p.relative_to(out))
                for p in [
                    out / "results.csv",
                    out / "results.json",
                    out / "summary.md",
                    *fig_paths,
                    *([video_path] if video_path else []),
                ]
                if Path(p).is_relative_to(out)
            ),
            timestamps={
                "started_utc": started.isoformat(timespec="seconds"),
                "finished_utc": _now().isoformat(timespec="seconds"),
            },
            timing={
                "simulation_s": round(sim_wall, 2),
                "total_s": round(total_s, 2),
                "jobs_cpu_s": round(cpu_s, 2),
                "jobs": len(jobs),
                "runs": total,
            },
        ),
    )

    print(report.summary_table(rows, report.ACCURACY_METRICS, keys))
    for c, ok, d in checks:
        print(f"[{'pass' if ok else 'FAIL'}] {c}: {d}")
    print(
        f"\nwrote {out}/results.csv, results.json, summary.md, run.json, "
        f"{len(fig_paths)} figures{', ' + str(video_path) if video_path else ''} in "
        f"{total_s:.1f} s (simulation {sim_wall:.1f} s wall, {cpu_s:.1f} s CPU in jobs; "
        f"backend {args.backend}, {args.workers} workers)"
    )
    if args.check and not all(ok for _, ok, _ in checks):
        return 1
    return 0


def _now() -> _dt.datetime:
    return _dt.datetime.now(_dt.timezone.utc)


def _md_escape(text: str) -> str:
    """Text for a markdown table cell (a bare '|' would end the cell)."""
    return text.replace("|", "\\|")


def _summary_markdown(
    suite,
    preset,
    specs,
    scenarios,
    configs,
    seeds,
    rows,
    checks,
    fig_paths,
    out,
    metric_kwargs,
    keys,
) -> str:
    from baselines.reporting import tables as report
    from pairflock_env.metrics import METRIC_DOCS

    horizons = sorted({c.episode_steps * c.dt for c in configs})
    window = metric_kwargs.get("steady_window")
    md = [
        f"# Benchmark `{suite}`",
        "",
        f"Preset `{preset}`; policies {', '.join(f'`{s.label}`' for s in specs)}; "
        f"{len(seeds)} seeds ({seeds[0]}-{seeds[-1]}) per scenario and policy, the same seeds "
        f"and initial states for every policy; horizon {', '.join(f'{h:g}' for h in horizons)} s"
        + (f"; steady state = last {window:g} s" if window else "")
        + ". "
        'Cells: median [min-max] over runs; "never in k/n": k runs never got there.',
        "",
        "## Scenarios",
        "",
        "| scenario | overrides of the preset |",
        "|---|---|",
    ]
    for sc in scenarios:
        ov = ", ".join(f"`{k}={v}`" for k, v in sc.overrides) or "none"
        md.append(f"| {sc.label} | {ov} |")
    steps = {sc.label: cfg.episode_steps for sc, cfg in zip(scenarios, configs, strict=False)}
    ended = [r for r in rows if r["steps_run"] < steps[r["scenario"]]]
    md += [
        "",
        "## Convergence and accuracy",
        "",
        report.summary_table(rows, report.ACCURACY_METRICS, keys),
        "",
        "## Cost and safety",
        "",
        report.summary_table(rows, report.COST_METRICS, keys),
        "",
        "## By scenario and policy",
        "",
    ]
    table_fmt = {m: (h, f) for m, h, f in report.ACCURACY_METRICS + report.COST_METRICS}
    for metric in report.PIVOT_METRICS:
        head, fmt = table_fmt[metric]
        md += [f"{head}:", "", report.pivot_table(rows, metric, fmt, keys), ""]
    if ended:
        md += [
            f"{len(ended)} runs ended early (divergence or collision termination); their "
            "series are frozen at the last state (column `steps_run`).",
            "",
        ]
    if checks:
        md += [
            "## Acceptance criteria (paper)",
            "",
            "| criterion | result | measured |",
            "|---|---|---|",
        ]
        md += [f"| {c} | {'pass' if ok else 'FAIL'} | {d} |" for c, ok, d in checks]
        md.append("")
    md += ["## Metrics", "", "| column | unit | meaning |", "|---|---|---|"]
    md += [f"| `{k}` | {u} | {_md_escape(m)} |" for k, (u, m) in METRIC_DOCS.items()]
    if fig_paths:
        md += ["", "## Figures", ""]
        md += [f"- `{p.relative_to(out)}`" for p in fig_paths]
    return "\n".join(md) + "\n"


if __name__ == "__main__":
    sys.exit(main())
