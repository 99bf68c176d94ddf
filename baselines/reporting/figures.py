"""Paper-style figures (Figs. 4-16) from rollout traces and metric rows; headless (Agg canvas,
no display, no pyplot state).

* :func:`snapshot_figure` - positions and headings at several times (Figs. 4, 8, 11; the last
  panel with velocity arrows as Figs. 5, 9, 12);
* :func:`surface_figure` / :func:`surface_panels_figure` - the sliding surface s(t) (Figs. 6, 13);
* :func:`error_figure` - pair distance error of several policies on one axis (Fig. 10);
* :func:`steady_error_figure` - box + strip plot of a per-run metric per scenario and policy;
* :func:`trajectories_3d_figure` - 3-D trajectories (Fig. 16).
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from baselines.runtime.files import atomic_write_bytes
from pairflock_env.render import PAIR_COLORS, UNPAIRED_COLOR, draw_swarm

__all__ = [
    "POLICY_STYLE",
    "error_figure",
    "policy_styles",
    "save_figure",
    "snapshot_figure",
    "steady_error_figure",
    "surface_figure",
    "surface_panels_figure",
    "trajectories_3d_figure",
]

#: the paper's comparison, drawn the same way in every figure
POLICY_STYLE = {
    "smc": dict(color="tab:red", label="sliding mode (eq. 28)"),
    "proportional": dict(color="tab:blue", label="normal method (eq. 44)"),
    "zero": dict(color="0.4", label="no pair term"),
}
#: widest figure (inches) before boxes get narrower instead
MAX_WIDTH_IN = 14.0
#: colours for every other policy spec, in order of appearance
_EXTRA_COLORS = (
    "tab:green",
    "tab:purple",
    "tab:orange",
    "tab:brown",
    "tab:pink",
    "tab:olive",
    "tab:cyan",
)


def policy_styles(labels: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Colour and legend text for each policy label: the paper's three keep their colours,
    other specs (gains, learned policies) take distinct ones."""
    out: dict[str, dict[str, Any]] = {}
    extra = iter(_EXTRA_COLORS * (1 + len(labels) // len(_EXTRA_COLORS)))
    for lab in labels:
        if lab in POLICY_STYLE:
            out[lab] = dict(POLICY_STYLE[lab])
            continue
        text = lab
        if lab.startswith("sb3:"):
            text = f"learned ({Path(lab[4:]).stem})"
        out[lab] = dict(color=next(extra), label=text)
    return out


def _style(policy: str) -> dict:
    return POLICY_STYLE.get(policy, dict(label=policy))


def save_figure(fig: Figure, path: str | Path, dpi: int = 110) -> Path:
    """Render ``fig`` to PNG and write it atomically (no timestamp in the file)."""
    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    return atomic_write_bytes(Path(path), buf.getvalue())


def _suptitle(fig: Figure, title: str) -> None:
    """Figure title above the panels: tight layout, then lower the panels if their titles
    would touch it (tight_layout alone lets them overlap in tall figures)."""
    text = fig.suptitle(title)
    fig.tight_layout()
    renderer = FigureCanvasAgg(fig).get_renderer()
    pad = 0.1 * fig.dpi  # 0.1 in
    bottom = text.get_window_extent(renderer).y0
    top = max(ax.get_tightbbox(renderer).y1 for ax in fig.axes)
    if top > bottom - pad:
        shift = (top - bottom + pad) / fig.bbox.height
        fig.subplots_adjust(top=fig.subplotpars.top - shift)


def _grid(n: int, ncols: int) -> tuple[int, int]:
    cols = max(1, min(n, ncols))
    return int(np.ceil(n / cols)), cols


def snapshot_figure(
    t: np.ndarray,
    positions: np.ndarray,
    velocities: np.ndarray,
    leader_positions: np.ndarray,
    pairs,
    d_m,
    times: Sequence[float],
    title: str,
) -> Figure:
    """Positions and headings at several times (Figs. 4, 8, 11); the last panel shows
    velocity arrows like Figs. 5, 9, 12. ``t`` are the sample times of ``positions``
    (need not be evenly spaced); each panel shows the sample nearest to the asked time.
    3-D states are drawn in the x-y plane."""
    t = np.asarray(t, dtype=float)
    n = len(times)
    rows, cols = _grid(n, 2 if n == 4 else 3)
    fig = Figure(figsize=(4.2 * cols, 4.0 * rows))
    headings = None
    for i, ti in enumerate(times):
        k = int(np.argmin(np.abs(t - ti)))
        ax = fig.add_subplot(rows, cols, i + 1)
        headings = draw_swarm(
            ax,
            positions[k],
            velocities[k],
            pairs,
            d_m,
            leader_positions[k],
            headings=headings,
            arrows=(i == n - 1),
            title=f"t = {round(float(t[k]), 2):g} s",
        )
        if positions.shape[-1] == 3:
            ax.set_title(f"t = {round(float(t[k]), 2):g} s (x-y plane)", fontsize=10)
    _suptitle(fig, title)
    return fig


def surface_panels_figure(
    panels: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]]],
    t_max: float,
    title: str,
    *,
    ncols: int = 3,
    linthresh: float = 10.0,
    sharey: bool = False,
) -> Figure:
    """Sliding surface s(t) (Figs. 6, 13, 17): panel title -> line label -> (t, s); symlog
    axis, linear within +-``linthresh`` (s starts near 1e5 m^2/s and chatters around 0);
    ``sharey`` gives every panel the same scale."""
    rows, cols = _grid(len(panels), ncols)
    fig = Figure(figsize=(5.6 * cols, 3.6 * rows + 0.5))
    first = None
    for i, (ptitle, series) in enumerate(panels.items()):
        ax = fig.add_subplot(rows, cols, i + 1, sharey=first if sharey else None)
        first = first or ax
        for c, (label, (t, s)) in enumerate(series.items()):
            m = t <= t_max
            ax.plot(
                t[m], s[m], lw=0.8, alpha=0.8, label=label, color=PAIR_COLORS[c % len(PAIR_COLORS)]
            )
        ax.set_yscale("symlog", linthresh=linthresh)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("s (m$^2$/s)")
        ax.set_title(ptitle, fontsize=10)
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=8)
    _suptitle(fig, title)
    return fig


