"""The pair interface: pair-frame observation, feed-forward + pair-frame action, and the
log-accuracy reward (equations and reasons: :mod:`pairflock_env.interfaces`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.interfaces.base import LearningInterface, symlog
from pairflock_env.interfaces.pair_params import PairInterfaceParams
from pairflock_env.layout import Field as LayoutField
from pairflock_env.layout import FlatLayout
from pairflock_env.task.observations import ObsLayout
from pairflock_env.task.rewards import DIVERGENCE_PENALTY
from pairflock_env.task.spaces import pair_error_bound, separation_bound

__all__ = ["PairInterface", "closest_approach", "pair_basis", "pair_feedforward"]


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
            p = p.replace(accel_scale=float(config.pair_accel_limit))
        if p.max_accel is None:
            p = p.replace(max_accel=p.accel_scale)
        if p.cohesion_distance is None:
            p = p.replace(cohesion_distance=float(config.radius))
        if p.threat_neighbors is None:
            p = p.replace(threat_neighbors=min(6, config.obs_neighbors))
        elif p.threat_neighbors > config.obs_neighbors:
            raise ValueError(
                f"threat_neighbors={p.threat_neighbors} is invalid: must be <= the config's "
                f"obs_neighbors={config.obs_neighbors}, the UAVs the env observes (raise "
                "obs_neighbors)"
            )
        self.params = p
        self.decision_period = p.decision_period
        D, K = config.dim, p.threat_neighbors
        sizes = dict(
            error=1,
            error_fine=1,
            rel_velocity=D,
            rel_velocity_fine=D,
            flock_difference=D,
            flock_accel=D,
            neighbor_offsets=K * D,
            neighbor_velocities=K * D,
            neighbor_mask=K,
            neighbor_tca=K,
            neighbor_miss=K,
        )
        #: the encoded observation, field by field (its docs table: ``features.markdown_table``)
        self.features = FlatLayout(
            (LayoutField(n, (k,), "1", self.FIELD_DOCS[n]) for n, k in sizes.items()),
            "encoded observation",
        )

    @property
    def observation_size(self) -> int:
        return self.features.size

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
        far = np.maximum(0.0, sep - p.cohesion_distance) if cfg.n_uavs > 2 else 0.0
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
        return {"name": self.name, **self.params.to_dict()}
