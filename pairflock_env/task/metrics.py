"""Episode metrics of the pair task, computed from recorded time series.

The same functions serve the paper reproduction, the benchmark CLI and the training
evaluation, so a number means the same thing everywhere. Times are in s, distances in m.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "METRIC_DOCS",
    "SAFETY_METRIC_DOCS",
    "pair_episode_metrics",
    "pair_safety_metrics",
    "settle_time",
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
    "max_collisions": ("pairs", "most UAV pairs closer than collision_distance at one time"),
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
