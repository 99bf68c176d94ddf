"""What a benchmark writes besides the raw rows: markdown tables, the paper's acceptance
checks, the figure set, and the recorded trajectories (``traces.npz``) the figures come from.

Everything here is a function of the result rows and traces, so ``python -m
baselines.benchmark --replot DIR`` redraws a finished run without simulating.
"""

from __future__ import annotations

import io
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from baselines.evaluation.io import atomic_write_bytes
from pairflock_env.metrics import METRIC_DOCS

__all__ = [
    "ACCURACY_METRICS",
    "COST_METRICS",
    "PIVOT_METRICS",
    "SCENARIO_KEYS",
    "check_paper_claims",
    "load_traces",
    "make_figures",
    "pivot_table",
    "save_traces",
    "stat_cell",
    "summarize",
    "summary_table",
]

#: (metric, header, format) of the two summary tables
ACCURACY_METRICS = (
    ("s_settle_time", "s settle (s)", "{:.2f}"),
    ("band_time", "0.5 m band (s)", "{:.2f}"),
    ("ss_mean_error", "steady mean err (m)", "{:.3f}"),
    ("ss_max_error", "steady max err (m)", "{:.3f}"),
)
COST_METRICS = (
    ("peak_accel", "peak accel (m/s^2)", "{:.0f}"),
    ("effort", "effort (m^2/s^3)", "{:.3g}"),
    ("chattering", "chattering (m/s^3)", "{:.3g}"),
    ("peak_speed", "peak speed (m/s)", "{:.1f}"),
    ("min_pair_separation", "min pair-other dist (m)", "{:.2f}"),
    ("pair_collision_steps", "collision steps", "{:.0f}"),
    ("final_velocity_mismatch", "velocity mismatch (m/s)", "{:.3f}"),
    ("final_largest_component", "largest component", "{:.0f}"),
)
#: metrics also tabulated scenarios-down, policies-across (the robustness view)
PIVOT_METRICS = ("ss_mean_error", "ss_max_error", "band_time")
for _m, _, _ in ACCURACY_METRICS + COST_METRICS:
    assert _m in METRIC_DOCS, _m  # the tables name only metrics that exist


def stat_cell(values: Sequence[float], fmt: str) -> str:
    """``median [min-max]`` over runs; NaN runs (a time never reached) are counted."""
    v = np.asarray(values, dtype=float)
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return "never"
    rng = f"{fmt.format(finite.min())}-{fmt.format(finite.max())}"
    if finite.size < v.size:
        return f"never in {v.size - finite.size}/{v.size}; others {rng}"
    return f"{fmt.format(np.median(v))} [{rng}]"


def _scenario(r: Mapping[str, Any]) -> str:
    return r["scenario"] if "scenario" in r else f"N={r['n_uavs']}"


def _ordered(rows: Sequence[Mapping[str, Any]], key) -> list:
    seen: dict[Any, None] = {}
    for r in rows:
        seen.setdefault(key(r), None)
    return list(seen)


Keys = Sequence[tuple[str, str]]
#: default leading columns of the tables: the scenario label
SCENARIO_KEYS: Keys = (("scenario", "scenario"),)


def _lead(rows: Sequence[Mapping[str, Any]], keys: Keys) -> list[tuple[str, list[str]]]:
    """(scenario, its leading cells) in order of appearance."""
    out = []
    for sc in _ordered(rows, _scenario):
        first = next(r for r in rows if _scenario(r) == sc)
        out.append((sc, [str(first.get(k, sc)) for _, k in keys]))
    return out


