"""Named presets and :func:`make_config`.

The defaults of every field ARE the paper's values (Sec. VI-A with the parameter set of
docs/paper-notes.md), so ``"paper"`` lists nothing: one source of truth, and
``PairFlockConfig()`` is the paper's experiment. Every other preset lists only what differs
from the defaults (a test checks that no preset repeats a default).
"""

from __future__ import annotations

from typing import Any

from pairflock_env.config.fields import invalid
from pairflock_env.config.model import SCHEMA, PairFlockConfig

__all__ = ["PRESETS", "make_config", "preset_names"]

PRESETS: dict[str, dict[str, Any]] = {
    # Sec. VI-A: the defaults.
    "paper": {},
    # Sec. VI-B at quadrotor scale, with the parameter set of docs/paper-notes.md ("Quadrotor
    # experiment"): 10 quadrotors, one pair, a leader that climbs, levels off and turns twice.
    "paper-quadrotor": dict(
        n_uavs=10,
        dynamics="quadrotor",
        dim=3,  # the scenario is 3-D whichever vehicle flies it (dynamics="particle" too)
        dt=0.02,  # protocol and pair action at 50 Hz ...
        substeps=10,  # ... physics and attitude loop at 500 Hz
        horizon=65.0,
        spacing=3.0,
        radius=3.6,
        attraction=0.3,
        repulsion=3.0,
        pin_position_gain=0.5,
        pin_velocity_gain=1.414,
        leader="climb_and_turn",
        leader_position=(0.0, 0.0, 20.0),
        leader_velocity=(5.0, 0.0, 1.0),  # 5 m/s along +x, climbing at 1 m/s ...
        leader_climb_time=20.0,  # ... until 20 s,
        leader_level_time=2.0,  # levelling off during the first turn
        leader_turns=((20.0, 2.0, 90.0), (50.0, 2.0, 90.0)),
        d_m=2.5,
        surface_slope=1.0,
        pair_accel_limit=20.0,
        swarm_center=(0.0, 0.0, 20.0),
        swarm_half_width=(6.0, 6.0, 1.5),
        pair_corner=(10.0, 10.0, 0.0),  # pair at (-10, -10, 20) and (10, 10, 20)
        quad_ground_altitude=0.0,
    ),
    # The quadrotor experiment scaled to an indoor motion-capture arena for Crazyflies
    # (docs/crazyflie.md, "The crazyflie preset"): lengths x 0.25 (spacing 0.75 m, d_m 0.625 m),
    # a leader that climbs 0.8 m at 0.3 m/s and flies a 3 m square, so that the swarm stays
    # in 6 m x 6 m x 2.6 m; commands kept smooth and below what flips a cf2x (measured by
    # benchmarks/crazyflie_feeding.py): a_des cut at 3 m/s^2, pair term at 1 m/s^2, the
    # firmware's velocity push bounded by a 0.1 m/s leash, velocity consensus 0.5 (with the
    # paper's 1 the flock alone commands 0.49 m/s^2 on average behind the Crazyflie's lag,
    # against 0.06 with particles; benchmarks/crazyflie_preset.py).
    "crazyflie": dict(
        n_uavs=10,
        dynamics="crazyflie",
        dim=3,
        dt=0.02,  # 50 Hz setpoints, 10 firmware ticks, plant at 500 Hz (substeps follow)
        horizon=65.0,
        spacing=0.75,
        radius=0.9,
        attraction=0.3,
        repulsion=3.0,
        consensus=0.5,
        pin_position_gain=0.5,
        pin_velocity_gain=1.414,
        leader="climb_and_turn",
        leader_position=(-1.5, -1.5, 1.0),
        leader_velocity=(0.3, 0.0, 0.04),  # 0.3 m/s along +x, climbing 0.04 m/s ...
        leader_climb_time=20.0,  # ... for 20 s (to 1.8 m),
        leader_level_time=2.0,
        leader_turns=tuple((10.0 * k, 2.0, 90.0) for k in range(1, 7)),  # a 3 m square
        d_m=0.625,
        surface_slope=1.0,
        pair_accel_limit=1.0,
        swarm_center=(-1.5, -1.5, 1.0),
        swarm_half_width=(1.5, 1.5, 0.375),
        pair_corner=(1.5, 1.5, 0.0),  # pair at (-3, -3, 1) and (0, 0, 1)
        min_init_spacing=0.5,
        collision_distance=0.125,  # Crazyswarm's collision ellipsoid: horizontal radius ...
        collision_height=0.375,  # ... and vertical (downwash) radius
        safety_distance=0.375,  # the filter's sphere holds that ellipsoid
        reward_separation_distance=0.375,
        crazyflie_accel_limit=3.0,
        crazyflie_leash_velocity=0.1,
        crazyflie_ground_altitude=0.0,
    ),
    # A large swarm (docs/large-swarms.md): 1,000 UAVs with 10 pairs drawn anywhere in the
    # start box (grown with N at the paper's density: +-158 m), the grid search (auto). The
    # safety filter keeps its 100 m default sensing radius (20 m here while 100 m cost
    # several times more; the suite's runs are the same with both, docs/large-swarms.md).
    "large": dict(
        n_uavs=1000,
        pairs=tuple((2 * k, 2 * k + 1) for k in range(10)),
        init="random",
        pair_corner=150.0,
    ),
}


def preset_names() -> tuple[str, ...]:
    """Names of the presets, for ``make_config`` and the ``--preset`` options."""
    return tuple(PRESETS)


def make_config(preset: str | None = "paper", **overrides: Any) -> PairFlockConfig:
    """Build a validated config from a preset name plus single-field overrides.

    ``preset=None`` starts from the defaults (which are the paper's values) with
    ``preset=None`` recorded. Unknown presets raise ``ValueError`` with the valid choices,
    unknown fields a ``TypeError`` with a did-you-mean hint; a field the preset sets keeps the
    preset's value unless overridden, the others follow the defaults (``dim`` and
    ``substeps`` follow ``dynamics``).
    """
    if preset is None:
        base: dict[str, Any] = {}
    elif not isinstance(preset, str):
        raise invalid("preset", preset, "must be None or one of " + _choices(), TypeError)
    elif preset not in PRESETS:
        raise invalid("preset", preset, "must be one of " + _choices())
    else:
        base = dict(PRESETS[preset])
    changed = SCHEMA.resolve(overrides)
    values = {**base, "preset": preset, **changed}
    return PairFlockConfig._create(values, tuple(changed))


def _choices() -> str:
    return ", ".join(map(repr, PRESETS))
