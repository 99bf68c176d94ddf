"""The runs of the quadrotor experiment (Sec. VI-B): one job per (vehicle model, policy),
all seeds batched in one core, with the experiment's own series and per-seed metrics.

Per seed it measures (times in s, distances in m):

* ``band_entry_time``: first time |pair error| < 0.5 m (unlike ``band_time``, the time
  after which the pair stays in the band);
* ``straight_max_error``: max |pair error| in straight flight, [15, 20], [27, 50], [57, 65];
* ``turn_peak_error``: max |pair error| in and after the turns, [20, 27] and [50, 57];
* ``min_distance``: smallest distance between any two UAVs (partners included) at any time;
* with the config's collision ellipsoid (``collision_height`` set, as on the ``crazyflie``
  preset), the same closest pass in the ellipsoid's measure: ``min_ellipsoid_separation``,
  the smallest sqrt((dx^2 + dy^2) / collision_distance^2 + dz^2 / collision_height^2) over
  any two UAVs at any time (>= 1: no two UAVs ever inside each other's downwash ellipsoid),
  and ``ellipsoid_contact_steps``, the sampled states (one per control step, the start
  included) with some pair inside it; from the same offsets as ``min_distance``;
* ``velocity_mismatch``: max ||p_i - p_leader|| of the unpaired UAVs in [35, 50] and [60, 65]
  (the band and windows of ``paper-quadrotor``; another scenario's, e.g. the scaled
  ``crazyflie`` preset's, come from
  :func:`~baselines.experiments.quadrotor.criteria.criteria_for`);
* ``pair_offset``: mean distance of the pair's midpoint from the virtual leader in straight
  flight (where the pair flies relative to its flock, which stays centred on the leader);
* ``turn_peak_since_filter``: with the safety filter on, the time from the end of the last
  control period whose command it changed (for either paired UAV) to the turn peak (0: it
  changed the last command before the peak; NaN when it had not acted before the peak, or
  is off): whether a large turn peak is the filter's deflection or the controller's own
  tracking after it;

plus the general episode metrics of ``pairflock_env.task.metrics`` and, for the quadrotor, how
often the paired UAVs fly at the acceleration/tilt limit or saturate a motor.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from baselines.controllers import make_pair_policy
from baselines.evaluation.recording import RecordOptions, recorded_rollout
from baselines.evaluation.rollout import trace_metrics
from baselines.experiments.quadrotor.criteria import QUADROTOR, QuadrotorCriteria, criteria_for
from baselines.runtime.threads import pin_threads
from pairflock_env import make_config

__all__ = [
    "PRESET",
    "STRAIGHT_WINDOWS",
    "TURN_WINDOWS",
    "VELOCITY_WINDOWS",
    "run_job",
    "scenario_metrics",
]

PRESET = "paper-quadrotor"
#: straight flight, and the turns with the recovery after them, in s
STRAIGHT_WINDOWS = QUADROTOR.straight_windows
TURN_WINDOWS = QUADROTOR.turn_windows
VELOCITY_WINDOWS = QUADROTOR.velocity_windows


def _window_mask(t: np.ndarray, windows) -> np.ndarray:
    m = np.zeros(t.shape, bool)
    for a, b in windows:
        m |= (t >= a - 1e-9) & (t <= b + 1e-9)
    return m


def scenario_metrics(
    t: np.ndarray,
    pair_error: np.ndarray,
    min_distance: np.ndarray,
    velocity_mismatch_max: np.ndarray,
    pair_offset: np.ndarray,
    band: float | None = None,
    filter_active: np.ndarray | None = None,
    criteria: QuadrotorCriteria = QUADROTOR,
) -> dict[str, float]:
    """The Sec. VI-B figures of one run from its series (each (T,), sampled at times t;
    ``filter_active``: whether the safety filter changed a paired UAV's command at each
    sample, None without the filter), in the windows of ``criteria`` (and its band unless
    ``band`` is given)."""
    err = np.abs(pair_error)
    inside = np.flatnonzero(err < (criteria.band if band is None else band))
    straight = _window_mask(t, criteria.straight_windows)
    turns = _window_mask(t, criteria.turn_windows)
    vel = _window_mask(t, criteria.velocity_windows)
    nan = float("nan")
    since = nan
    if filter_active is not None and turns.any():
        peak = np.flatnonzero(turns)[np.argmax(err[turns])]
        acted = np.flatnonzero(filter_active[: peak + 1])
        since = float(t[peak] - t[acted[-1]]) if acted.size else nan
    return {
        "band_entry_time": float(t[inside[0]]) if inside.size else nan,
        "straight_max_error": float(err[straight].max()) if straight.any() else nan,
        "straight_mean_error": float(err[straight].mean()) if straight.any() else nan,
        "turn_peak_error": float(err[turns].max()) if turns.any() else nan,
        "min_distance": float(min_distance.min()),
        "velocity_mismatch": float(velocity_mismatch_max[vel].max()) if vel.any() else nan,
        "pair_offset": float(pair_offset[straight].mean()) if straight.any() else nan,
        "turn_peak_since_filter": since,
    }


class _Recorder:
    """``rollout`` hook: what the trace does not keep (all-UAV distance, unpaired velocity
    mismatch, quadrotor limits, and the attitude of one paired UAV of one swarm)."""

    def __init__(
        self,
        B: int,
        T: int,
        pair: tuple[int, int],
        attitude_of: tuple[int, int] | None,
        ellipsoid: tuple[float, float] | None = None,
    ) -> None:
        self.pair = pair
        # (horizontal, vertical) radii of the collision ellipsoid, or None
        self.ellipsoid = ellipsoid
        self.ellipsoid_separation = np.full((B, T + 1), np.nan) if ellipsoid else None
        self.ellipsoid_contacts = np.zeros(B, np.int64)
        self.pair_offset = np.full((B, T + 1), np.nan)
        self.min_distance = np.full((B, T + 1), np.nan)
        self.velocity_mismatch = np.full((B, T + 1), np.nan)
        self.limited_steps = np.zeros(B, np.int64)
        self.saturated_steps = np.zeros(B, np.int64)
        self.crashed = np.zeros(B, bool)
        self.filter_active: np.ndarray | None = None  # (B, T + 1), with the filter on
        self.attitude_of = attitude_of
        self.R = np.full((T + 1, 3, 3), np.nan) if attitude_of else None
        self.R_des = np.full((T + 1, 3, 3), np.nan) if attitude_of else None

    def __call__(self, k: int, core, res, live: np.ndarray) -> None:
        q = core.q
        sq = (q[:, :, None, :] - q[:, None, :, :]) ** 2
        d2 = np.sum(sq, axis=-1)
        N = q.shape[1]
        d2[:, np.arange(N), np.arange(N)] = np.inf
        self.min_distance[live, k] = np.sqrt(d2.min(axis=(1, 2)))[live]
        if self.ellipsoid is not None:  # the same offsets in the ellipsoid's measure
            h, v = self.ellipsoid
            e2 = (sq[..., 0] + sq[..., 1]) / h**2 + sq[..., 2] / v**2
            e2[:, np.arange(N), np.arange(N)] = np.inf
            e = np.sqrt(e2.min(axis=(1, 2)))
            self.ellipsoid_separation[live, k] = e[live]
            self.ellipsoid_contacts[live] += e[live] < 1.0
        self.velocity_mismatch[live, k] = res.info["velocity_mismatch_max"][live]
        if core.config.safety_filter != "none":
            if self.filter_active is None:
                self.filter_active = np.zeros(self.min_distance.shape, bool)
            if k > 0:
                self.filter_active[live, k] = res.info["safety_active"][live].any(axis=1)
        lq, _ = core.leader_state()
        mid = 0.5 * (q[:, self.pair[0]] + q[:, self.pair[1]])
        self.pair_offset[live, k] = np.linalg.norm(mid - lq, axis=-1)[live]
        if "accel_limited" in res.info and k > 0:
            self.limited_steps[live] += res.info["accel_limited"][live].any(axis=1)
            self.saturated_steps[live] += res.info["motor_saturated"][live].any(axis=1)
            self.crashed |= res.info["vehicle_terminated"] & live
        if self.attitude_of is not None and hasattr(core.vehicle, "R_des"):
            b, i = self.attitude_of
            if live[b]:
                self.R[k] = core.vehicle.R[b, i]
                self.R_des[k] = core.vehicle.R_des[b, i]

    def finish(self, ended: np.ndarray) -> None:
        """Hold each swarm's series at its last value after its episode ended."""
        for b, e in enumerate(ended):
            for arr in (self.min_distance, self.velocity_mismatch, self.pair_offset):
                arr[b, e + 1 :] = arr[b, e]
            if self.ellipsoid_separation is not None:
                self.ellipsoid_separation[b, e + 1 :] = self.ellipsoid_separation[b, e]