def summary_table(
    rows: Sequence[Mapping[str, Any]], metrics=ACCURACY_METRICS, keys: Keys = SCENARIO_KEYS
) -> str:
    """Markdown: one line per (scenario, policy) in order of appearance, median [min-max].

    ``keys``: (header, row key) of the leading columns, e.g. ``(("N", "n_uavs"),)`` for a
    sweep over N (default: the scenario label)."""
    heads = [h for h, _ in keys]
    header = "| " + " | ".join(heads) + " | policy | " + " | ".join(h for _, h, _ in metrics) + " |"
    lines = [header, "|" + "---|" * (len(metrics) + len(keys) + 1)]
    for sc, lead in _lead(rows, keys):
        for pol in _ordered([r for r in rows if _scenario(r) == sc], lambda r: r["policy"]):
            sel = [r for r in rows if _scenario(r) == sc and r["policy"] == pol]
            cells = [stat_cell([r[k] for r in sel], fmt) for k, _, fmt in metrics]
            lines.append("| " + " | ".join([*lead, pol, *cells]) + " |")
    return "\n".join(lines)


def summarize(rows: Sequence[Mapping[str, Any]], keys: Keys = SCENARIO_KEYS) -> str:
    """Both summary tables (accuracy, then cost and safety)."""
    return (
        summary_table(rows, ACCURACY_METRICS, keys)
        + "\n\n"
        + summary_table(rows, COST_METRICS, keys)
    )


def pivot_table(
    rows: Sequence[Mapping[str, Any]], metric: str, fmt: str, keys: Keys = SCENARIO_KEYS
) -> str:
    """Markdown: scenarios down, policies across, ``median [min-max]`` of ``metric``."""
    pols = _ordered(rows, lambda r: r["policy"])
    heads = [h for h, _ in keys]
    lines = ["| " + " | ".join(heads + pols) + " |", "|" + "---|" * (len(pols) + len(keys))]
    for sc, lead in _lead(rows, keys):
        cells = []
        for pol in pols:
            sel = [r[metric] for r in rows if _scenario(r) == sc and r["policy"] == pol]
            cells.append(stat_cell(sel, fmt) if sel else "-")
        lines.append("| " + " | ".join(lead + cells) + " |")
    return "\n".join(lines)


def check_paper_claims(rows: Sequence[Mapping[str, Any]]) -> list[tuple[str, bool, str]]:
    """The acceptance criteria of the Sec. VI-A reproduction, per scenario (every seed)."""
    out = []
    for sc in _ordered(rows, _scenario):
        sel = [r for r in rows if _scenario(r) == sc]
        smc = [r for r in sel if r["policy"] == "smc"]
        prop = [r for r in sel if r["policy"] == "proportional"]
        zero = [r for r in sel if r["policy"] == "zero"]
        if smc:
            s = np.array([r["s_settle_time"] for r in smc])
            b = np.array([r["band_time"] for r in smc])
            e = np.array([r["ss_mean_error"] for r in smc])
            out.append(
                (
                    f"{sc} smc: s settles in 1.5-3.0 s on every seed",
                    bool(np.all((s >= 1.5) & (s <= 3.0))),
                    stat_cell(s, "{:.2f}") + " s",
                )
            )
            out.append(
                (
                    f"{sc} smc: 0.5 m band in 3.0-5.0 s on every seed",
                    bool(np.all((b >= 3.0) & (b <= 5.0))),
                    stat_cell(b, "{:.2f}") + " s",
                )
            )
            out.append(
                (
                    f"{sc} smc: steady mean error <= 0.20 m on every seed",
                    bool(np.all(e <= 0.20)),
                    f"max {np.max(e):.3f} m",
                )
            )
            if prop:
                pm = float(np.median([r["ss_mean_error"] for r in prop]))
                sm = float(np.median(e))
                out.append(
                    (
                        f"{sc} proportional median error >= 5x smc median",
                        pm >= 5 * sm,
                        f"{pm:.3f} m vs {sm:.3f} m ({pm / sm:.1f}x)",
                    )
                )
        if zero:
            z = np.array([r["ss_mean_error"] for r in zero])
            out.append(
                (
                    f"{sc} zero: steady mean error >= 10 m on every seed",
                    bool(np.all(z >= 10.0)),
                    f"min {np.min(z):.1f} m",
                )
            )
    return out


