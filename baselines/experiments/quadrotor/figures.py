"""Figures of the quadrotor experiment in the style of Figs. 15-20 (headless, Agg canvas).

Each ``*_figure`` function returns a matplotlib ``Figure``; :func:`figure_set` draws and
writes the experiment's whole set (with :func:`baselines.reporting.figures.save_figure`).
The 3-D trajectories and the sliding surface use :mod:`baselines.reporting.figures`, as the
benchmark does.
Swarm snapshots reuse ``pairflock_env.render.draw_swarm`` (triangles along the heading, the
pair circled with radius d_m, the leader as a star).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from baselines.reporting.figures import save_figure, surface_panels_figure, trajectories_3d_figure
from pairflock_env.math3d import euler_zyx
from pairflock_env.render import draw_swarm

__all__ = [
    "euler_figure",
    "figure_set",
    "pair_error_figure",
    "snapshots_figure",
]

_STYLE = {
    ("quadrotor", "smc"): dict(color="tab:red", label="quadrotor, sliding mode"),
    ("quadrotor", "proportional"): dict(color="tab:blue", label="quadrotor, normal method"),
    ("quadrotor", "zero"): dict(color="0.45", label="quadrotor, no pair term"),
    ("particle", "smc"): dict(color="tab:orange", ls="--", label="particle, sliding mode"),
    ("particle", "proportional"): dict(color="tab:cyan", ls="--", label="particle, normal method"),
    ("particle", "zero"): dict(color="0.7", ls="--", label="particle, no pair term"),
}


def _nearest(t: np.ndarray, ti: float) -> int:
    return int(np.argmin(np.abs(np.asarray(t) - ti)))


def snapshots_figure(
    t, positions, velocities, leader_positions, pairs, d_m, times: Sequence[float], title: str
) -> Figure:
    """Positions and headings (x-y plane) at several times (Fig. 15), one panel each, with
    the mean altitude in the panel title and velocity arrows (1 m/s = 0.4 m) on the last."""
    n = len(times)
    cols = min(n, 4)
    rows = int(np.ceil(n / cols))
    fig = Figure(figsize=(3.6 * cols, 3.6 * rows))
    headings = None
    for i, ti in enumerate(times):
        k = _nearest(t, ti)
        ax = fig.add_subplot(rows, cols, i + 1)
        q, p = positions[k], velocities[k]
        headings = draw_swarm(
            ax,
            q,
            p,
            pairs,
            d_m,
            leader_positions[k],
            headings=headings,
            size=0.8,
            title=f"t = {t[k]:.0f} s, z = {q[:, 2].mean():.1f} m",
        )
        if i == n - 1:
            ax.quiver(
                q[:, 0],
                q[:, 1],
                p[:, 0],
                p[:, 1],
                color="0.3",
                width=0.004,
                angles="xy",
                scale_units="xy",
                scale=2.5,
            )
        ax.tick_params(labelsize=7)
        ax.xaxis.label.set_size(8)
        ax.yaxis.label.set_size(8)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def pair_error_figure(
    curves: Mapping[tuple[str, str], tuple[np.ndarray, np.ndarray]],
    straight_windows,
    band: float,
    title: str,
) -> Figure:
    """Pair distance error over time (Fig. 18): the whole run on a symlog axis, and from 5 s
    on a linear axis with the straight-flight windows shaded and the +-band lines."""
    fig = Figure(figsize=(12.0, 4.0))
    ax1 = fig.add_subplot(1, 2, 1)
    ax2 = fig.add_subplot(1, 2, 2)
    rank = {"smc": 0, "proportional": 1, "zero": 2}
    order = sorted(curves, key=lambda k: (k[0] != "quadrotor", rank.get(k[1], 3), k[1]))
    for key in order:
        t, e = curves[key]
        st = _STYLE.get(key, dict(label=f"{key[0]}, {key[1]}"))
        for ax in (ax1, ax2):
            ax.plot(t, e, lw=0.9, color=st.get("color"), ls=st.get("ls", "-"), label=st["label"])
    ax1.set_yscale("symlog", linthresh=0.5)
    ax1.set_title("whole run", fontsize=9)
    t_end = max(float(c[0][-1]) for c in curves.values())
    ax2.set_xlim(5.0, t_end)
    ax2.set_ylim(-1.2, 1.2)
    for a, b in straight_windows:
        ax2.axvspan(a, b, color="tab:green", alpha=0.08, lw=0)
    ax2.set_title(
        "from 5 s (shaded: straight flight, where |error| <= 0.5 m is required)", fontsize=9
    )
    for ax in (ax1, ax2):
        ax.axhline(0.0, color="k", lw=0.6)
        for b in (-band, band):
            ax.axhline(b, color="0.5", lw=0.7, ls=":")
        ax.set_xlabel("time (s)")
        ax.set_ylabel(r"$\|y\| - d_m$ (m)")
        ax.grid(True, lw=0.3)
    ax1.legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def euler_figure(t, R_des, R, title: str, zoom: tuple[float, float] = (0.0, 10.0)) -> Figure:
    """Euler angles (ZYX roll, pitch, yaw, degrees) commanded by the position loop (Fig. 19)
    next to the actual ones (Fig. 20): the whole run on the left, a zoom on the right."""
    cmd = np.degrees(euler_zyx(R_des))
    act = np.degrees(euler_zyx(R))
    names = ("roll", "pitch", "yaw")
    fig = Figure(figsize=(12.0, 7.0))
    zm = (t >= zoom[0]) & (t <= zoom[1])
    for i, name in enumerate(names):
        for j, sel in enumerate((slice(None), zm)):
            ax = fig.add_subplot(3, 2, 2 * i + j + 1)
            ax.plot(t[sel], cmd[sel, i], lw=0.8, color="tab:orange", label="command")
            ax.plot(t[sel], act[sel, i], lw=0.8, color="tab:blue", label="actual")
            ax.set_ylabel(f"{name} (deg)")
            ax.grid(True, lw=0.3)
            if i == 0:
                ax.set_title("whole run" if j == 0 else f"{zoom[0]:g}-{zoom[1]:g} s", fontsize=9)
                ax.legend(fontsize=8, loc="upper right")
            if i == 2:
                ax.set_xlabel("time (s)")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- the figure set
def _recorded_figures(key, job, seed, out: Path, dpi: int) -> list[Path]:
    """Snapshots and 3-D trajectories of the recorded run of ``job`` (the main combination)."""
    cfg = job["config"]
    times = [0.0, 4.0, 8.0, 20.0, 21.0, 35.0, 51.0, float(job["t"][-1])]
    fig = snapshots_figure(
        job["t"],
        job["positions"],
        job["velocities"],
        job["leader_positions"],
        cfg.pairs,
        cfg.d_m,
        times,
        f"10 quadrotors, sliding mode: positions and headings (seed {seed})",
    )
    paths = [save_figure(fig, out / "snapshots.png", dpi=dpi)]
    fig = trajectories_3d_figure(
        job["positions"],
        job["leader_positions"],
        cfg.pairs,
        f"3-D trajectories, {key[0]}, sliding mode (seed {seed})",
        t=job["t"],
        marks=(0.0, 20.0, 35.0, 50.0),
    )
    paths.append(save_figure(fig, out / "trajectories_3d.png", dpi=dpi))
    return paths


def figure_set(
    jobs: Mapping[tuple[str, str], Mapping[str, Any]],
    out: Path,
    dpi: int,
    straight_windows: Sequence[tuple[float, float]],
    band: float,
) -> list[Path]:
    """The experiment's PNGs from its job results (``(dynamics, policy) -> run_job(...)``):
    snapshots, 3-D trajectories, sliding surface, pair error and Euler angles."""
    main_key = ("quadrotor", "smc") if ("quadrotor", "smc") in jobs else next(iter(jobs))
    j = jobs[main_key]
    seed = j["rows"][0]["seed"]
    paths = _recorded_figures(main_key, j, seed, out, dpi) if "positions" in j else []
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
    title = f"Pair distance error ||y|| - d_m (seed {seed})"
    fig = pair_error_figure(curves, straight_windows, band, title)
    paths.append(save_figure(fig, out / "pair_error.png", dpi=dpi))
    if "R" in j:
        fig = euler_figure(
            j["t"],
            j["R_des"],
            j["R"],
            f"Paired UAV No. 1, sliding mode: attitude commands (Fig. 19) "
            f"and response (Fig. 20), seed {seed}",
        )
        paths.append(save_figure(fig, out / "euler_angles.png", dpi=dpi))
    return paths