def surface_figure(
    series: Mapping[str, tuple[np.ndarray, np.ndarray]], t_max: float, title: str
) -> Figure:
    """Sliding surface s(t) (Figs. 6, 13): one line per label, one panel."""
    fig = surface_panels_figure({"": series}, t_max, title)
    return fig


def error_figure(
    panels: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]]],
    title: str,
    *,
    styles: Mapping[str, Mapping[str, Any]] | None = None,
    ncols: int = 3,
) -> Figure:
    """Pair distance error ||y|| - d_m over time, several policies per panel (Fig. 10).

    ``panels``: panel title -> policy -> (t, error). Symlog axis: the error starts near
    250 m and ends near 0.1 m; dashed lines mark the +-0.5 m band.
    """
    rows, cols = _grid(len(panels), ncols)
    fig = Figure(figsize=(5.4 * cols, 3.6 * rows + 0.5))
    for i, (ptitle, curves) in enumerate(panels.items()):
        ax = fig.add_subplot(rows, cols, i + 1)
        for policy, (t, e) in curves.items():
            st = (styles or {}).get(policy) or _style(policy)
            ax.plot(t, e, lw=1.0, color=st.get("color"), label=st["label"])
        ax.set_yscale("symlog", linthresh=0.1)
        ax.axhline(0.0, color="k", lw=0.6)
        for b in (-0.5, 0.5):
            ax.axhline(b, color="0.6", lw=0.6, ls="--")
        ax.set_xlabel("time (s)")
        ax.set_ylabel(r"$\|y\| - d_m$ (m)")
        ax.set_title(ptitle, fontsize=10)
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=8)
    _suptitle(fig, title)
    return fig


def _box_with_dots(ax, v: np.ndarray, x: float, width: float, color) -> None:
    """One box (min to max whiskers) at ``x`` with every run as a dot."""
    bp = ax.boxplot(
        [v],
        positions=[x],
        widths=width * 0.8,
        whis=(0, 100),
        patch_artist=True,
        manage_ticks=False,
    )
    for box in bp["boxes"]:
        box.set(facecolor=color, alpha=0.25, edgecolor=color)
    for part in ("whiskers", "caps", "medians"):
        for line in bp[part]:
            line.set(color=color, lw=1.2 if part == "medians" else 0.8)
    # deterministic spread of the dots across the box width
    jitter = np.linspace(-0.3, 0.3, v.size) * width if v.size > 1 else np.zeros(1)
    ax.plot(x + jitter, v, "o", ms=3, color=color, mec="k", mew=0.3, alpha=0.9)


