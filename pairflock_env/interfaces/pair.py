"""The pair interface: pair-frame observation, feed-forward + pair-frame action, and the
log-accuracy reward (equations and reasons: :mod:`pairflock_env.interfaces`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.interfaces.base import LearningInterface, symlog
from pairflock_env.interfaces.pair_kernels import decode_rows, encode_rows, reward_rows
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


def _rows(obs: np.ndarray) -> np.ndarray:
    """Observations (..., obs_size) as C-ordered rows (n, obs_size), float32 or float64."""
    if obs.dtype != np.float32:
        obs = obs.astype(np.float64, copy=False)
    return np.ascontiguousarray(obs.reshape(-1, obs.shape[-1]))


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
        self._kernel_args()

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
    def _kernel_args(self) -> None:
        """The kernels' field offsets and parameters, resolved once."""
        p, lay, feat = self.params, self.layout, self.features

        def at(layout, *names):
            return [layout.slice(n).start if n in layout else -1 for n in names]

        obs_at = at(lay, "partner_offset", "partner_velocity", "target_distance", "flock_accel")
        obs_at += at(lay, "partner_flock_accel", "neighbor_offsets", "neighbor_velocities")
        obs_at += at(lay, "neighbor_mask")
        enc_at = at(feat, "error", "rel_velocity", "flock_difference", "flock_accel")
        enc_at += at(feat, "neighbor_offsets", "neighbor_velocities", "neighbor_mask")
        enc_at += at(feat, "neighbor_tca", "neighbor_miss")
        self._enc_at = np.array(obs_at + enc_at, np.int64)
        self._fine = (feat.slice("error_fine"), feat.slice("rel_velocity_fine"))
        enc = (p.position_scale, p.velocity_scale, p.fine_position, p.fine_velocity)
        self._enc_prm = np.array([*enc, p.max_accel, p.neighbor_scale, p.tca_horizon])
        K = self.config.obs_neighbors
        self._sort = (np.zeros(max(K, 1), np.int64), np.zeros(max(K, 1)))
        self._dec_at = np.array([obs_at[0], obs_at[3], obs_at[4]], np.int64)
        L = float(self.config.pair_accel_limit)
        bound = min(p.max_accel, L)
        self._dec_prm = np.array([p.accel_scale, float(p.feedforward), bound, L])
        self._rew_at = np.array([*obs_at[5:8], K], np.int64)
        cfg = self.config
        rew = (p.w_error, p.w_progress, p.position_scale, p.w_band, p.band, p.w_effort)
        rew += (cfg.dim, p.w_separation, p.separation_distance, cfg.collision_distance)
        rew += (p.w_collision, p.w_cohesion, p.cohesion_distance, p.approach_horizon)
        self._rew_prm = np.array([*rew, DIVERGENCE_PENALTY], np.float64)
        #: the reward kernel's flags (use the approach, n_uavs > 2), by whether to use it
        self._rew_flags = {a: np.array([a, cfg.n_uavs > 2], np.bool_) for a in (False, True)}
        self._dims = (0,) * self.config.dim

    def encode(self, obs: np.ndarray) -> np.ndarray:
        obs = self._check_obs_shape(obs)
        # flocking terms in units of the policy's own budget (stored with the model), so that
        # the features mean the same in an env with another pair_accel_limit
        lead = obs.shape[:-1]
        rows = _rows(obs)
        n = rows.shape[0]
        out = np.empty((n, self.features.size))
        fine = np.empty((n, 1 + self.config.dim))
        order, keys = self._sort
        args = (self._enc_at, self._enc_prm, self.params.threat_neighbors, self._dims)
        encode_rows(rows, *args, out, fine, order, keys)
        sl_e, sl_v = self._fine
        out[:, sl_e] = np.clip(symlog(fine[:, :1]) / _SYMLOG_DIV, -_CLIP, _CLIP)
        out[:, sl_v] = np.clip(symlog(fine[:, 1:]) / _SYMLOG_DIV, -_CLIP, _CLIP)
        return out.astype(np.float32).reshape(*lead, -1)

    # ------------------------------------------------------------------ decode
    def decode(self, obs: np.ndarray, action: np.ndarray) -> np.ndarray:
        obs = self._check_obs_shape(obs)
        lead = obs.shape[:-1]
        a = self._check_action(action, lead).reshape(-1, self.config.dim)
        out = np.empty(a.shape)
        decode_rows(_rows(obs), self._dec_at, a, self._dec_prm, self._dims, out)
        return out.reshape(*lead, self.config.dim)

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
        lead = err.shape
        approach = obs is not None and p.approach_horizon > 0 and cfg.obs_neighbors > 0
        rows = _rows(self._check_obs_shape(obs)) if approach else np.zeros((1, self.layout.size))
        log_err = np.log1p(err / p.error_scale)  # numpy's logarithm (pair_kernels' docstring)
        diverged = np.asarray(info["diverged"], dtype=bool)
        if lead and diverged.shape == lead[:-1]:  # per swarm: every agent of a diverged swarm
            diverged = np.repeat(diverged, lead[-1])
        elif diverged.shape != lead:
            diverged = diverged.reshape(diverged.shape + (1,) * (err.ndim - diverged.ndim))
            diverged = np.broadcast_to(diverged, lead)
        if sep.shape != lead:
            sep = np.broadcast_to(sep, lead)
        a = np.asarray(action, dtype=np.float64).reshape(-1, cfg.dim)
        out = np.empty(err.size)
        flags = self._rew_flags[approach]
        reward_rows(
            log_err.reshape(-1), err.reshape(-1), sep.reshape(-1), a,
            diverged.reshape(-1), rows, self._rew_at, self._rew_prm, flags, self._dims, out,
        )  # fmt: skip
        return out.reshape(lead)

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
