"""The ``crazyflie`` preset flown by the analytic pair controllers, filter off and on: the
measurements behind its choices (docs/crazyflie.md, "The crazyflie preset").

    python benchmarks/crazyflie_preset.py                  # 16 seeds, both tables (minutes)
    python benchmarks/crazyflie_preset.py --seeds 4        # quicker

Table 1, per controller and filter setting over the seeds (whole 65 s episodes): crashed
swarms, the mean |pair distance - d_m| over the last 10 s (and its largest value there), the
closest approach of a paired UAV to any other UAV, the largest tilt, how far the swarm went
(largest |x|, |y|; lowest and highest z) and the share of UAV-steps with a clamped PWM or
torque.

Table 2, the flock alone (zero pair action) over [10, 30] s: the mean norm of the unpaired
UAVs' desired acceleration with the paper's velocity consensus (1) and the preset's (0.5),
for the particle, the quadrotor and the Crazyflie.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402

import numpy as np  # noqa: E402

from baselines.controllers import make_pair_policy  # noqa: E402
from pairflock_env import PairFlockCore, make_config  # noqa: E402

CONTROLLERS = ("smc", "proportional", "braking")


def episode(controller: str, seeds: list[int], **overrides) -> dict[str, float]:
    """Whole episodes of the preset for ``seeds`` (one swarm each) under ``controller``."""
    cfg = make_config("crazyflie", **overrides)
    B, M = len(seeds), 2 * cfg.n_pairs
    core = PairFlockCore(cfg, num_swarms=B)
    pol = make_pair_policy(controller, cfg)
    res = core.reset(seed=seeds)
    veh, tail = core.vehicle, round(10.0 / cfg.dt)
    err, sep, tilt, sat = [], np.inf, 0.0, 0
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for _ in range(cfg.episode_steps):
        a, _ = pol.predict(res.obs.reshape(B * M, -1))
        res = core.step(a.reshape(B, M, -1))
        q = core.q
        err.append(np.abs(np.linalg.norm(q[:, 0] - q[:, 1], axis=-1) - cfg.d_m[0]))
        d = np.linalg.norm(q[:, :2, None] - q[:, None], axis=-1)
        d[:, 0, 0] = d[:, 1, 1] = np.inf
        sep, tilt = min(sep, float(d.min())), max(tilt, float(veh.tilt().max()))
        lo, hi = np.minimum(lo, q.min(axis=(0, 1))), np.maximum(hi, q.max(axis=(0, 1)))
        sat += int(veh.motor_saturated.sum())
    last = np.array(err[-tail:])
    return {
        "crashed": int(veh.crashed.any(axis=1).sum()),
        "error": float(last.mean()),
        "error_max": float(last.max()),
        "separation": sep,
        "tilt": tilt,
        "xy": float(max(-lo[0], hi[0], -lo[1], hi[1])),
        "z": (float(lo[2]), float(hi[2])),
        "saturated": sat / (cfg.episode_steps * B * cfg.n_uavs),
    }


def controllers_table(seeds: list[int]) -> None:
    print(f"Seeds {seeds[0]}-{seeds[-1]}, whole episodes\n")
    print(
        "| controller | filter | crashed | pair error, last 10 s: mean (max) (m) | closest "
        "pair-other (m) | max tilt (deg) | max abs x, y (m) | z range (m) | saturated |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for c in CONTROLLERS:
        for f in ("none", "cbf"):
            r = episode(c, seeds, safety_filter=f)
            print(
                f"| {c} | {f} | {r['crashed']} / {len(seeds)} | {r['error']:.3f} "
                f"({r['error_max']:.3f}) | {r['separation']:.3f} | {r['tilt']:.1f} | "
                f"{r['xy']:.2f} | {r['z'][0]:.2f}-{r['z'][1]:.2f} | {r['saturated']:.1%} |"
            )


def flock_activity(dynamics: str, consensus: float, seeds: list[int]) -> float:
    """Mean |a_des| of the unpaired UAVs over [10, 30] s with zero pair action."""
    kw = dict(dynamics=dynamics, consensus=consensus, horizon=30.0)
    if dynamics == "quadrotor":
        kw["quad_ground_altitude"] = 0.0
    cfg = make_config("crazyflie", **kw)
    core = PairFlockCore(cfg, num_swarms=len(seeds))
    core.reset(seed=seeds)
    seen: list[np.ndarray] = []
    advance = core.vehicle.advance

    def recording(q, p, a):
        seen.append(np.linalg.norm(a[:, 2:], axis=-1).mean())
        advance(q, p, a)

    core.vehicle.advance = recording
    zero = np.zeros((len(seeds), 2 * cfg.n_pairs, 3))
    for _ in range(cfg.episode_steps):
        core.step(zero)
    return float(np.mean(seen[round(10.0 / cfg.dt) :]))


def consensus_table(seeds: list[int]) -> None:
    print("\nFlock alone: mean |a_des| of the unpaired UAVs over [10, 30] s (m/s^2)\n")
    print("| vehicle | consensus 1 (the paper's) | consensus 0.5 (the preset's) |\n|---|---|---|")
    for dyn in ("particle", "quadrotor", "crazyflie"):
        cells = [flock_activity(dyn, b, seeds) for b in (1.0, 0.5)]
        print(f"| {dyn} | {cells[0]:.3f} | {cells[1]:.3f} |")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=16, help="seeds 0..n-1")
    seeds = list(range(ap.parse_args(argv).seeds))
    controllers_table(seeds)
    consensus_table(seeds[:4])


if __name__ == "__main__":
    main()
