"""Named benchmark suites (defaults of a run) and the grid shortcut options."""

from __future__ import annotations

import dataclasses
from typing import Any

__all__ = ["SHORTCUTS", "SUITES", "Suite"]


@dataclasses.dataclass(frozen=True)
class Suite:
    """Defaults of a named benchmark (every field can be overridden on the command line)."""

    description: str
    preset: str
    policies: tuple[str, ...]
    seeds: int
    base: tuple[tuple[str, Any], ...] = ()
    grid: tuple[tuple[str, tuple[Any, ...]], ...] = ()
    scenarios: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...] = ()
    check: bool = False
    snapshots: bool = True
    first_seed: int = 0


#: no filter, the pair filter, the swarm layer (docs/swarm-safety.md)
SWARM_LAYERS = (
    ("off", ()),
    ("pairs", (("safety_filter", "cbf"),)),
    ("swarm", (("safety_filter", "cbf"), ("safety_scope", "swarm"))),
)
#: the held-out seeds of the swarm layer's suites (never used to choose its parameters)
SWARM_SEEDS = 72000

SUITES: dict[str, Suite] = {
    "paper": Suite(
        "Sec. VI-A: sliding mode vs the normal method vs no pair term, N = 20/50/100, "
        "10 seeds, with the acceptance checks",
        preset="paper",
        policies=("smc", "proportional", "zero"),
        seeds=10,
        grid=(("n_uavs", (20, 50, 100)),),
        check=True,
    ),
    "robustness": Suite(
        "what the proofs assume away, N = 50, 10 seeds: sensor noise on y and y', partner "
        "delay, random acceleration disturbance",
        preset="paper",
        policies=("smc", "proportional"),
        seeds=10,
        base=(("n_uavs", 50),),
        scenarios=(
            ("nominal", ()),
            ("noise y 0.3 m", (("obs_noise_position", 0.3),)),
            ("noise y 1 m", (("obs_noise_position", 1.0),)),
            ("noise y 3 m", (("obs_noise_position", 3.0),)),
            ("noise y' 1 m/s", (("obs_noise_velocity", 1.0),)),
            ("noise y' 3 m/s", (("obs_noise_velocity", 3.0),)),
            ("noise y' 10 m/s", (("obs_noise_velocity", 10.0),)),
            ("delay 3 steps", (("partner_delay", 3),)),
            ("delay 10 steps", (("partner_delay", 10),)),
            ("delay 30 steps", (("partner_delay", 30),)),
            ("disturbance 3 m/s^2", (("disturbance_std", 3.0),)),
            ("disturbance 30 m/s^2", (("disturbance_std", 30.0),)),
            ("disturbance 100 m/s^2", (("disturbance_std", 100.0),)),
        ),
        snapshots=False,
    ),
    "quick": Suite(
        "a sanity run in seconds: N = 20, 15 s, 3 seeds, smc vs proportional",
        preset="paper",
        policies=("smc", "proportional"),
        seeds=3,
        base=(("n_uavs", 20), ("horizon", 15.0)),
    ),
    "safety": Suite(
        "the CBF safety filter off vs on: N = 20/50/100 x corners/random starts x smc, "
        "proportional, the safe learned policy (sb3:pair_safe_a50), 100 held-out seeds 30000-30099",
        preset="paper",
        policies=("smc", "proportional", "sb3:pair_safe_a50"),
        seeds=100,
        first_seed=30000,
        base=(("obs_neighbors", 12),),  # what the learned policy observes
        grid=(
            ("n_uavs", (20, 50, 100)),
            ("init", ("corners", "random")),
            ("safety_filter", ("none", "cbf")),
        ),
        snapshots=False,
    ),
    "large": Suite(
        "a large swarm: 1,000 UAVs with 10 pairs drawn anywhere in the start box (preset "
        "'large', docs/large-swarms.md), sliding mode vs the normal method vs the learned "
        "policy, 3 seeds",
        preset="large",
        policies=("smc", "proportional", "sb3:pair_n20_a50"),
        seeds=3,
    ),
    "swarm-safety": Suite(
        "every UAV safe (safety_scope='swarm', docs/swarm-safety.md): N = 20/50/100 x "
        "corners/random starts x smc, proportional, braking, the safe learned policy "
        "(sb3:pair_safe_a50), no filter vs the pair filter vs the swarm layer, 100 held-out "
        "seeds 72000-72099",
        preset="paper",
        policies=("smc", "proportional", "braking", "sb3:pair_safe_a50"),
        seeds=100,
        first_seed=SWARM_SEEDS,
        base=(("obs_neighbors", 12),),  # what the learned policy observes
        grid=(("n_uavs", (20, 50, 100)), ("init", ("corners", "random"))),
        scenarios=SWARM_LAYERS,
        snapshots=False,
    ),
    "swarm-safety-large": Suite(
        "the swarm layer among 1,000 UAVs (preset 'large'): smc and the safe learned policy, "
        "no filter vs the pair filter vs the swarm layer, 20 held-out seeds 72000-72019",
        preset="large",
        policies=("smc", "sb3:pair_safe_a50"),
        seeds=20,
        first_seed=SWARM_SEEDS,
        base=(("obs_neighbors", 12),),
        scenarios=SWARM_LAYERS,
        snapshots=False,
    ),
    "swarm-safety-10k": Suite(
        "the swarm layer among 10,000 UAVs (preset 'large', 10 pairs): smc, 5 held-out seeds "
        "72000-72004 (run with --no-figures: a recorded 10,000-UAV episode takes 0.8 GB)",
        preset="large",
        policies=("smc",),
        seeds=5,
        first_seed=SWARM_SEEDS,
        base=(("n_uavs", 10000),),
        scenarios=(SWARM_LAYERS[2],),
        snapshots=False,
    ),
    "quadrotor": Suite(
        "Sec. VI-B: 10 quadrotors (preset 'paper-quadrotor', docs/quadrotor.md), 5 seeds",
        preset="paper-quadrotor",
        policies=("smc", "proportional", "zero"),
        seeds=5,
    ),
}

#: grid shortcuts: option -> (config field, type, help)
SHORTCUTS = (
    ("--n-uavs", "n_uavs", int, "swarm sizes N"),
    ("--dim", "dim", int, "spatial dimension (2 or 3)"),
    ("--d-m", "d_m", float, "desired pair distance d_m (m)"),
    (
        "--pairs",
        "pairs",
        int,
        "number of pairs K: UAVs (0, 1), (2, 3), ... (K > 2^(dim-1) needs --set init=random)",
    ),
    ("--dynamics", "dynamics", str, "vehicle model (see PairFlockConfig.dynamics)"),
    ("--dt", "dt", float, "control period (s)"),
    ("--horizon", "horizon", float, "episode length (s)"),
    ("--noise-position", "obs_noise_position", float, "std of the noise on the observed y (m)"),
    ("--noise-velocity", "obs_noise_velocity", float, "std of the noise on the observed y' (m/s)"),
    ("--delay", "partner_delay", int, "delay of the partner's state (control steps)"),
    (
        "--disturbance",
        "disturbance_std",
        float,
        "std of a random acceleration on every UAV (m/s^2)",
    ),
)
