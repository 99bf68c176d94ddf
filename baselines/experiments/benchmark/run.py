"""Run a benchmark :class:`~baselines.experiments.benchmark.cli.Plan` and write its files."""

from __future__ import annotations

import dataclasses
import datetime as _dt
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from baselines.evaluation.jobs import make_jobs, run_jobs
from baselines.evaluation.recording import report_line, written
from baselines.evaluation.specs import slug
from baselines.experiments.benchmark.cli import PROG, Plan, build_parser, resolve
from baselines.experiments.benchmark.figures import load_traces, make_figures, save_traces
from baselines.experiments.benchmark.summary import summary_markdown
from baselines.reporting.criteria import all_passed, check_paper_claims, criteria_lines
from baselines.reporting.tables import (
    ACCURACY_METRICS,
    has_safety_columns,
    has_swarm_columns,
    safety_table,
    summary_table,
    swarm_table,
)
from baselines.reporting.video import write_episode_video
from baselines.runtime.files import (
    atomic_write_text,
    dumps_stable,
    json_rows,
    write_csv,
    write_json,
)
from baselines.runtime.folders import INCOMPLETE_MARKER, result_folder
from baselines.runtime.record import run_record
from pairflock_env.task.metrics import (
    FLOCK_METRIC_DOCS,
    METRIC_DOCS,
    SAFETY_METRIC_DOCS,
    SWARM_SAFETY_METRIC_DOCS,
)

__all__ = ["Results", "main", "replot", "simulate"]


@dataclasses.dataclass
class Results:
    """What the jobs of a plan returned, in a fixed order."""

    rows: list[dict[str, Any]]  # scenario, policy (as given), seed, pair
    columns: list[str]  # of results.csv
    traces: dict[tuple[int, int], dict[str, Any]]  # (scenario, policy) -> recorded run
    started: _dt.datetime
    sim_wall: float
    cpu_s: float  # summed over jobs: a load-independent measure of the work
    jobs: int
    runs: int


def _now() -> _dt.datetime:
    return _dt.datetime.now(_dt.timezone.utc)


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
        return json.dumps(v, separators=(",", ":"))
    return v


def _ordered_rows(plan: Plan, results, columns: list[str]) -> list[dict[str, Any]]:
    rows = []
    for i, (sc, cfg) in enumerate(zip(plan.scenarios, plan.configs, strict=True)):
        d = {**cfg.to_dict(), "n_pairs": cfg.n_pairs}
        lead = {"scenario": sc.label, "preset": plan.preset}
        lead.update({k: _cell(d[k]) for k in columns[2:]})
        for j, spec in enumerate(plan.specs):
            for m in sorted(results[i, j], key=lambda r: (r["seed"], r["pair"])):
                rows.append({**lead, "policy": spec.label, **m})
    return rows


def simulate(plan: Plan, args) -> Results:
    """Run every (scenario, policy, seed block) job on the chosen backend."""
    jobs = make_jobs(
        plan.configs,
        plan.specs,
        plan.seeds,
        batch_size=args.batch_size,
        record=lambda i, j: plan.figures or plan.video == (i, j),
        record_stride=lambda cfg: max(1, round(args.frame_dt / cfg.dt)),
        metric_kwargs=plan.metric_kwargs,
        recording=plan.recording,
    )
    started, t0 = _now(), time.perf_counter()
    results: dict[tuple[int, int], list[dict[str, Any]]] = {}
    traces: dict[tuple[int, int], dict[str, Any]] = {}
    total = len(plan.seeds) * len(plan.specs) * len(plan.scenarios)
    cpu_s = 0.0
    bar = tqdm(total=total, unit="run", desc=f"benchmark {plan.suite_name}", disable=args.quiet)
    with bar:
        for job, res in run_jobs(
            jobs, backend=args.backend, workers=args.workers, ray_address=args.ray_address
        ):
            results.setdefault((job.scenario, job.policy), []).extend(res["rows"])
            if "trace" in res:
                traces[job.scenario, job.policy] = res["trace"]
            cpu_s += res["cpu_s"]
            bar.update(len(job.seeds))
    sim_wall = time.perf_counter() - t0
    columns = _columns(plan.scenarios, plan.configs)
    rows = _ordered_rows(plan, results, columns)
    return Results(rows, columns, traces, started, sim_wall, cpu_s, len(jobs), total)


