"""Physics invariants of the quadrotor model, measured (the tests assert the same functions).

    python -m baselines.quadrotor_invariants

* hover: every UAV level at the exact hover rotor speed, zero command, 10 s: position drift;
* SO(3): max |R^T R - I| over the 65 s paper-quadrotor scenario flown by sliding mode;
* acceleration step: a 2 m/s^2 horizontal step command from hover: time to 90 %, time to
  stay within 10 %, overshoot, and whether any rotor reached a thrust limit.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np

from baselines.controllers import make_pair_policy
from baselines.runtime.cli import ArgumentParser, at_least
from pairflock_env import PairFlockCore, make_config
from pairflock_env.dynamics.quadrotor import QuadrotorModel
from pairflock_env.math3d import orthonormality_error

__all__ = ["hover_drift", "main", "orthonormality_over_scenario", "step_response"]

PRESET = "paper-quadrotor"


def hovering_model(B: int = 1, N: int = 2, **overrides):
    """A bare quadrotor model (every UAV level, at rest, rotors at hover speed) and its state."""
    cfg = make_config(PRESET, n_uavs=N, **overrides)
    model = QuadrotorModel(cfg, B)
    q = np.zeros((B, N, 3))
    q[..., 0] = 5.0 * np.arange(N)
    q[..., 2] = 20.0
    p = np.zeros((B, N, 3))
    model.reset_rows(np.arange(B), q, p)
    return cfg, model, q, p


def hover_drift(seconds: float = 10.0, B: int = 2, N: int = 3) -> dict[str, float]:
    """Largest position and velocity drift (m, m/s) of hovering UAVs under a zero command."""
    cfg, model, q, p = hovering_model(B, N)
    q0 = q.copy()
    a = np.zeros_like(q)
    saturated = False
    for _ in range(round(seconds / cfg.dt)):
        model.advance(q, p, a)
        saturated |= bool(model.motor_saturated.any())

    return {
        "seconds": seconds,
        "position_drift_m": float(np.abs(q - q0).max()),
        "velocity_drift_mps": float(np.abs(p).max()),
        "rotor_speed_change": float(np.abs(model.rotor_speed - model.params.hover_speed).max()),
        "orthonormality_error": float(orthonormality_error(model.R).max()),
        "motor_saturated": saturated,
    }


def orthonormality_over_scenario(seed: int = 0, policy: str = "smc") -> dict[str, float]:
    """max |R^T R - I| over all UAVs and control steps of the paper scenario, and the largest
    tilt reached (deg), so that a small error is not just a vehicle that never rotated."""
    cfg = make_config(PRESET)
    core = PairFlockCore(cfg, num_swarms=1, seed=seed)
    res = core.reset()
    pol = make_pair_policy(policy, cfg)
    model = core.vehicle
    worst, max_tilt = 0.0, 0.0
    for _ in range(cfg.episode_steps):
        act, _ = pol.predict(res.obs.reshape(core.n_agents, -1))
        res = core.step(act.reshape(1, core.n_agents, 3))
        worst = max(worst, float(orthonormality_error(model.R).max()))
        max_tilt = max(max_tilt, float(model.tilt().max()))
    return {
        "sim_time_s": float(core.t[0]),
        "max_orthonormality_error": worst,
        "max_tilt_deg": max_tilt,
        "terminated": bool(res.terminated[0]),
    }


def step_response(
    direction=(1.0, 0.0), size: float = 2.0, seconds: float = 2.0, **overrides
) -> dict[str, float]:
    """Response of the horizontal acceleration (along the command) to a step of ``size``
    m/s^2 from hover, sampled every physics step (500 Hz)."""
    cfg, model, q, p = hovering_model(dt=0.002, substeps=1, **overrides)
    a = np.zeros_like(q)
    d = np.asarray(direction, dtype=float)
    a[0, 0, :2] = size * d / np.linalg.norm(d)
    n = round(seconds / cfg.dt)
    acc = np.empty(n)
    saturated = False
    for k in range(n):
        v0 = p[0, 0, :2].copy()
        model.advance(q, p, a)
        acc[k] = (p[0, 0, :2] - v0) @ a[0, 0, :2] / size / cfg.dt
        saturated |= bool(model.motor_saturated.any())
    t = cfg.dt * np.arange(1, n + 1)
    ratio = acc / size
    reached = np.flatnonzero(ratio >= 0.9)
    outside = np.flatnonzero(np.abs(ratio - 1.0) > 0.1)
    if outside.size == 0:
        settle = float(t[0])
    elif outside[-1] + 1 < n:
        settle = float(t[outside[-1] + 1])
    else:
        settle = float("nan")  # still outside at the end
    return {
        "t90_s": float(t[reached[0]]) if reached.size else float("nan"),
        "settle_10pct_s": settle,
        "overshoot": float(max(0.0, ratio.max() - 1.0)),
        "motor_saturated": saturated,
        "altitude_change_m": float(q[0, 0, 2] - 20.0),
        "t": t,
        "ratio": ratio,
    }


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python -m baselines.quadrotor_invariants``."""
    ap = ArgumentParser(
        prog="python -m baselines.quadrotor_invariants", description=__doc__.split("\n\n")[0]
    )
    ap.add_argument("--seed", type=at_least(0), default=0, help="seed of the 65 s scenario run")
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    """Measure and print the invariants; returns the exit status."""
    args = build_parser().parse_args(argv)
    h = hover_drift()
    print(
        f"hover {h['seconds']:g} s (float64): position drift {h['position_drift_m']:.3g} m, "
        f"velocity {h['velocity_drift_mps']:.3g} m/s, rotor speed change "
        f"{h['rotor_speed_change']:.3g} rad/s, |R^T R - I| {h['orthonormality_error']:.3g}"
    )
    o = orthonormality_over_scenario(args.seed)
    print(
        f"SO(3) over the {o['sim_time_s']:g} s scenario (smc, seed {args.seed}): max |R^T R - I| "
        f"= {o['max_orthonormality_error']:.3g}, largest tilt {o['max_tilt_deg']:.1f} deg"
    )
    print("2 m/s^2 horizontal acceleration step from hover:")
    for d in ((1.0, 0.0), (0.0, 1.0), (1.0, -1.0)):
        s = step_response(d)
        print(
            f"  direction {d}: 90 % at {s['t90_s']:.3f} s, within 10 % from "
            f"{s['settle_10pct_s']:.3f} s, overshoot {100 * s['overshoot']:.2f} %, motor "
            f"limit hit: {s['motor_saturated']}, altitude change {s['altitude_change_m']:+.3f} m"
        )
    return 0
