"""What a learned pair policy sees, how its action becomes the env's action, and its reward.

The env's observation is physical (SI units, world frame; see :mod:`.observations`) and its
action is a world-frame pair acceleration in units of ``pair_accel_limit``: that is what the
analytic controllers read and write. A neural network learns faster and generalises better in
a frame that matches the task, so the views (``interface=`` on PettingZoo, Gymnasium and SB3)
and the ``sb3:`` policy loader put an *interface* between the env and the network. There are
two, both pure functions of the env's own observation and action (one implementation, shared
by every view and by the loader, so training and evaluation cannot drift apart):

``"world"``
    the identity: raw observation, raw action, the core's reward (``pairflock_env.task.rewards``).

``"pair"`` (:class:`PairInterface`, the default for learning)
    *Frame.* Everything is expressed in the pair frame of the observing UAV: ``e_r`` points at
    the partner, ``e_t`` is ``e_r`` turned by +90 degrees (3-D: ``e_t1`` horizontal, ``e_t2``
    completing a right-handed frame). Partner A's frame is partner B's turned by 180 degrees,
    so one shared policy serves both members. The pair-distance task is then one-dimensional
    (radial) plus a tangential velocity to cancel.

    *Action.* The network outputs ``a`` in [-1, 1]^dim in the pair frame; the UAV applies

        u_i = 1/2 (f_j - f_i) + accel_scale * R_i^T a

    where ``f_i``, ``f_j`` are its own and its partner's flocking commands (both observed,
    ``flock_accel`` / ``partner_flock_accel``). The feed-forward is physics, not a tuned
    gain: since y'' = (f_B - f_A) + (u_B - u_A) (eq. 23), each member cancelling half of the
    flocking difference leaves the pair's relative motion a pure double integrator driven by
    the two network outputs, z'' = -accel_scale R_i^T (a_i + a_j) (z = partner offset). The
    network learns the closing law (``a_r > 0`` accelerates toward the partner) and, through
    asymmetric outputs, where the pair's midpoint goes (avoidance). The sum is scaled down as a
    whole (direction kept) if its magnitude ||u_i|| would exceed ``max_accel`` (by default the
    ``pair_accel_limit`` the interface was built for, stored with a model) or the env's own
    limit: the bound is on the acceleration vector, not on each axis (a box would allow
    sqrt(dim) times more along a diagonal), and the env never clips.

    *Observation* (float32, every entry in [-5, 5], named in
    :attr:`PairInterface.fields`): the pair error ``e = ||z|| - d_m`` and the relative
    velocity in the pair frame, each twice: linear (``/ position_scale``,
    ``/ velocity_scale``) for the large transient and ``symlog(x / fine_scale) / 8`` so that
    millimetres stay visible to the network; the flocking difference ``f_j - f_i`` and the own
    flocking command (pair frame, ``/ max_accel``), which tell the network how much of its budget
    the feed-forward takes; and the ``threat_neighbors`` most threatening of the
    ``obs_neighbors`` nearest other UAVs, ranked by their distance at closest approach within
    ``tca_horizon`` if both kept their velocity: offset and velocity (pair frame,
    ``/ neighbor_scale``, ``/ velocity_scale``), a mask, the time and the distance of closest
    approach (``/ tca_horizon``, ``/ neighbor_scale``), what collision avoidance needs.

    *Reward* (per UAV, every term <= 0):

        r = - w_error * log(1 + |e| / error_scale) - w_progress * |e| / position_scale
            - w_band * [|e| > band]
            - w_effort * ||a||^2 / dim
            - w_separation * max(0, separation_distance - s) / separation_distance
            - w_collision * [s < collision_distance]
            - w_cohesion * max(0, s - cohesion_distance) / position_scale

    The logarithm keeps the transient (|e| ~ 250 m) and the last centimetres (|e| ~ 0.01 m)
    in the same few units, so the network is paid for precision; the linear term pays for
    closing the large initial distance quickly; the band term (off by default) pays for
    entering the |e| <= band zone early instead of creeping into it. ``s`` is the smaller of
    the distance to the nearest non-partner UAV (``min_separation``) and the closest approach
    to an observed neighbour within ``approach_horizon`` at constant velocities, so that a
    collision course costs before the UAVs are close (at 50 m/s a close pass lasts a few
    hundredths of a second, its warning half a second; a predicted collision is charged as
    one). ``a`` in the effort term is the network's own action, also with
    ``safety_filter="cbf"``: the policy is charged for what it asks, not for the filter's
    correction, which it does not choose (the core's reward, the world interface and the
    ``pair_accel`` info use the applied, filtered command; ``safety_correction`` reports the
    change). The cohesion term keeps the pair in the flock:
    nothing in the pair task itself stops both members from fleeing the swarm together, an
    escape route from the separation penalty that an early policy found. A diverged swarm
    gets the core's ``-DIVERGENCE_PENALTY``.

    *Decision period.* The policy acts every ``decision_period`` control steps (default 5:
    every 0.05 s at the paper's dt = 0.01 s) and its pair-frame action is held in between,
    while the frame and the feed-forward are recomputed every control step from the fresh
    observation. The learning views report the mean reward over the held steps. A decision
    every 0.05 s shortens the credit-assignment horizon five-fold (a 3-4 s approach is 70
    decisions, not 350) and cuts the network's cost per simulated second, which is what lets
    PPO learn the task in minutes; the flocking protocol, the physics and the feed-forward
    still run at the paper's 100 Hz. The ``sb3:`` loader holds the action the same way
    (through SB3's ``predict`` state); both use :class:`pairflock_env.interfaces.hold.DecisionHold`.

Each interface declares the box of its observations (:meth:`LearningInterface.observation_bounds`:
the physical bounds of :mod:`pairflock_env.task.spaces` for ``"world"``, [-5, 5] for ``"pair"``)
and the range of its reward (``reward_range``), both derived from the config.
``make_interface(name, config, **params)`` builds one; ``interface.to_dict()`` /
``interface_from_dict(d, config)`` store it with a trained model so that the loader rebuilds
the same transform for any env it is evaluated on.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pairflock_env.compat import upgrade_stored
from pairflock_env.config import PairFlockConfig
from pairflock_env.config.fields import UnknownFieldError
from pairflock_env.interfaces.base import LearningInterface, symlog
from pairflock_env.interfaces.pair import (
    PairInterface,
    closest_approach,
    pair_basis,
    pair_feedforward,
)
from pairflock_env.interfaces.pair_params import PairInterfaceParams
from pairflock_env.interfaces.world import WorldInterface

__all__ = [
    "INTERFACES",
    "LearningInterface",
    "PairInterface",
    "PairInterfaceParams",
    "WorldInterface",
    "closest_approach",
    "interface_from_dict",
    "make_interface",
    "pair_basis",
    "pair_feedforward",
    "symlog",
]


INTERFACES: dict[str, type[LearningInterface]] = {
    "world": WorldInterface,
    "pair": PairInterface,
}


def make_interface(name: str, config: PairFlockConfig, **params: Any) -> LearningInterface:
    """Build the learning interface ``name`` ("world" or "pair") for ``config``."""
    valid = f"must be one of {', '.join(map(repr, INTERFACES))}"
    if not isinstance(name, str):
        raise TypeError(f"interface={name!r} is invalid: {valid}")
    if name not in INTERFACES:
        raise ValueError(f"interface={name!r} is invalid: {valid}")
    extra = sorted(set(params) - {"decision_period"})
    if name == "world" and extra:
        raise UnknownFieldError(
            f"unknown world-interface parameter {extra[0]!r}: the world interface takes only "
            "decision_period"
        )
    return INTERFACES[name](config, **params)


def interface_from_dict(d: Mapping[str, Any], config: PairFlockConfig) -> LearningInterface:
    """Rebuild an interface stored with :meth:`LearningInterface.to_dict` for ``config``."""
    if not isinstance(d, Mapping):
        raise TypeError(f"interface description {d!r} is invalid: must be a mapping")
    if "name" not in d:
        raise ValueError(f"interface description {d!r} is invalid: needs a 'name' key")
    # a stored model keeps the parameter names of the release that trained it
    params = {k: v for k, v in upgrade_stored("interface", d).items() if k != "name"}
    return make_interface(d["name"], config, **params)