def _records(plan: Plan) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    scenarios = [
        {"label": sc.label, "overrides": dict(sc.overrides), "config": cfg.to_dict()}
        for sc, cfg in zip(plan.scenarios, plan.configs, strict=True)
    ]
    policies = [
        {"label": s.label, "name": s.name, "gains": dict(s.gains), "resolved": plan.reprs[s.label]}
        for s in plan.specs
    ]
    return scenarios, policies


def _write_results(out: Path, plan: Plan, res: Results, sc_records, pol_records) -> None:
    metric_cols = [k for k in res.rows[0] if k not in res.columns and k != "policy"]
    write_csv(out / "results.csv", res.rows, [*res.columns, "policy", *metric_cols])
    record = {
        "suite": plan.suite_name,
        "preset": plan.preset,
        "seeds": plan.seeds,
        "scenarios": sc_records,
        "policies": pol_records,
        "metrics": {
            k: list(v)
            for k, v in {
                **METRIC_DOCS,
                **(SAFETY_METRIC_DOCS if has_safety_columns(res.rows) else {}),
                **(
                    {**SWARM_SAFETY_METRIC_DOCS, **FLOCK_METRIC_DOCS}
                    if has_swarm_columns(res.rows)
                    else {}
                ),
            }.items()
        },
        "snapshots": plan.snapshots,
        "runs": json_rows(res.rows),
    }
    atomic_write_text(out / "results.json", dumps_stable(record))


def _video_path(out: Path, folder: Path, plan: Plan, res: Results, args) -> tuple[Path, Path]:
    """(where to write the video, where it ends up): inside ``out`` it goes through the
    staging ``folder`` like every other result file."""
    i, j = plan.video
    seed = res.traces[i, j]["seed"]
    if args.video == "auto":
        name = f"episode_{slug(plan.scenarios[i].label)}_{slug(plan.specs[j].label)}_seed{seed}.mp4"
        return folder / name, out / name
    final = Path(args.video)
    if final.resolve().is_relative_to(out.resolve()):
        return folder / final.resolve().relative_to(out.resolve()), final
    return final, final


def _write_video(path: Path, plan: Plan, res: Results, args) -> Path:
    i, j = plan.video
    tr, cfg = res.traces[i, j], plan.configs[i]
    sc, spec = plan.scenarios[i], plan.specs[j]
    return write_episode_video(
        path,
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
        title=f"{cfg.n_uavs} UAVs, {spec.label}, {sc.label}",
    )


def _recordings(plan: Plan) -> list[str]:
    """The recordings of the runs (--record), relative to the output folder."""
    return written(plan.recorded_runs(), plan.seeds, plan.out)


def _run_record(plan: Plan, res: Results, args, records, outputs, total_s: float):
    sc_records, pol_records = records
    return run_record(
        suite=plan.suite_name,
        preset=plan.preset,
        seeds=plan.seeds,
        policies=pol_records,
        scenarios=sc_records,
        backend=args.backend,
        workers=args.workers,
        batch_size=args.batch_size,
        ray_address=args.ray_address,
        metric_options=plan.metric_kwargs,
        outputs=outputs,
        recordings=_recordings(plan),
        timestamps={
            "started_utc": res.started.isoformat(timespec="seconds"),
            "finished_utc": _now().isoformat(timespec="seconds"),
        },
        timing={
            "simulation_s": round(res.sim_wall, 2),
            "total_s": round(total_s, 2),
            "jobs_cpu_s": round(res.cpu_s, 2),
            "jobs": res.jobs,
            "runs": res.runs,
        },
    )