# ---------------------------------------------------------------------------------------
# recorded trajectories
# ---------------------------------------------------------------------------------------
_TRACE_KEYS = (
    "t",
    "pair_error",
    "surface",
    "frame_t",
    "positions",
    "velocities",
    "leader_positions",
)


def save_traces(path: Path, traces: Mapping[tuple[int, int], Mapping[str, Any]]) -> Path:
    """``traces[(scenario, policy)]`` -> one compressed npz (keys ``s{i}_p{j}_{name}``)."""
    arrays: dict[str, np.ndarray] = {}
    for (i, j), tr in sorted(traces.items()):
        arrays[f"s{i}_p{j}_seed"] = np.asarray(tr["seed"])
        for k in _TRACE_KEYS:
            arrays[f"s{i}_p{j}_{k}"] = np.asarray(tr[k])
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return atomic_write_bytes(Path(path), buf.getvalue())


def load_traces(path: Path) -> dict[tuple[int, int], dict[str, Any]]:
    out: dict[tuple[int, int], dict[str, Any]] = {}
    with np.load(Path(path)) as z:
        for key in z.files:
            head, name = key.split("_", 2)[:2], key.split("_", 2)[2]
            ij = (int(head[0][1:]), int(head[1][1:]))
            v = z[key]
            out.setdefault(ij, {})[name] = int(v) if name == "seed" else v
    return out


# ---------------------------------------------------------------------------------------
# figures
# ---------------------------------------------------------------------------------------
def _median_finite(values: Sequence[float]) -> float | None:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.median(v)) if v.size else None


def _snapshot_times(rows: Sequence[Mapping[str, Any]], horizon: float) -> list[float]:
    """0, when s settles, when the pair enters the band (medians over the scenario's runs
    that get there; the paper's Figs. 4, 8, 11 show these moments) and the end."""
    s = _median_finite([r["s_settle_time"] for r in rows])
    b = _median_finite([r["band_time"] for r in rows])
    mid = [x for x in (s, b) if x is not None and 0.0 < x < horizon]
    while len(mid) < 2:  # nothing converged: spread the middle panels over the episode
        mid.append(horizon * (len(mid) + 1) / 3)
    return [0.0, *sorted(mid), horizon]


def _title(cfg: Mapping[str, Any], policy: str, scenario: str, seed: int) -> str:
    n = cfg["n_uavs"]
    extra = "" if scenario in ("nominal", f"N={n}") else f", {scenario}"
    return f"{n} UAVs, {policy}{extra} (seed {seed})"