def steady_error_figure(
    values: Mapping[tuple[str, str], Sequence[float]],
    scenarios: Sequence[str],
    policies: Sequence[str],
    ylabel: str,
    title: str,
    *,
    styles: Mapping[str, Mapping[str, Any]] | None = None,
    log: bool = True,
) -> Figure:
    """Box plot with every run as a dot, grouped by scenario, one colour per policy.

    ``values[(scenario, policy)]``: one number per run (NaN runs are left out and counted in
    the x label). Log axis by default: the policies differ by orders of magnitude.
    """
    styles = dict(styles or policy_styles(policies))
    P = len(policies)
    width = 0.8 / P
    S = len(scenarios)
    fig = Figure(figsize=(min(MAX_WIDTH_IN, max(5.0, 1.1 + 0.45 * P * S + 0.5 * S)), 4.6))
    ax = fig.add_subplot(1, 1, 1)
    labels = []
    for i, sc in enumerate(scenarios):
        missing = 0
        for j, pol in enumerate(policies):
            v = np.asarray(values.get((sc, pol), ()), dtype=float)
            missing += int(np.sum(~np.isfinite(v)))
            v = v[np.isfinite(v)]
            if v.size == 0:
                continue
            _box_with_dots(ax, v, i + (j - (P - 1) / 2) * width, width, styles[pol]["color"])
        labels.append(sc if not missing else f"{sc}\n({missing} runs: never)")
    for pol in policies:
        ax.plot([], [], "s", color=styles[pol]["color"], alpha=0.6, label=styles[pol]["label"])
    ax.set_xticks(range(len(scenarios)))
    long = max((len(s) for s in scenarios), default=0) > 12
    ax.set_xticklabels(
        labels, rotation=25 if long else 0, ha="right" if long else "center", fontsize=8
    )
    ax.set_xlim(-0.6, len(scenarios) - 0.4)
    if log:
        ax.set_yscale("log")
        # plain numbers at 1-2-5 steps: decades alone are too sparse to read 0.2 m off
        ax.yaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, axis="y", which="both", lw=0.3)
    # outside the axes: no box can hide behind it
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    return fig


def trajectories_3d_figure(
    positions: np.ndarray,
    leader_positions: np.ndarray,
    pairs,
    title: str,
    *,
    t: np.ndarray | None = None,
    marks: Sequence[float] = (),
) -> Figure:
    """3-D trajectories (Fig. 16): every other UAV in grey, the pairs in colour, the leader
    dashed with a star at its end. Without ``marks`` a dot marks each start and a triangle
    each end; with ``marks`` (times, needs the sample times ``t``) the whole swarm is dotted
    at the samples nearest to those times, labelled next to the leader."""
    positions = np.asarray(positions, dtype=float)
    if positions.ndim != 3 or positions.shape[-1] != 3:
        raise ValueError(f"positions has shape {positions.shape}; expected (T, N, 3) (dim = 3)")
    if len(marks) and t is None:
        raise ValueError("marks need the sample times t")
    fig = Figure(figsize=(6.4, 5.6))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    paired = {i: k for k, pr in enumerate(pairs) for i in pr}
    others = [i for i in range(positions.shape[1]) if i not in paired]
    for n, i in enumerate(others):
        xyz = positions[:, i]
        ax.plot(
            xyz[:, 0],
            xyz[:, 1],
            xyz[:, 2],
            lw=0.5,
            color=UNPAIRED_COLOR,
            alpha=0.45,
            label="other UAVs" if n == 0 else None,
        )
    for i, k in sorted(paired.items()):
        xyz = positions[:, i]
        color = PAIR_COLORS[k % len(PAIR_COLORS)]
        first = i == pairs[k][0]
        label = f"pair {k} (UAVs {pairs[k][0]}, {pairs[k][1]})" if first else None
        ax.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], lw=1.4, color=color, label=label)
    lq = np.asarray(leader_positions, dtype=float)
    if len(marks):
        t = np.asarray(t, dtype=float)
        for tm in marks:
            k = int(np.argmin(np.abs(t - tm)))
            ax.scatter(*positions[k].T, s=7, color="k", depthshade=False)
            ax.text(*(lq[k] + np.array([0.0, 0.0, 3.0])), f"{t[k]:.0f} s", fontsize=7)
    else:
        ax.scatter(*positions[0].T, s=6, color="0.3", depthshade=False)
        ax.scatter(*positions[-1].T, s=14, marker="^", color="0.1", depthshade=False)
    ax.plot(lq[:, 0], lq[:, 1], lq[:, 2], "k--", lw=1.2, label="virtual leader")
    ax.scatter(*lq[-1], marker="*", s=160, color="gold", edgecolor="k", depthshade=False)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    return fig