def _write_all(plan: Plan, res: Results, args, t0: float):
    """Every output file, through a staging folder (:func:`~baselines.runtime.folders.
    result_folder`); returns (checks, figure paths, video path, total seconds)."""
    out = plan.out
    records = _records(plan)
    checks = []
    if (plan.suite.check or args.check) and plan.preset == "paper":
        checks = check_paper_claims(res.rows)
    with result_folder(out) as folder:
        _write_results(folder, plan, res, *records)
        names = ["results.csv", "results.json", "summary.md"]
        fig_names: list[str] = []
        if plan.figures:
            save_traces(folder / "traces.npz", res.traces)
            labels = [s.label for s in plan.specs]
            figs = make_figures(
                folder, res.rows, res.traces, records[0], labels, snapshots=plan.snapshots
            )
            fig_names = [str(p.relative_to(folder)) for p in figs]
            names += ["traces.npz", *fig_names]
        video_path = None
        if plan.video is not None:
            write_to, video_path = _video_path(out, folder, plan, res, args)
            _write_video(write_to, plan, res, args)
            if write_to.is_relative_to(folder):
                names.append(str(write_to.relative_to(folder)))
        md = summary_markdown(plan, res.rows, checks, [out / n for n in fig_names])
        atomic_write_text(folder / "summary.md", md)
        total_s = time.perf_counter() - t0
        record = _run_record(plan, res, args, records, sorted(names), total_s)
        write_json(folder / "run.json", record)
    return checks, [out / n for n in fig_names], video_path, total_s


def replot(args, parser) -> int:
    """``--replot DIR``: redraw the figures of a finished run from its files."""
    d = args.replot
    if (d / INCOMPLETE_MARKER).exists():
        parser.error(
            f"--replot {str(d)!r}: the folder is marked {INCOMPLETE_MARKER} (a run was "
            "interrupted while writing it); rerun the benchmark"
        )
    try:
        res = json.loads((d / "results.json").read_text())
    except FileNotFoundError:
        parser.error(f"--replot {str(d)!r} is invalid: no results.json there")
    rows = [{k: (float("nan") if v is None else v) for k, v in r.items()} for r in res["runs"]]
    traces = load_traces(d / "traces.npz") if (d / "traces.npz").exists() else {}
    snapshots = bool(res["snapshots"]) and not args.no_snapshots
    policies = [p["label"] for p in res["policies"]]
    paths = make_figures(d, rows, traces, res["scenarios"], policies, snapshots=snapshots)
    print(f"wrote {len(paths)} figures in {d}")
    return 0


def main(argv: Sequence[str] | None = None, prog: str = PROG) -> int:
    """The benchmark CLI (``python -m baselines.benchmark``); returns the exit status."""
    parser = build_parser(prog)
    args = parser.parse_args(argv)
    if args.replot is not None:
        return replot(args, parser)
    plan = resolve(args, parser)
    t0 = time.perf_counter()
    res = simulate(plan, args)
    checks, fig_paths, video_path, total_s = _write_all(plan, res, args, t0)
    print(summary_table(res.rows, ACCURACY_METRICS, plan.keys))
    if has_safety_columns(res.rows):
        print("\n" + safety_table(res.rows, plan.keys))
    if has_swarm_columns(res.rows):
        print("\n" + swarm_table(res.rows, plan.keys))
    for line in criteria_lines(checks):
        print(line)
    print(
        f"\nwrote {plan.out}/results.csv, results.json, summary.md, run.json, "
        f"{len(fig_paths)} figures{', ' + str(video_path) if video_path else ''} in "
        f"{total_s:.1f} s (simulation {res.sim_wall:.1f} s wall, {res.cpu_s:.1f} s CPU in jobs; "
        f"backend {args.backend}, {args.workers} workers)"
    )
    if plan.record is not None:
        print(report_line(_recordings(plan), plan.out))
    if args.check and not all_passed(checks):
        if not checks:
            print("--check: no acceptance criterion applies to these policies")
        return 1
    return 0