def _rows(
    dynamics: str, policy: str, tr, rec: _Recorder, criteria: QuadrotorCriteria = QUADROTOR
) -> list[dict[str, Any]]:
    """One row per swarm (the scenario has one pair)."""
    rows = []
    for b, g in enumerate(trace_metrics(tr)):
        sm = scenario_metrics(
            tr.t,
            tr.pair_error[b, 0],
            rec.min_distance[b],
            rec.velocity_mismatch[b],
            rec.pair_offset[b],
            filter_active=None if rec.filter_active is None else rec.filter_active[b],
            criteria=criteria,
        )
        steps = max(int(tr.ended[b]), 1)
        if rec.ellipsoid_separation is not None:  # after min_distance, as its other measure
            items = list(sm.items())
            at = 1 + [key for key, _ in items].index("min_distance")
            extra = (
                ("min_ellipsoid_separation", float(rec.ellipsoid_separation[b].min())),
                ("ellipsoid_contact_steps", int(rec.ellipsoid_contacts[b])),
            )
            sm = dict([*items[:at], *extra, *items[at:]])
        rows.append(
            {
                "dynamics": dynamics,
                "policy": policy,
                "seed": g["seed"],
                **sm,
                "pair_accel_limited_frac": 100.0 * rec.limited_steps[b] / steps,
                "pair_motor_saturated_frac": 100.0 * rec.saturated_steps[b] / steps,
                "crashed": int(rec.crashed[b]),
                **{k: v for k, v in g.items() if k not in ("seed", "pair")},
            }
        )
    return rows


