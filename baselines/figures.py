"""Paper-style figures (Figs. 4-14) from rollout traces; headless (Agg canvas, no display)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from pairflock_env.render import PAIR_COLORS, draw_swarm

from .io import atomic_write_bytes

__all__ = ["save_figure", "snapshot_figure", "surface_figure", "error_figure", "POLICY_STYLE"]

POLICY_STYLE = {
    "smc": dict(color="tab:red", label="sliding mode (eq. 28)"),
    "proportional": dict(color="tab:blue", label="normal method (eq. 44)"),
    "zero": dict(color="0.4", label="no pair term"),
}


def _style(policy: str) -> dict:
    return POLICY_STYLE.get(policy, dict(label=policy))


def save_figure(fig: Figure, path: str | Path, dpi: int = 110) -> Path:
    """Render ``fig`` to PNG and write it atomically."""
    import io

    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    return atomic_write_bytes(Path(path), buf.getvalue())


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
    velocity arrows like Figs. 5, 9, 12."""
    n = len(times)
    cols = min(n, 2 if n == 4 else 3)
    rows = int(np.ceil(n / cols))
    fig = Figure(figsize=(4.2 * cols, 4.0 * rows))
    headings = None
    last = len(t) - 1
    for i, ti in enumerate(times):
        k = min(int(round(ti / (t[1] - t[0]))), last)
        ax = fig.add_subplot(rows, cols, i + 1)
        headings = draw_swarm(
            ax, positions[k], velocities[k], pairs, d_m, leader_positions[k],
            headings=headings, arrows=(i == n - 1), title=f"t = {t[k]:.1f} s",
        )  # fmt: skip
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def surface_figure(series: Mapping[str, tuple[np.ndarray, np.ndarray]], t_max: float, title: str) -> Figure:
    """Sliding surface s(t) (Figs. 6, 13): one line per label, symlog axis."""
    fig = Figure(figsize=(6.4, 3.8))
    ax = fig.add_subplot(1, 1, 1)
    for i, (label, (t, s)) in enumerate(series.items()):
        m = t <= t_max
        ax.plot(t[m], s[m], lw=1.2, label=label, color=PAIR_COLORS[i % len(PAIR_COLORS)])
    ax.set_yscale("symlog", linthresh=10.0)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("s (m$^2$/s)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def error_figure(
    panels: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]]], title: str
) -> Figure:
    """Pair distance error ||y|| - d_m over time, several policies per panel (Fig. 10).

    ``panels``: panel title -> policy -> (t, error). Symlog axis: the error starts near
    250 m and ends near 0.1 m.
    """
    n = len(panels)
    fig = Figure(figsize=(5.2 * n, 3.8))
    for i, (ptitle, curves) in enumerate(panels.items()):
        ax = fig.add_subplot(1, n, i + 1)
        for policy, (t, e) in curves.items():
            st = _style(policy)
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
    fig.suptitle(title)
    fig.tight_layout()
    return fig