def make_figures(
    out_dir: Path,
    rows: Sequence[Mapping[str, Any]],
    traces: Mapping[tuple[int, int], Mapping[str, Any]],
    scenarios: Sequence[Mapping[str, Any]],
    policies: Sequence[str],
    *,
    snapshots: bool = True,
    dpi: int = 90,
) -> list[Path]:
    """The figure set of a benchmark run; returns the PNG paths written.

    ``scenarios``: per scenario index, ``{"label", "config"}`` (config as a dict: pairs, d_m,
    dim, horizon); ``policies``: labels by index; ``traces[(i, j)]`` as from
    :func:`baselines.sweep.run_job`.
    """
    from baselines.evaluation.specs import slug

    from .figures import (
        error_figure,
        policy_styles,
        save_figure,
        snapshot_figure,
        steady_error_figure,
        surface_panels_figure,
        trajectories_3d_figure,
    )

    out_dir = Path(out_dir)
    styles = policy_styles(policies)
    labels = [s["label"] for s in scenarios]
    paths: list[Path] = []
    first_seed = {ij: tr["seed"] for ij, tr in traces.items()}

    # pair error, several policies per panel (Fig. 10)
    panels = {}
    for i, lab in enumerate(labels):
        curves = {
            policies[j]: (traces[i, j]["t"], traces[i, j]["pair_error"][0])
            for j in range(len(policies))
            if (i, j) in traces
        }
        if curves:
            panels[lab] = curves
    if panels:
        seed = next(iter(first_seed.values()))
        paths.append(
            save_figure(
                error_figure(panels, f"Pair distance error (pair 0, seed {seed})", styles=styles),
                out_dir / "pair_error.png",
                dpi=dpi,
            )
        )

    # sliding surface: one panel per controlling policy, one line per scenario (Figs. 6, 13)
    spanels = {}
    t_ends = []  # when s settles, per plotted run
    for j, pol in enumerate(policies):
        if pol == "zero":
            continue
        series = {
            labels[i]: (traces[i, j]["t"], traces[i, j]["surface"][0])
            for i in range(len(labels))
            if (i, j) in traces
        }
        if series:
            spanels[styles[pol]["label"]] = series
            t_ends += [r["s_settle_time"] for r in rows if r["policy"] == pol]
    if spanels:
        # show the reaching phase and a little of the sliding phase (its chattering looks
        # the same for the rest of the episode): up to twice the latest settle time
        t_max = max(float(tr["t"][-1]) for tr in traces.values())
        reached = [x for x in t_ends if np.isfinite(x)]
        if reached:
            t_max = min(t_max, 2.0 * max(reached))
        paths.append(
            save_figure(
                surface_panels_figure(spanels, t_max, "Sliding surface s(t) (pair 0, first seed)"),
                out_dir / "sliding_surface.png",
                dpi=dpi,
            )
        )

    # steady-state error per scenario and policy, every run a dot
    boxes = (
        ("ss_mean_error", "steady_error.png", "steady mean |error|"),
        ("ss_max_error", "steady_max_error.png", "steady max |error|"),
    )
    for metric, name, ylabel in boxes:
        vals: dict[tuple[str, str], list[float]] = {}
        for r in rows:
            vals.setdefault((_scenario(r), r["policy"]), []).append(r[metric])
        unit, meaning = METRIC_DOCS[metric]
        paths.append(
            save_figure(
                steady_error_figure(
                    vals,
                    labels,
                    list(policies),
                    f"{ylabel} ({unit})",
                    f"Steady-state pair error: {meaning}",
                    styles=styles,
                ),
                out_dir / name,
                dpi=dpi,
            )
        )

    # snapshots and 3-D trajectories of the recorded run
    for (i, j), tr in sorted(traces.items()):
        cfg = scenarios[i]["config"]
        pol = policies[j]
        name = f"{slug(labels[i])}_{slug(pol)}"
        if snapshots and pol != "zero":
            # the same moments for every policy of a scenario: those of its first policy
            ref = next((p for p in policies if p != "zero"), pol)
            sel = [r for r in rows if _scenario(r) == labels[i] and r["policy"] == ref]
            times = _snapshot_times(sel, float(tr["frame_t"][-1]))
            fig = snapshot_figure(
                tr["frame_t"],
                tr["positions"],
                tr["velocities"],
                tr["leader_positions"],
                cfg["pairs"],
                cfg["d_m"],
                times,
                _title(cfg, styles[pol]["label"], labels[i], tr["seed"]),
            )
            paths.append(save_figure(fig, out_dir / f"snapshots_{name}.png", dpi=dpi))
        if int(cfg["dim"]) == 3:
            fig = trajectories_3d_figure(
                tr["positions"],
                tr["leader_positions"],
                cfg["pairs"],
                _title(cfg, styles[pol]["label"], labels[i], tr["seed"]),
            )
            paths.append(save_figure(fig, out_dir / f"trajectories3d_{name}.png", dpi=dpi))
    return paths


def json_rows(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Rows for JSON: NaN (a time never reached) becomes null."""
    out = []
    for r in rows:
        out.append(
            {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in r.items()}
        )
    return out


def dumps_stable(obj: Any) -> str:
    """JSON text that is byte-identical for equal content (sorted keys, fixed layout)."""
    from baselines.evaluation.io import _json_default

    return json.dumps(obj, indent=1, sort_keys=True, default=_json_default, allow_nan=False) + "\n"
