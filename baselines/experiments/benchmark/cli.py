"""The benchmark's command line: the parser, and its options resolved into a :class:`Plan`.

Every check of the options happens here, before anything runs: a bad option, scenario or
gain ends the command with one line naming it and exit status 2
(:mod:`baselines.runtime.cli`).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path
from typing import Any

from baselines.evaluation.jobs import BACKENDS
from baselines.evaluation.recording import (
    RecordOptions,
    add_record_options,
    check_run_names,
    record_options,
    run_name,
)
from baselines.evaluation.specs import (
    SHORT_NAMES,
    expand_scenarios,
    parse_policy,
    parse_scenario,
    parse_value,
    split_top_level,
)
from baselines.experiments.benchmark.suites import SHORTCUTS, SUITES, Suite
from baselines.reporting.tables import SCENARIO_KEYS
from baselines.runtime import optional
from baselines.runtime.cli import ArgumentParser, user_errors
from pairflock_env import make_config, preset_names

__all__ = ["PROG", "Plan", "build_parser", "resolve"]

PROG = "python -m baselines.benchmark"
DESCRIPTION = (
    "Benchmark pair controllers: policies x scenarios x seeds, with tables, figures and video."
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
        "values: numbers as written (1e-3, 5e1, 20), true/false, none, JSON/Python lists, or text",
    ]
    return "\n".join(lines)


def _scenario_options(p: argparse.ArgumentParser) -> None:
    grid = p.add_argument_group("scenarios (each option with several values is a grid axis)")
    for opt, field, typ, text in SHORTCUTS:
        grid.add_argument(
            opt, nargs="+", type=typ, default=None, metavar="V", help=f"{text} [{field}]"
        )
    grid.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=V1,V2",
        help="vary any config field (repeatable)",
    )
    grid.add_argument(
        "--scenario",
        action="append",
        default=None,
        metavar="[LABEL:]K=V,...",
        help="a named scenario (repeatable; replaces the suite's list)",
    )


def _seed_and_execution_options(p: argparse.ArgumentParser) -> None:
    sd = p.add_argument_group("seeds and metrics")
    sd.add_argument("--seeds", type=int, default=None, help="seeds per (scenario, policy)")
    sd.add_argument(
        "--first-seed",
        type=int,
        default=None,
        help="seeds are first-seed, first-seed + 1, ... (default: the suite's, mostly 0)",
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
        "batched core); smaller spreads a grid over more workers",
    )


def _output_options(out: argparse._ArgumentGroup) -> None:
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
        "--video-policy", metavar="SPEC", help="policy of the video (default: the first)"
    )
    out.add_argument(
        "--video-scenario", metavar="LABEL", help="scenario of the video (default: the first)"
    )
    out.add_argument("--video-fps", type=int, default=25, help="video frames per second")
    out.add_argument(
        "--video-speed", type=float, default=5.0, help="simulated seconds per video second"
    )
    out.add_argument(
        "--check",
        action="store_true",
        help="paper preset: exit with status 1 if an acceptance check fails (or none applies)",
    )
    out.add_argument(
        "--replot",
        type=Path,
        default=None,
        metavar="DIR",
        help="only redraw the figures of a finished run in DIR",
    )
    out.add_argument("--quiet", action="store_true", help="no progress bar")


def build_parser(prog: str = PROG) -> argparse.ArgumentParser:
    """The benchmark's argument parser (``--help`` lists suites and spec syntax)."""
    p = ArgumentParser(
        prog=prog,
        description=DESCRIPTION,
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
    _scenario_options(p)
    _seed_and_execution_options(p)
    _output_options(p.add_argument_group("output"))
    add_record_options(p)
    return p


# --------------------------------------------------------------------------- resolution
@dataclasses.dataclass
class Plan:
    """What a benchmark command runs: the suite's defaults with every option applied."""

    suite_name: str
    suite: Suite
    preset: str
    specs: list  # PolicySpec
    scenarios: list  # Scenario
    configs: list  # PairFlockConfig, one per scenario
    seeds: list[int]
    reprs: dict[str, str]  # policy label -> repr of the built policy (resolved gains)
    keys: tuple[tuple[str, str], ...]  # leading columns of the tables
    video: tuple[int, int] | None  # (scenario, policy) of the video
    out: Path
    metric_kwargs: dict[str, Any]
    figures: bool
    snapshots: bool
    record: RecordOptions | None = None  # --record

    def recording(self, i: int, j: int) -> RecordOptions | None:
        """The recording options of scenario i x policy j (None without --record)."""
        if self.record is None:
            return None
        sc, spec = self.scenarios[i], self.specs[j]
        name = run_name(sc.label, spec.label)
        return self.record.run(name, spec.label, scenario=sc.label, policy=spec.label)

    def recorded_runs(self) -> list[RecordOptions]:
        """The recording options of every recorded run (none without --record)."""
        runs = (
            self.recording(i, j) for i in range(len(self.scenarios)) for j in range(len(self.specs))
        )
        return [r for r in runs if r is not None]


def _check_numbers(args: argparse.Namespace, parser: argparse.ArgumentParser) -> None:
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
            optional.load("ray", "--backend ray")
        except ModuleNotFoundError as e:
            parser.error(str(e))


def _grid(args: argparse.Namespace, suite: Suite, parser) -> dict[str, list[Any]]:
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


def _policies_and_seeds(args, suite: Suite, parser):
    try:
        specs = [parse_policy(s) for s in (args.policies or suite.policies)]
    except (ValueError, TypeError) as e:
        parser.error(f"--policies: {e}")
    labels = [s.label for s in specs]
    if len(set(labels)) != len(labels):
        parser.error(f"--policies {labels} names a policy twice")
    n_seeds = suite.seeds if args.seeds is None else args.seeds
    if n_seeds < 1:
        parser.error(f"--seeds {n_seeds} is invalid: must be >= 1")
    first = suite.first_seed if args.first_seed is None else args.first_seed
    if first < 0:
        parser.error(f"--first-seed {first} is invalid: must be >= 0")
    return specs, list(range(first, first + n_seeds))


def _scenarios(args, suite: Suite, preset: str, grid, parser):
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
    return listed, scenarios, configs


def _built_policies(specs, scenarios, configs, parser) -> dict[str, str]:
    """Build every policy once per scenario, so that bad gains fail here, not in a worker."""
    reprs = {}
    for spec in specs:
        for sc, cfg in zip(scenarios, configs, strict=True):
            try:
                reprs[spec.label] = repr(spec.build(cfg))
            except (ValueError, TypeError, KeyError, FileNotFoundError) as e:
                parser.error(f"policy {spec.label!r} on scenario {sc.label!r}: {e}")
    return reprs


def _table_keys(grid, suite: Suite, listed) -> tuple[tuple[str, str], ...]:
    """The tables lead with the grid axes when the scenarios are a plain grid ("| N | ..."):
    the suite's own axes, and any other axis with several values."""
    axes = [k for k, v in grid.items() if k in dict(suite.grid) or len(v) > 1]
    if not axes or listed:
        return tuple(SCENARIO_KEYS)
    return tuple((SHORT_NAMES.get(k, k), "n_pairs" if k == "pairs" else k) for k in axes)


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


def _metric_kwargs(args: argparse.Namespace, configs) -> dict[str, Any]:
    """Options of the episode metrics: the steady window, and the safety columns in every
    run as soon as one scenario has the safety filter on (so that off and on compare), the
    whole swarm's columns as soon as one has ``safety_scope="swarm"``."""
    kw: dict[str, Any] = {}
    if args.steady_window is not None:
        kw["steady_window"] = args.steady_window
    if any(c.safety_filter != "none" for c in configs):
        kw["safety_metrics"] = True
    if any(c.safety_scope == "swarm" for c in configs):
        kw["swarm_metrics"] = True
    return kw


def resolve(args: argparse.Namespace, parser: argparse.ArgumentParser) -> Plan:
    """Suite defaults + options -> :class:`Plan`; any bad option ends in ``parser.error``."""
    _check_numbers(args, parser)
    suite = SUITES[args.suite]
    preset = args.preset or suite.preset
    if preset not in preset_names():
        extra = ""
        if args.preset is None:
            extra = f" (suite {args.suite!r} needs it; it is not available in this install)"
        parser.error(
            f"--preset {preset!r} is invalid{extra}: valid presets are {', '.join(preset_names())}"
        )
    specs, seeds = _policies_and_seeds(args, suite, parser)
    grid = _grid(args, suite, parser)
    listed, scenarios, configs = _scenarios(args, suite, preset, grid, parser)
    reprs = _built_policies(specs, scenarios, configs, parser)
    if args.check and preset != "paper":
        parser.error(
            f"--check verifies the paper's claims: it needs --preset paper, not {preset!r}"
        )
    out = args.out or Path("results") / "benchmark" / args.suite
    with user_errors(parser):
        record = record_options(args, out, seeds)
    plan = Plan(
        suite_name=args.suite,
        suite=suite,
        preset=preset,
        specs=specs,
        scenarios=scenarios,
        configs=configs,
        seeds=seeds,
        reprs=reprs,
        keys=_table_keys(grid, suite, listed),
        video=_video_target(args, specs, scenarios, parser),
        out=out,
        metric_kwargs=_metric_kwargs(args, configs),
        figures=not args.no_figures,
        snapshots=suite.snapshots and not args.no_snapshots,
        record=record,
    )
    with user_errors(parser):  # two runs whose recordings would share a folder
        check_run_names(plan.recorded_runs())
    return plan