def run_job(
    dynamics: str,
    policy: str,
    seeds: Sequence[int],
    overrides: dict[str, Any],
    gains: dict[str, Any],
    record: bool,
    recording: RecordOptions | None = None,
    *,
    preset: str = PRESET,
) -> dict[str, Any]:
    """One (vehicle model, policy) combination over all seeds, batched in one core: its
    rows, the series of pair 0 and, with ``record``, the first seed's states for figures;
    ``recording`` writes the runs' recordings (:mod:`baselines.evaluation.recording`);
    ``preset``: the scenario (its Sec. VI-B windows: ``criteria_for(preset)``)."""
    pin_threads()

    cfg = make_config(preset, dynamics=dynamics, **overrides)
    pol = make_pair_policy(policy, cfg, **gains.get(policy, {}))
    T = cfg.episode_steps
    attitude_of = (0, cfg.pairs[0][0]) if record else None
    ellipsoid = None
    if cfg.collision_height is not None:
        ellipsoid = (cfg.collision_distance, cfg.collision_height)
    rec = _Recorder(len(seeds), T, cfg.pairs[0], attitude_of, ellipsoid)
    kept = (0,) if record else ()
    t0 = time.perf_counter()
    tr = recorded_rollout(recording, cfg, pol, seeds, record_rows=kept, on_step=rec)
    wall = time.perf_counter() - t0
    rec.finish(tr.ended)
    out: dict[str, Any] = {
        "dynamics": dynamics,
        "policy": policy,
        "rows": _rows(dynamics, policy, tr, rec, criteria_for(preset)),
        "wall_s": wall,
        "sim_s": float(len(seeds) * T * cfg.dt),
        "t": tr.t,
        "pair_error": tr.pair_error[:, 0],
        "surface": tr.surface[:, 0],
        "config": cfg,
    }
    if record:
        out["positions"] = tr.positions[0]
        out["velocities"] = tr.velocities[0]
        out["leader_positions"] = tr.leader_positions[0]
        if rec.R is not None and np.isfinite(rec.R).all():
            out["R"], out["R_des"] = rec.R, rec.R_des
    return out
