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

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.config.fields import UnknownFieldError
from pairflock_env.interfaces.pair_params import PAIR_INTERFACE_SCHEMA, PairInterfaceParams
from pairflock_env.task.observations import ObsLayout
from pairflock_env.task.rewards import DIVERGENCE_PENALTY
from pairflock_env.task.spaces import (
    core_reward_range,
    pair_error_bound,
    physical_observation_bounds,
    separation_bound,
)

try:  # the ufunc np.clip ends in for float arrays with both bounds, without ~1 us of dispatch
    from numpy._core.umath import clip as _clip
except ImportError:  # pragma: no cover - another numpy layout
    _clip = np.clip

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


def symlog(x: np.ndarray) -> np.ndarray:
    """sign(x) log(1 + |x|): linear near 0, logarithmic far out."""
    return np.sign(x) * np.log1p(np.abs(x))


def pair_feedforward(layout: ObsLayout, obs: np.ndarray) -> np.ndarray:
    """Half the flocking difference, 1/2 (f_j - f_i) (..., dim), from the UAV's own
    observation: the feed-forward that leaves the pair's relative motion (eq. 23) to the two
    pair terms alone."""
    return 0.5 * (layout.get(obs, "partner_flock_accel") - layout.get(obs, "flock_accel"))


def pair_basis(z: np.ndarray) -> np.ndarray:
    """Orthonormal pair frame of partner offsets ``z`` (..., dim): rows (e_r, e_t[, e_t2]).

    2-D: e_r = z / |z|, e_t = e_r turned by +90 degrees. 3-D: e_t1 = (up x e_r) / |.| (the
    x axis replaces ``up`` when z is vertical), e_t2 = e_r x e_t1. z = 0 gives the world axes.
    Returns (..., dim, dim); ``R @ x`` expresses a world vector in the frame.
    """
    z = np.asarray(z, dtype=np.float64)
    D = z.shape[-1]
    r = np.sqrt(np.einsum("...k,...k->...", z, z))[..., None]
    er = np.where(r > 1e-12, z / np.maximum(r, 1e-12), np.eye(D)[0])
    if D == 2:
        et = np.stack([-er[..., 1], er[..., 0]], axis=-1)
        return np.stack([er, et], axis=-2)
    if D == 3:
        up = np.array([0.0, 0.0, 1.0])
        t1 = np.cross(up, er)
        n1 = np.linalg.norm(t1, axis=-1, keepdims=True)
        alt = np.cross(np.array([1.0, 0.0, 0.0]), er)
        t1 = np.where(n1 > 1e-6, t1, alt)
        t1 = t1 / np.linalg.norm(t1, axis=-1, keepdims=True)
        t2 = np.cross(er, t1)
        return np.stack([er, t1, t2], axis=-2)
    raise ValueError(f"dim={D} is invalid: the pair frame is defined for dim 2 or 3")


def closest_approach(x: np.ndarray, w: np.ndarray, horizon: float):
    """Time in [0, horizon] and distance of closest approach of relative positions ``x`` and
    velocities ``w`` (..., dim) moving at constant velocity."""
    w2 = np.einsum("...k,...k->...", w, w)
    tca = np.clip(-np.einsum("...k,...k->...", x, w) / np.maximum(w2, 1e-9), 0.0, horizon)
    miss = np.sqrt(np.einsum("...k,...k->...", x + w * tca[..., None], x + w * tca[..., None]))
    return tca, miss


def _to_frame(R: np.ndarray, x: np.ndarray) -> np.ndarray:
    """World vectors x (..., [K,] dim) in frames R (..., dim, dim)."""
    if x.ndim == R.ndim:  # (..., K, dim)
        return np.einsum("...ij,...kj->...ki", R, x)
    return np.einsum("...ij,...j->...i", R, x)


