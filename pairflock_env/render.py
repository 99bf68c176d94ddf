"""Paper-style swarm pictures with matplotlib, headless by default.

UAVs are triangles pointing along their velocity (Figs. 4-15), paired UAVs are drawn in
colour inside a circle of radius d_m around the pair's midpoint, and the virtual leader is a
star. ``rgb_array`` frames are drawn on an off-screen Agg canvas, so no display is needed;
``human`` mode opens a pyplot window when an interactive backend is available.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

__all__ = [
    "PAIR_COLORS",
    "SwarmArtists",
    "SwarmRenderer",
    "draw_swarm",
    "fit_limits",
    "triangle_markers",
]

PAIR_COLORS = ("tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown")
UNPAIRED_COLOR = "0.35"
#: fixed margins of an rgb_array frame (pixels)
FRAME_MARGIN_PX = {"left": 70, "right": 20, "bottom": 55, "top": 50}
#: velocity arrows (Figs. 5, 9, 12): the 90th-percentile speed is drawn this fraction of the view
ARROW_FRACTION = 0.08
#: up to this many UAVs markers and arrows keep their size; a larger swarm spreads over more
#: of the view, so both shrink as sqrt(CROWD_UAVS / N) and the picture stays legible
CROWD_UAVS = 100


def crowd_scale(n_uavs: int) -> float:
    """Marker and arrow scale for a picture of ``n_uavs`` UAVs (1 up to CROWD_UAVS)."""
    return min(1.0, math.sqrt(CROWD_UAVS / max(n_uavs, 1)))


def triangle_markers(xy: np.ndarray, heading: np.ndarray, size: float) -> np.ndarray:
    """Vertices (n, 3, 2) of isosceles triangles at ``xy`` (n, 2) pointing along ``heading``
    (n,) radians; ``size`` is the triangle's length in data units."""
    c, s = np.cos(heading), np.sin(heading)
    local = np.array([[0.6, 0.0], [-0.4, 0.3], [-0.4, -0.3]]) * size  # tip first
    rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (n, 2, 2)
    return xy[:, None, :] + np.einsum("nij,vj->nvi", rot, local)


def _headings(p: np.ndarray, prev: np.ndarray | None) -> np.ndarray:
    speed = np.linalg.norm(p[:, :2], axis=1)
    h = np.arctan2(p[:, 1], p[:, 0])
    if prev is not None:
        h = np.where(speed > 1e-6, h, prev)
    else:
        h = np.where(speed > 1e-6, h, math.pi / 2)
    return h


def fit_limits(
    q: np.ndarray, leader_q: np.ndarray | None = None, min_span: float = 10.0
) -> tuple[float, float, float, float]:
    """Square x-y view (xmin, xmax, ymin, ymax) around every UAV and the leader, with a
    margin; never narrower than ``min_span`` metres."""
    xy = np.asarray(q, dtype=float)[:, :2]
    pts = xy if leader_q is None else np.vstack([xy, np.asarray(leader_q, dtype=float)[None, :2]])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = max(float(np.max(hi - lo)), min_span)
    mid = (lo + hi) / 2
    half = 0.55 * span + 2.0
    return (mid[0] - half, mid[0] + half, mid[1] - half, mid[1] + half)


