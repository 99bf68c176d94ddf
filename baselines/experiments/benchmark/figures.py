"""The benchmark's figure set and the recorded trajectories (``traces.npz``) it is drawn from.

Everything here is a function of the result rows and traces, so ``python -m
baselines.benchmark --replot DIR`` redraws a finished run without simulating.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from baselines.evaluation.specs import slug
from baselines.reporting.figures import (
    error_figure,
    policy_styles,
    save_figure,
    snapshot_figure,
    steady_error_figure,
    surface_panels_figure,
    trajectories_3d_figure,
)
from baselines.runtime.files import atomic_write_bytes
from pairflock_env.task.metrics import METRIC_DOCS

__all__ = ["load_traces", "make_figures", "save_traces"]

Traces = Mapping[tuple[int, int], Mapping[str, Any]]


def _scenario(r: Mapping[str, Any]) -> str:
    return r["scenario"] if "scenario" in r else f"N={r['n_uavs']}"


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
    """The traces written by :func:`save_traces`, keyed by (scenario, policy) index."""
    out: dict[tuple[int, int], dict[str, Any]] = {}
    with np.load(Path(path)) as z:
        for key in z.files:
            head, name = key.split("_", 2)[:2], key.split("_", 2)[2]
            ij = (int(head[0][1:]), int(head[1][1:]))
            v = z[key]
            out.setdefault(ij, {})[name] = int(v) if name == "seed" else v
    return out


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


def _pair_error(out_dir, traces, labels, policies, styles, dpi) -> list[Path]:
    """Pair error, several policies per panel (Fig. 10)."""
    panels = {}
    for i, lab in enumerate(labels):
        curves = {
            policies[j]: (traces[i, j]["t"], traces[i, j]["pair_error"][0])
            for j in range(len(policies))
            if (i, j) in traces
        }
        if curves:
            panels[lab] = curves
    if not panels:
        return []
    seed = next(iter(traces.values()))["seed"]
    fig = error_figure(panels, f"Pair distance error (pair 0, seed {seed})", styles=styles)
    return [save_figure(fig, out_dir / "pair_error.png", dpi=dpi)]


def _sliding_surface(out_dir, rows, traces, labels, policies, styles, dpi) -> list[Path]:
    """Sliding surface: one panel per controlling policy, one line per scenario (Figs. 6, 13)."""
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
    if not spanels:
        return []
    # show the reaching phase and a little of the sliding phase (its chattering looks the
    # same for the rest of the episode): up to twice the latest settle time
    t_max = max(float(tr["t"][-1]) for tr in traces.values())
    reached = [x for x in t_ends if np.isfinite(x)]
    if reached:
        t_max = min(t_max, 2.0 * max(reached))
    fig = surface_panels_figure(spanels, t_max, "Sliding surface s(t) (pair 0, first seed)")
    return [save_figure(fig, out_dir / "sliding_surface.png", dpi=dpi)]


_BOXES = (
    ("ss_mean_error", "steady_error.png", "steady mean |error|"),
    ("ss_max_error", "steady_max_error.png", "steady max |error|"),
)


def _steady_error(out_dir, rows, labels, policies, styles, dpi) -> list[Path]:
    """Steady-state error per scenario and policy, every run a dot."""
    paths = []
    for metric, name, ylabel in _BOXES:
        vals: dict[tuple[str, str], list[float]] = {}
        for r in rows:
            vals.setdefault((_scenario(r), r["policy"]), []).append(r[metric])
        unit, meaning = METRIC_DOCS[metric]
        fig = steady_error_figure(
            vals,
            labels,
            list(policies),
            f"{ylabel} ({unit})",
            f"Steady-state pair error: {meaning}",
            styles=styles,
        )
        paths.append(save_figure(fig, out_dir / name, dpi=dpi))
    return paths


def _recorded_runs(
    out_dir, rows, traces, scenarios, policies, styles, snapshots, dpi
) -> list[Path]:
    """Snapshots and 3-D trajectories of each recorded run."""
    labels = [s["label"] for s in scenarios]
    paths = []
    for (i, j), tr in sorted(traces.items()):
        cfg = scenarios[i]["config"]
        pol = policies[j]
        name = f"{slug(labels[i])}_{slug(pol)}"
        title = _title(cfg, styles[pol]["label"], labels[i], tr["seed"])
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
                title,
            )
            paths.append(save_figure(fig, out_dir / f"snapshots_{name}.png", dpi=dpi))
        if int(cfg["dim"]) == 3:
            fig = trajectories_3d_figure(
                tr["positions"], tr["leader_positions"], cfg["pairs"], title
            )
            paths.append(save_figure(fig, out_dir / f"trajectories3d_{name}.png", dpi=dpi))
    return paths


def make_figures(
    out_dir: Path,
    rows: Sequence[Mapping[str, Any]],
    traces: Traces,
    scenarios: Sequence[Mapping[str, Any]],
    policies: Sequence[str],
    *,
    snapshots: bool = True,
    dpi: int = 90,
) -> list[Path]:
    """The figure set of a benchmark run; returns the PNG paths written.

    ``scenarios``: per scenario index, ``{"label", "config"}`` (config as a dict: pairs, d_m,
    dim, horizon); ``policies``: labels by index; ``traces[(i, j)]`` as from
    :func:`baselines.evaluation.jobs.run_job`.
    """
    out_dir = Path(out_dir)
    styles = policy_styles(policies)
    labels = [s["label"] for s in scenarios]
    return [
        *_pair_error(out_dir, traces, labels, policies, styles, dpi),
        *_sliding_surface(out_dir, rows, traces, labels, policies, styles, dpi),
        *_steady_error(out_dir, rows, labels, policies, styles, dpi),
        *_recorded_runs(out_dir, rows, traces, scenarios, policies, styles, snapshots, dpi),
    ]