class LearningInterface:
    """Maps the env's observation/action/reward to what a learned policy sees and outputs.

    Subclasses are stateless apart from their frozen parameters, so the same object serves
    every row of a batch and can be rebuilt from :meth:`to_dict`.
    """

    name: str = ""
    #: control steps a policy action is held (the policy period is decision_period * dt)
    decision_period: int = 1
    #: True when :meth:`decode` returns a checked action unchanged and :meth:`reward` the
    #: core's reward (the views then skip both)
    passes_through: bool = False

    def __init__(self, config: PairFlockConfig) -> None:
        if not isinstance(config, PairFlockConfig):
            raise TypeError(f"config={config!r} is invalid: must be a PairFlockConfig")
        self.config = config
        self.layout = ObsLayout(config.dim, config.obs_neighbors)

    #: every entry of an encoded observation lies in [-observation_bound, observation_bound]
    observation_bound: float = np.inf

    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high), each float32 (observation_size,): the box every encoded observation
        lies in (what the views' observation spaces are)."""
        b = np.full(self.observation_size, self.observation_bound, np.float32)
        return -b, b

    @property
    def reward_range(self) -> tuple[float, float]:  # pragma: no cover - abstract
        """(low, high): every per-agent reward of :meth:`reward` lies in this range."""
        raise NotImplementedError

    @property
    def observation_size(self) -> int:  # pragma: no cover - abstract
        raise NotImplementedError

    def encode(self, obs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        """Policy observation (..., observation_size) float32 from env observations
        (..., obs_size)."""
        raise NotImplementedError

    def decode(self, obs: np.ndarray, action: np.ndarray) -> np.ndarray:  # pragma: no cover
        """Env actions (..., dim) (units of pair_accel_limit) from policy actions (..., dim)."""
        raise NotImplementedError

    def action_for(self, obs: np.ndarray, u: np.ndarray) -> np.ndarray:  # pragma: no cover
        """Policy actions (..., dim) that decode to the world-frame pair accelerations ``u``
        (..., dim, m/s^2) where the action box allows, clipped to it elsewhere: the inverse of
        :meth:`decode`, to label an analytic controller's commands (:mod:`train.imitate`)."""
        raise NotImplementedError

    def _check_accel(self, obs: np.ndarray, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=np.float64)
        if u.shape != (*obs.shape[:-1], self.config.dim):
            raise ValueError(
                f"u has shape {u.shape}; expected {(*obs.shape[:-1], self.config.dim)} "
                "(one world-frame acceleration per observation)"
            )
        return u

    def reward(
        self,
        reward: np.ndarray,
        info: Mapping[str, np.ndarray],
        action: np.ndarray,
        obs: np.ndarray | None = None,
    ) -> np.ndarray:  # pragma: no cover - abstract
        """Per-agent learning reward (B, M) from the core's reward and infos of a control step,
        the policy actions (B, M, dim) and the physical observation (B, M, obs_size) after it."""
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "decision_period": self.decision_period}

    def _check_obs_shape(self, obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs)
        if obs.shape[-1:] != (self.layout.size,):
            raise ValueError(
                f"observation has shape {obs.shape}; expected (..., {self.layout.size}) "
                f"(dim={self.config.dim}, obs_neighbors={self.config.obs_neighbors})"
            )
        return obs

    def _check_obs(self, obs: np.ndarray) -> np.ndarray:
        return self._check_obs_shape(obs).astype(np.float64, copy=False)

    def _check_action(self, action: np.ndarray, lead: tuple[int, ...]) -> np.ndarray:
        a = np.asarray(action, dtype=np.float64)
        D = self.config.dim
        if a.shape != (*lead, D):
            raise ValueError(f"action has shape {a.shape}; expected {(*lead, D)}")
        if not np.all(np.isfinite(a)):
            raise ValueError("action contains NaN or inf; actions must be finite")
        return a


class WorldInterface(LearningInterface):
    """The identity: the env's observation, action and reward, unchanged."""

    name = "world"
    passes_through = True

    def __init__(self, config: PairFlockConfig, decision_period: int = 1) -> None:
        super().__init__(config)
        self.decision_period = _check_period(decision_period)
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def observation_size(self) -> int:
        return self.layout.size

    def _box(self) -> tuple[np.ndarray, np.ndarray]:
        if self._bounds is None:
            self._bounds = physical_observation_bounds(self.config)
        return self._bounds

    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The physical observation's box, derived from the config
        (:func:`~pairflock_env.task.spaces.physical_observation_bounds`)."""
        low, high = self._box()
        return low.copy(), high.copy()

    @property
    def reward_range(self) -> tuple[float, float]:
        """The core's reward range (:func:`~pairflock_env.task.spaces.core_reward_range`)."""
        return core_reward_range(self.config)

    def encode(self, obs: np.ndarray) -> np.ndarray:
        """The physical observation as float32, inside :meth:`observation_bounds` (only
        observation noise beyond ``NOISE_SIGMAS`` standard deviations is ever clipped)."""
        obs = self._check_obs_shape(obs)
        low, high = self._box()
        return _clip(obs.astype(np.float32, copy=False), low, high)

    def decode(self, obs: np.ndarray, action: np.ndarray) -> np.ndarray:
        return self._check_action(action, self._check_obs_shape(obs).shape[:-1])

    def action_for(self, obs: np.ndarray, u: np.ndarray) -> np.ndarray:
        u = self._check_accel(self._check_obs_shape(obs), u)
        return np.clip(u / self.config.pair_accel_limit, -1.0, 1.0)

    def reward(self, reward, info, action, obs=None):
        return np.asarray(reward, dtype=np.float64)


_CLIP = 5.0
_SYMLOG_DIV = 8.0


class PairInterface(LearningInterface):
    """Pair-frame observation, feed-forward + pair-frame action, log-accuracy reward.

    See the module docstring for the equations and the reasons.
    """

    name = "pair"
    observation_bound = _CLIP

    def __init__(self, config: PairFlockConfig, **params: Any) -> None:
        super().__init__(config)
        p = PairInterfaceParams(**params)
        if p.accel_scale is None:
            p = dataclasses.replace(p, accel_scale=float(config.pair_accel_limit))
        if p.max_accel is None:
            p = dataclasses.replace(p, max_accel=p.accel_scale)
        if p.cohesion_distance is None:
            p = dataclasses.replace(p, cohesion_distance=float(config.radius))
        if p.threat_neighbors is None:
            p = dataclasses.replace(p, threat_neighbors=min(6, config.obs_neighbors))
        elif p.threat_neighbors > config.obs_neighbors:
            raise ValueError(
                f"threat_neighbors={p.threat_neighbors} is invalid: must be <= the config's "
                f"obs_neighbors={config.obs_neighbors}, the UAVs the env observes (raise "
                "obs_neighbors)"
            )
        self.params = p
        self.decision_period = p.decision_period
        D, K = config.dim, p.threat_neighbors
        fields: list[tuple[str, int]] = [
            ("error", 1),
            ("error_fine", 1),
            ("rel_velocity", D),
            ("rel_velocity_fine", D),
            ("flock_difference", D),
            ("flock_accel", D),
            ("neighbor_offsets", K * D),
            ("neighbor_velocities", K * D),
            ("neighbor_mask", K),
            ("neighbor_tca", K),
            ("neighbor_miss", K),
        ]
        self.fields: tuple[tuple[str, int], ...] = tuple((n, s) for n, s in fields if s > 0)
        self._size = sum(s for _, s in self.fields)

    @property
    def observation_size(self) -> int:
        return self._size

    #: what each encoded field holds (for docs and readers of the encoded vector)
    FIELD_DOCS = {
        "error": "pair error e = norm(z) - d_m (z: partner offset), / position_scale",
        "error_fine": "symlog(e / fine_position) / 8",
        "rel_velocity": "partner velocity relative to self, pair frame (radial, tangential), "
        "/ velocity_scale",
        "rel_velocity_fine": "symlog(relative velocity / fine_velocity) / 8",
        "flock_difference": "f_partner - f_self in the pair frame, / max_accel",
        "flock_accel": "own flocking command f_self in the pair frame, / max_accel",
        "neighbor_offsets": "offsets of the threat-ranked neighbours, pair frame, / neighbor_scale",
        "neighbor_velocities": "their velocities relative to self, pair frame, / velocity_scale",
        "neighbor_mask": "1 where a neighbour slot holds a UAV",
        "neighbor_tca": "time of closest approach in [0, tca_horizon], / tca_horizon",
        "neighbor_miss": "distance at closest approach, / neighbor_scale",
    }

    def markdown_table(self) -> str:
        """The encoded observation, field by field (generated from the interface itself)."""
        rows = ["| slice | field | size | meaning |", "|---|---|---|---|"]
        for name, sl in self.field_slices().items():
            rows.append(
                f"| {sl.start}:{sl.stop} | `{name}` | {sl.stop - sl.start} | "
                f"{self.FIELD_DOCS[name]} |"
            )
        return "\n".join(rows)

    def field_slices(self) -> dict[str, slice]:
        out, k = {}, 0
        for n, s in self.fields:
            out[n] = slice(k, k + s)
            k += s
        return out

    # ------------------------------------------------------------------ encode
    def encode(self, obs: np.ndarray) -> np.ndarray:
        obs = self._check_obs(obs)
        # flocking terms in units of the policy's own budget (stored with the model), so that
        # the features mean the same in an env with another pair_accel_limit
        p, L, lay = self.params, self.params.max_accel, self.layout
        z = lay.get(obs, "partner_offset")
        v = lay.get(obs, "partner_velocity")
        dm = lay.get(obs, "target_distance")
        fi = lay.get(obs, "flock_accel")
        fj = lay.get(obs, "partner_flock_accel")
        R = pair_basis(z)
        e = np.sqrt(np.einsum("...k,...k->...", z, z))[..., None] - dm
        vp = _to_frame(R, v)
        parts = [
            np.clip(e / p.position_scale, -_CLIP, _CLIP),
            symlog(e / p.fine_position) / _SYMLOG_DIV,
            np.clip(vp / p.velocity_scale, -_CLIP, _CLIP),
            symlog(vp / p.fine_velocity) / _SYMLOG_DIV,
            np.clip(_to_frame(R, fj - fi) / L, -_CLIP, _CLIP),
            np.clip(_to_frame(R, fi) / L, -_CLIP, _CLIP),
        ]
        if p.threat_neighbors:
            x = lay.get(obs, "neighbor_offsets")  # (..., K, D)
            w = lay.get(obs, "neighbor_velocities")
            mask = lay.get(obs, "neighbor_mask")  # (..., K)
            tca, miss = closest_approach(x, w, p.tca_horizon)
            # the most threatening first: smallest distance at closest approach (empty last)
            order = np.argsort(np.where(mask > 0, miss, np.inf), axis=-1, kind="stable")
            order = order[..., : p.threat_neighbors]
            x = np.take_along_axis(x, order[..., None], axis=-2)
            w = np.take_along_axis(w, order[..., None], axis=-2)
            mask = np.take_along_axis(mask, order, axis=-1)
            tca = np.take_along_axis(tca, order, axis=-1)
            miss = np.take_along_axis(miss, order, axis=-1)
            xp = _to_frame(R, x)
            wp = _to_frame(R, w)
            lead = obs.shape[:-1]
            m = mask[..., None]
            parts += [
                (np.clip(xp / p.neighbor_scale, -_CLIP, _CLIP) * m).reshape((*lead, -1)),
                (np.clip(wp / p.velocity_scale, -_CLIP, _CLIP) * m).reshape((*lead, -1)),
                mask,
                tca / p.tca_horizon * mask,
                np.minimum(miss / p.neighbor_scale, _CLIP) * mask,
            ]
        out = np.concatenate(parts, axis=-1)
        return np.clip(out, -_CLIP, _CLIP).astype(np.float32)

    # ------------------------------------------------------------------ decode
    def decode(self, obs: np.ndarray, action: np.ndarray) -> np.ndarray:
        obs = self._check_obs(obs)
        a = np.clip(self._check_action(action, obs.shape[:-1]), -1.0, 1.0)
        lay, L = self.layout, self.config.pair_accel_limit
        z = lay.get(obs, "partner_offset")
        R = pair_basis(z)
        u = self.params.accel_scale * np.einsum("...ji,...j->...i", R, a)  # R^T a
        if self.params.feedforward:
            u = u + pair_feedforward(lay, obs)
        bound = min(self.params.max_accel, L)
        over = np.sqrt(np.einsum("...k,...k->...", u, u))[..., None] / bound
        return u / (L * np.maximum(over, 1.0))

    def action_for(self, obs: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The network action in [-1, 1]^dim for a world-frame pair acceleration ``u`` (m/s^2):
        ``decode(obs, action_for(obs, u)) * pair_accel_limit == u`` whenever ``||u||`` is
        within the bound and the pair-frame action within the box; outside, the action is
        clipped to the box."""
        obs = self._check_obs(obs)
        u = self._check_accel(obs, u)
        lay = self.layout
        if self.params.feedforward:
            u = u - pair_feedforward(lay, obs)
        a = _to_frame(pair_basis(lay.get(obs, "partner_offset")), u) / self.params.accel_scale
        return np.clip(a, -1.0, 1.0)

    # ------------------------------------------------------------------ reward
    def reward(self, reward, info, action, obs=None):
        p, cfg = self.params, self.config
        err = np.abs(np.asarray(info["pair_error"], dtype=np.float64))
        sep = np.asarray(info["min_separation"], dtype=np.float64)
        if obs is not None and p.approach_horizon > 0 and cfg.obs_neighbors:
            obs = self._check_obs(obs)
            _, miss = closest_approach(
                self.layout.get(obs, "neighbor_offsets"),
                self.layout.get(obs, "neighbor_velocities"),
                p.approach_horizon,
            )
            miss = np.where(self.layout.get(obs, "neighbor_mask") > 0, miss, np.inf)
            sep = np.minimum(sep, miss.min(axis=-1))
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        r = -p.w_error * np.log1p(err / p.error_scale) - p.w_progress * err / p.position_scale
        r -= p.w_band * (err > p.band)
        r -= p.w_effort * np.einsum("...k,...k->...", a, a) / cfg.dim
        r -= p.w_separation * np.maximum(0.0, p.separation_distance - sep) / p.separation_distance
        r -= p.w_collision * (sep < cfg.collision_distance)
        # a UAV with no other UAV at all (n_uavs = 2) has no flock to leave
        far = np.where(np.isfinite(sep), np.maximum(0.0, sep - p.cohesion_distance), 0.0)
        r -= p.w_cohesion * far / p.position_scale
        diverged = np.asarray(info["diverged"], dtype=bool)
        r[diverged] = -DIVERGENCE_PENALTY
        return r

    @property
    def reward_range(self) -> tuple[float, float]:
        """(low, 0): the worst case of every term at once, with the largest pair error and
        separation a non-diverged state allows
        (:func:`~pairflock_env.task.spaces.pair_error_bound`), or ``-DIVERGENCE_PENALTY``.
        Typical rewards are of order one per control step (see ``docs/clients.md``), far
        inside this guaranteed range."""
        p = self.params
        e, s = pair_error_bound(self.config), separation_bound(self.config)
        worst = (
            p.w_error * np.log1p(e / p.error_scale)
            + p.w_progress * e / p.position_scale
            + p.w_band
            + p.w_effort
            + p.w_separation
            + p.w_collision
            + p.w_cohesion * max(0.0, s - p.cohesion_distance) / p.position_scale
        )
        return -max(float(worst) * (1 + 1e-6), DIVERGENCE_PENALTY), 0.0

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, **dataclasses.asdict(self.params)}


def _check_period(v: Any) -> int:
    return PAIR_INTERFACE_SCHEMA.fields["decision_period"].kind.check("decision_period", v, {})


INTERFACES: dict[str, type[LearningInterface]] = {
    "world": WorldInterface,
    "pair": PairInterface,
}


def make_interface(name: str, config: PairFlockConfig, **params: Any) -> LearningInterface:
    """Build the learning interface ``name`` ("world" or "pair") for ``config``."""
    valid = f"must be one of {', '.join(map(repr, INTERFACES))}"
    if not isinstance(name, str):
        raise TypeError(f"frame={name!r} is invalid: {valid}")
    if name not in INTERFACES:
        raise ValueError(f"frame={name!r} is invalid: {valid}")
    extra = sorted(set(params) - {"decision_period"})
    if name == "world" and extra:
        raise UnknownFieldError(
            f"unknown world-frame parameter {extra[0]!r}: the world frame takes only "
            "decision_period"
        )
    return INTERFACES[name](config, **params)


def interface_from_dict(d: Mapping[str, Any], config: PairFlockConfig) -> LearningInterface:
    """Rebuild an interface stored with :meth:`LearningInterface.to_dict` for ``config``."""
    if not isinstance(d, Mapping):
        raise TypeError(f"interface description {d!r} is invalid: must be a mapping")
    if "name" not in d:
        raise ValueError(f"interface description {d!r} is invalid: needs a 'name' key")
    params = {k: v for k, v in d.items() if k != "name"}
    if d["name"] == "pair":
        # a stored model keeps the parameter names of the release that trained it
        params = PAIR_INTERFACE_SCHEMA.resolve(params, warn=False)
    return make_interface(d["name"], config, **params)
