"""Episode metrics of the pair task, computed from recorded time series.

The same functions serve the paper reproduction, the benchmark CLI and the training
evaluation, so a number means the same thing everywhere. Times are in s, distances in m.
Besides the pair's metrics: the safety filter's (:func:`pair_safety_metrics`), the whole
swarm's separation (:func:`swarm_safety_metrics`) and the flock's quality
(:func:`flock_state`, :func:`flock_quality_metrics`; docs/swarm-safety.md).
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import jit_kernel
from pairflock_env.swarm.grid import NeighborGrid, within_radius

__all__ = [
    "FLOCK_METRIC_DOCS",
    "FLOCK_STATE_NAMES",
    "METRIC_DOCS",
    "SAFETY_METRIC_DOCS",
    "SWARM_SAFETY_METRIC_DOCS",
    "flock_quality_metrics",
    "flock_state",
    "pair_episode_metrics",
    "pair_safety_metrics",
    "settle_time",
    "swarm_safety_metrics",
]

#: name -> (unit, meaning) of every metric returned by :func:`pair_episode_metrics`
METRIC_DOCS: dict[str, tuple[str, str]] = {
    "s_settle_time": ("s", "first time after which |s| < 1 % of |s(0)| for good"),
    "band_time": ("s", "first time after which |pair error| < 0.5 m for good"),
    "ss_mean_error": ("m", "mean |pair error| over the last 10 s"),
    "ss_max_error": ("m", "max |pair error| over the last 10 s"),
    "min_pair_separation": ("m", "smallest distance from a paired UAV to a non-partner UAV"),
    "pair_collision_steps": ("steps", "control steps with that distance < collision_distance"),
    "peak_accel": ("m/s^2", "largest applied pair acceleration ||u|| of either member"),
    "effort": ("m^2/s^3", "integral of ||u||^2 dt, summed over both members"),
    "chattering": (
        "m/s^3",
        "total variation of u per second over the last 10 s, mean of both members",
    ),
    "peak_speed": ("m/s", "largest speed of either member"),
    "final_largest_component": ("UAVs", "largest connected component of the swarm at the end"),
    "final_velocity_mismatch": ("m/s", "mean ||p_i - p_leader|| of unpaired UAVs at the end"),
    "max_collisions": (
        "pairs",
        "most UAV pairs in collision at one time (collision_distance, collision_height)",
    ),
}


#: name -> (unit, meaning) of the safety filter's metrics (:func:`pair_safety_metrics`)
SAFETY_METRIC_DOCS: dict[str, tuple[str, str]] = {
    "closest_pass": (
        "m",
        "smallest distance from a paired UAV to any other UAV, its partner included",
    ),
    "closest_pass_ok": ("0/1", "1 if closest_pass >= safety_distance"),
    "safety_active_steps": ("steps", "agent-steps the filter changed a command for safety"),
    "safety_infeasible_steps": (
        "steps",
        "agent-steps no command within the bound met every constraint",
    ),
    "peak_correction": ("m/s^2", "largest ||u - u_nom|| the filter applied to either member"),
}


def pair_safety_metrics(
    min_separation: np.ndarray,
    pair_distance: np.ndarray,
    active_steps: np.ndarray,
    infeasible_steps: np.ndarray,
    peak_correction: np.ndarray,
    safety_distance: float,
) -> dict[str, float]:
    """Safety metrics of one pair over one episode (:data:`SAFETY_METRIC_DOCS`).

    Args:
        min_separation: nearest non-partner distance of each member (2, T).
        pair_distance: ||y|| (T,).  active_steps, infeasible_steps, peak_correction: (2,)
            per member over the episode.  safety_distance: D_s (m).
    """
    closest = float(min(np.min(min_separation), np.min(pair_distance)))
    return {
        "closest_pass": closest,
        "closest_pass_ok": int(closest >= safety_distance),
        "safety_active_steps": int(np.sum(active_steps)),
        "safety_infeasible_steps": int(np.sum(infeasible_steps)),
        "peak_correction": float(np.max(peak_correction)),
    }


def settle_time(t: np.ndarray, inside: np.ndarray) -> float:
    """First time after which ``inside`` holds for good (last sample included).

    ``t`` (T,), ``inside`` (..., T) bool. Returns ``t[k]`` for the smallest k with
    ``inside[k:]`` all true, or ``nan`` if the last sample is outside. Works on one series.
    """
    inside = np.asarray(inside, dtype=bool)
    if not inside[-1]:
        return float("nan")
    outside = np.flatnonzero(~inside)
    k = 0 if outside.size == 0 else outside[-1] + 1
    return float(t[k])


def pair_episode_metrics(
    t: np.ndarray,
    pair_error: np.ndarray,
    surface: np.ndarray,
    min_separation: np.ndarray,
    u: np.ndarray,
    speed: np.ndarray,
    largest_component: np.ndarray,
    velocity_mismatch: np.ndarray,
    collisions: np.ndarray,
    dt: float,
    collision_distance: float,
    *,
    steady_window: float = 10.0,
    band: float = 0.5,
    s_fraction: float = 0.01,
) -> dict[str, float]:
    """Metrics of one pair over one episode.

    Args:
        t: sample times (T,), t[0] = 0 (the reset state).
        pair_error: ||y|| - d_m (T,).  surface: s of eq. 26 (T,).
        min_separation: nearest non-partner distance of each member (2, T).
        u: applied pair acceleration of each member (2, T - 1, dim) (held between samples).
        speed: speed of each member (2, T).
        largest_component, velocity_mismatch, collisions: swarm series (T,).
    """
    err = np.abs(pair_error)
    s = np.abs(surface)
    steady = t >= t[-1] - steady_window + 1e-9
    un = np.linalg.norm(u, axis=-1)  # (2, T-1)
    u_steady = u[:, steady[1:]]  # u[:, k] is held over (t[k], t[k+1]]
    if u_steady.shape[1] > 1:
        tv = np.linalg.norm(np.diff(u_steady, axis=1), axis=-1).sum(axis=1)
        chatter = float(np.mean(tv) / (dt * (u_steady.shape[1] - 1)))
    else:
        chatter = 0.0
    sep = min_separation.min(axis=0)
    return {
        "s_settle_time": settle_time(t, s < s_fraction * max(s[0], 1e-12)),
        "band_time": settle_time(t, err < band),
        "ss_mean_error": float(err[steady].mean()),
        "ss_max_error": float(err[steady].max()),
        "min_pair_separation": float(sep.min()),
        "pair_collision_steps": int(np.sum(sep < collision_distance)),
        "peak_accel": float(un.max()) if un.size else 0.0,
        "effort": float(np.sum(un**2) * dt),
        "chattering": chatter,
        "peak_speed": float(speed.max()),
        "final_largest_component": int(largest_component[-1]),
        "final_velocity_mismatch": float(velocity_mismatch[-1]),
        "max_collisions": int(collisions.max()),
    }


#: name -> (unit, meaning) of the whole swarm's separation (:func:`swarm_safety_metrics`)
SWARM_SAFETY_METRIC_DOCS: dict[str, tuple[str, str]] = {
    "swarm_closest": ("m", "smallest distance between any two UAVs of the swarm over the episode"),
    "swarm_steps_below": ("steps", "control steps with two UAVs closer than safety_distance"),
    "swarm_active_uav_steps": (
        "UAV-steps",
        "UAV-steps on which the safety stage changed a command for safety",
    ),
    "swarm_infeasible_uav_steps": (
        "UAV-steps",
        "UAV-steps on which no command met every constraint (the max-margin one was applied)",
    ),
    "swarm_infeasible_steps": ("steps", "control steps with at least one infeasible UAV"),
}

#: what :func:`flock_state` returns, in order (the unpaired UAVs; all UAVs if none)
FLOCK_STATE_NAMES = ("flock_gyration", "flock_tracking", "flock_lattice_deviation")

#: name -> (unit, meaning) of the flock's quality over the steady window
#: (:func:`flock_quality_metrics`)
FLOCK_METRIC_DOCS: dict[str, tuple[str, str]] = {
    "flock_gyration": (
        "m",
        "cohesion: RMS distance of the unpaired UAVs from their centroid (steady-window mean)",
    ),
    "flock_velocity_mismatch": (
        "m/s",
        "mean ||p_i - p_leader|| of the unpaired UAVs (steady-window mean)",
    ),
    "flock_tracking": (
        "m",
        "distance of the unpaired UAVs' centroid from the leader (steady mean)",
    ),
    "flock_lattice_deviation": (
        "m^2",
        "Olfati-Saber's deviation energy: sum over UAV pairs within radius of (|q_ij| - "
        "spacing)^2, over (edges + 1) (steady-window mean)",
    ),
    "flock_min_component": (
        "UAVs",
        "smallest largest connected component (UAVs within radius) over the steady window",
    ),
}


def swarm_safety_metrics(
    separation: np.ndarray, active: np.ndarray, infeasible: np.ndarray, safety_distance: float
) -> dict[str, float]:
    """The whole swarm's separation over one episode (:data:`SWARM_SAFETY_METRIC_DOCS`).

    Args:
        separation: the closest two UAVs at every sample (T + 1,) (``swarm_min_separation``).
        active, infeasible: UAVs counted per step (T,) (``swarm_filter_active``,
            ``swarm_filter_infeasible``).  safety_distance: D_s (m).
    """
    return {
        "swarm_closest": float(np.min(separation)),
        "swarm_steps_below": int(np.sum(separation < safety_distance)),
        "swarm_active_uav_steps": int(np.sum(active)),
        "swarm_infeasible_uav_steps": int(np.sum(infeasible)),
        "swarm_infeasible_steps": int(np.count_nonzero(infeasible)),
    }


@jit_kernel
def _edges_grid(q, b, r2, spacing, g, hits, pt):
    """(edges, sum of (|q_ij| - spacing)^2) over the UAV pairs of swarm b closer than
    sqrt(r2), each once, from the grid ``g``."""
    n, total = 0, 0.0
    for i in range(q.shape[1]):
        for k in range(q.shape[2]):
            pt[k] = q[b, i, k]
        for t in range(within_radius(q, b, pt, r2, i, g, hits)):
            j = hits[t]
            if j > i:
                d2 = 0.0
                for k in range(q.shape[2]):
                    d2 += (q[b, j, k] - pt[k]) ** 2
                n += 1
                total += (np.sqrt(d2) - spacing) ** 2
    return n, total


def _edges(q: np.ndarray, b: int, radius: float, spacing: float, grid: NeighborGrid | None):
    if grid is not None and grid.ok[b]:
        hits = np.empty(q.shape[1], np.int64)
        return _edges_grid(q, b, radius * radius, spacing, grid.arrays, hits, np.zeros(3))
    x = q[b]
    d = np.sqrt(((x[:, None] - x[None]) ** 2).sum(-1))[np.triu_indices(len(x), 1)]
    d = d[d < radius]
    return d.size, float(((d - spacing) ** 2).sum())


def flock_state(
    q: np.ndarray,
    b: int,
    leader_q: np.ndarray,
    unpaired: np.ndarray,
    radius: float,
    spacing: float,
    grid: NeighborGrid | None = None,
) -> tuple[float, float, float]:
    """Swarm b's flock in one state (:data:`FLOCK_STATE_NAMES`): the radius of gyration and
    the leader tracking error of the unpaired UAVs (``unpaired`` (N,) bool; all UAVs when
    none is unpaired), and the lattice deviation energy of Olfati-Saber (IEEE TAC 2006) over
    all UAV pairs closer than ``radius``.

    Args:
        q: positions (B, N, dim); leader_q: the leader's position (dim,).
        grid: optionally a :class:`~pairflock_env.swarm.grid.NeighborGrid` built from ``q``
            with cells of at least ``radius`` (O(N) instead of O(N^2)).
    """
    x = q[b, unpaired] if unpaired.any() else q[b]
    c = x.mean(axis=0)
    rg = float(np.sqrt(((x - c) ** 2).sum(axis=1).mean()))
    n, total = _edges(q, b, radius, spacing, grid)
    return rg, float(np.linalg.norm(c - leader_q)), total / (n + 1)


def flock_quality_metrics(
    t_samples: np.ndarray,
    states: np.ndarray,
    t: np.ndarray,
    velocity_mismatch: np.ndarray,
    largest_component: np.ndarray,
    *,
    steady_window: float = 10.0,
) -> dict[str, float]:
    """The flock's quality over the steady window (:data:`FLOCK_METRIC_DOCS`).

    Args:
        t_samples: times (S,) of the :func:`flock_state` samples ``states`` (S, 3).
        t: step times (T + 1,) of the series ``velocity_mismatch`` and
            ``largest_component`` (T + 1,).
    """
    end = t[-1] - steady_window + 1e-9
    s = t_samples >= end
    means = states[s].mean(axis=0) if s.any() else np.full(len(FLOCK_STATE_NAMES), np.nan)
    k = t >= end
    out = {name: float(v) for name, v in zip(FLOCK_STATE_NAMES, means, strict=True)}
    out["flock_velocity_mismatch"] = float(np.mean(velocity_mismatch[k]))
    out["flock_min_component"] = int(np.min(largest_component[k]))
    return {name: out[name] for name in FLOCK_METRIC_DOCS}