class SwarmArtists:
    """The artists of one swarm picture on an Axes, created once and moved by :meth:`update`.

    A video redraws the same picture hundreds of times; moving existing artists avoids
    rebuilding the axes (ticks, labels) for every frame. :func:`draw_swarm` uses it for a
    single picture, so both draw exactly the same thing.
    """

    def __init__(self, ax, n_uavs: int, pairs, d_m, *, leader: bool = True) -> None:
        from matplotlib.collections import PolyCollection
        from matplotlib.patches import Circle

        self.ax = ax
        self.pairs = tuple(tuple(int(i) for i in pr) for pr in pairs)
        self.d_m = np.broadcast_to(np.asarray(d_m, dtype=float), (len(self.pairs),))
        colors = [UNPAIRED_COLOR] * n_uavs
        for k, (a, b) in enumerate(self.pairs):
            colors[a] = colors[b] = PAIR_COLORS[k % len(PAIR_COLORS)]
        # a crowded picture draws the paired UAVs last (on top) and at the uncrowded size
        self._crowd = crowd_scale(n_uavs)
        self._paired = np.asarray(self.pairs, dtype=np.int64).reshape(-1)
        self._order = np.arange(n_uavs)
        if self._crowd < 1.0:
            rest = np.setdiff1d(self._order, self._paired)
            self._order = np.concatenate([rest, self._paired])
        self.triangles = PolyCollection(
            np.zeros((n_uavs, 3, 2)),
            facecolors=[colors[i] for i in self._order],
            edgecolors="k",
            linewidths=0.3 * self._crowd,
        )
        ax.add_collection(self.triangles, autolim=False)
        # per pair: one circle around the converged pair (the paper's marker), or one around
        # each member while they are still apart
        self.circles = []
        for k in range(len(self.pairs)):
            color = PAIR_COLORS[k % len(PAIR_COLORS)]
            trio = [
                Circle((0.0, 0.0), self.d_m[k], fill=False, lw=1.2, color=color) for _ in range(3)
            ]
            for c in trio:
                ax.add_patch(c)
            self.circles.append(trio)
        self.leader = None
        if leader:
            (self.leader,) = ax.plot(
                [],
                [],
                marker="*",
                ms=14,
                color="gold",
                mec="k",
                mew=0.8,
                ls="none",
                label="virtual leader",
            )
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.grid(True, lw=0.3, alpha=0.5)
        self.title = ax.set_title("", fontsize=10)

    def update(
        self,
        q: np.ndarray,
        p: np.ndarray,
        leader_q: np.ndarray | None = None,
        *,
        headings: np.ndarray | None = None,
        size: float | None = None,
        limits: tuple[float, float, float, float] | None = None,
        title: str | None = None,
    ) -> np.ndarray:
        """Move the picture to state q, p (N, dim) (x-y plane); arguments as in
        :func:`draw_swarm`. Returns the headings used."""
        q = np.asarray(q, dtype=float)
        p = np.asarray(p, dtype=float)
        xy = q[:, :2]
        if limits is None:
            limits = fit_limits(q, leader_q)
        span = max(limits[1] - limits[0], limits[3] - limits[2])
        if size is None:
            size = 0.025 * span * crowd_scale(len(q))
        h = _headings(p, headings)
        verts = triangle_markers(xy, h, size)
        if self._crowd < 1.0:
            pr = self._paired
            verts[pr] = triangle_markers(xy[pr], h[pr], size / self._crowd)
        self.triangles.set_verts(verts[self._order])
        for k, (a, b) in enumerate(self.pairs):
            together, ca, cb = self.circles[k]
            close = bool(np.linalg.norm(xy[a] - xy[b]) <= 2 * self.d_m[k])
            together.set_visible(close)
            ca.set_visible(not close)
            cb.set_visible(not close)
            together.center = tuple((xy[a] + xy[b]) / 2)
            ca.center, cb.center = tuple(xy[a]), tuple(xy[b])
        if self.leader is not None:
            if leader_q is None:
                self.leader.set_data([], [])
            else:
                lq = np.asarray(leader_q, dtype=float)
                self.leader.set_data([lq[0]], [lq[1]])
        self.ax.set_xlim(limits[0], limits[1])
        self.ax.set_ylim(limits[2], limits[3])
        self.title.set_text(title or "")
        return h


def draw_swarm(
    ax,
    q: np.ndarray,
    p: np.ndarray,
    pairs,
    d_m,
    leader_q: np.ndarray | None = None,
    *,
    headings: np.ndarray | None = None,
    size: float | None = None,
    arrows: bool = False,
    limits: tuple[float, float, float, float] | None = None,
    title: str | None = None,
) -> np.ndarray:
    """Draw one swarm snapshot (x-y plane) on a matplotlib Axes; returns the headings used.

    Args:
        q, p: positions and velocities (N, dim); only x and y are drawn.
        pairs: sequence of (A, B) UAV indices; d_m: one distance per pair.
        leader_q: leader position (dim,) or None.
        headings: previous headings, kept for UAVs at rest.
        size: triangle length in data units (default: 2.5 % of the view, times
            :func:`crowd_scale` for swarms of more than CROWD_UAVS).
        arrows: draw velocity arrows (Figs. 5, 9, 12), length proportional to speed.
        limits: (xmin, xmax, ymin, ymax); default fits every UAV and the leader.
    """
    q = np.asarray(q, dtype=float)
    p = np.asarray(p, dtype=float)
    if limits is None:
        limits = fit_limits(q, leader_q)
    art = SwarmArtists(ax, len(q), pairs, d_m, leader=leader_q is not None)
    h = art.update(q, p, leader_q, headings=headings, size=size, limits=limits, title=title)
    span = max(limits[1] - limits[0], limits[3] - limits[2])
    speed = np.linalg.norm(p[:, :2], axis=1)
    ref = float(np.percentile(speed, 90)) if len(q) else 0.0
    if arrows and ref > 0:
        # arrow length proportional to speed; most arrows at most ARROW_FRACTION of the view
        ax.quiver(
            q[:, 0],
            q[:, 1],
            p[:, 0],
            p[:, 1],
            color="0.5",
            width=0.002,
            angles="xy",
            scale_units="xy",
            scale=ref / (ARROW_FRACTION * crowd_scale(len(q)) * span),
        )
    return h


class SwarmRenderer:
    """Renders one swarm of a core as an RGB array or in a pyplot window."""

    def __init__(self, pairs, d_m, render_mode: str | None, size_px: tuple[int, int] = (640, 640)):
        self.pairs = tuple(pairs)
        self.d_m = d_m
        self.render_mode = render_mode
        self.size_px = size_px
        self._headings: np.ndarray | None = None
        self._fig = None
        self._canvas = None
        self._artists: SwarmArtists | None = None
        self._window = None
        self._window_artists: SwarmArtists | None = None

    def reset(self) -> None:
        self._headings = None

    def _frame(self, n_uavs: int, leader: bool) -> SwarmArtists:
        """The off-screen frame, built once with fixed pixel margins: rebuilding the axes
        and a tight layout for every frame would cost more than drawing the swarm."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        art = self._artists
        if (
            art is None
            or len(art.triangles.get_paths()) != n_uavs
            or ((art.leader is not None) != leader)
        ):
            dpi = 100
            w, h = self.size_px
            self._fig = Figure(figsize=(w / dpi, h / dpi), dpi=dpi)
            self._canvas = FigureCanvasAgg(self._fig)
            self._fig.subplots_adjust(
                left=FRAME_MARGIN_PX["left"] / w,
                right=1 - FRAME_MARGIN_PX["right"] / w,
                bottom=FRAME_MARGIN_PX["bottom"] / h,
                top=1 - FRAME_MARGIN_PX["top"] / h,
            )
            ax = self._fig.add_subplot(1, 1, 1)
            self._artists = SwarmArtists(ax, n_uavs, self.pairs, self.d_m, leader=leader)
        return self._artists

    def rgb_array(self, q, p, leader_q, title: str | None = None, *, limits=None) -> np.ndarray:
        """One frame (H, W, 3) uint8 of swarm state q, p (N, dim); ``limits`` as in
        :func:`draw_swarm` (default: fit this frame)."""
        art = self._frame(len(q), leader_q is not None)
        self._headings = art.update(
            q, p, leader_q, headings=self._headings, title=title, limits=limits
        )
        self._canvas.draw()
        return np.asarray(self._canvas.buffer_rgba())[..., :3].copy()

    def human(self, q, p, leader_q, title: str | None = None, *, limits=None) -> None:
        import matplotlib
        import matplotlib.pyplot as plt

        backend = matplotlib.get_backend().lower()
        if "agg" in backend or backend in ("pdf", "svg", "ps", "cairo", "template"):
            if self._window is None:
                warnings.warn(
                    f'render_mode="human" needs an interactive matplotlib backend (current: '
                    f'{backend}); nothing is shown. Use render_mode="rgb_array" when headless.',
                    stacklevel=3,
                )
                self._window = False
            return
        if not self._window or not plt.fignum_exists(self._window.number):
            self._window = plt.figure(figsize=(6.4, 6.4))
            self._window_artists = SwarmArtists(
                self._window.add_subplot(1, 1, 1), len(q), self.pairs, self.d_m, leader=True
            )
        self._headings = self._window_artists.update(
            q, p, leader_q, headings=self._headings, title=title, limits=limits
        )
        self._window.canvas.draw_idle()
        plt.pause(0.001)

    def close(self) -> None:
        if self._window:
            import matplotlib.pyplot as plt

            plt.close(self._window)
        self._window = self._window_artists = None
        self._fig = self._canvas = self._artists = None
