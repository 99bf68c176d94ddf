"""The pair interface's encode, decode and reward as numpy wrote them before the kernels of
:mod:`pairflock_env.interfaces.pair_kernels`: the reference those must equal bit for bit
(tests/test_interface_kernels.py). Plain array code on purpose."""

from __future__ import annotations

import numpy as np

from pairflock_env.interfaces.base import symlog
from pairflock_env.interfaces.pair import closest_approach, pair_basis, pair_feedforward
from pairflock_env.task.rewards import DIVERGENCE_PENALTY

_CLIP = 5.0


def _to_frame(R, x):
    if x.ndim == R.ndim:
        return np.einsum("...ij,...kj->...ki", R, x)
    return np.einsum("...ij,...j->...i", R, x)


def encode(itf, obs):
    obs = np.asarray(obs).astype(np.float64)
    p, L, lay = itf.params, itf.params.max_accel, itf.layout
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
        symlog(e / p.fine_position) / 8.0,
        np.clip(vp / p.velocity_scale, -_CLIP, _CLIP),
        symlog(vp / p.fine_velocity) / 8.0,
        np.clip(_to_frame(R, fj - fi) / L, -_CLIP, _CLIP),
        np.clip(_to_frame(R, fi) / L, -_CLIP, _CLIP),
    ]
    if p.threat_neighbors:
        x = lay.get(obs, "neighbor_offsets")
        w = lay.get(obs, "neighbor_velocities")
        mask = lay.get(obs, "neighbor_mask")
        tca, miss = closest_approach(x, w, p.tca_horizon)
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


def decode(itf, obs, action):
    obs = np.asarray(obs).astype(np.float64)
    a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
    lay, L = itf.layout, itf.config.pair_accel_limit
    R = pair_basis(lay.get(obs, "partner_offset"))
    u = itf.params.accel_scale * np.einsum("...ji,...j->...i", R, a)
    if itf.params.feedforward:
        u = u + pair_feedforward(lay, obs)
    bound = min(itf.params.max_accel, L)
    over = np.sqrt(np.einsum("...k,...k->...", u, u))[..., None] / bound
    return u / (L * np.maximum(over, 1.0))


def reward(itf, info, action, obs=None):
    p, cfg = itf.params, itf.config
    err = np.abs(np.asarray(info["pair_error"], dtype=np.float64))
    sep = np.asarray(info["min_separation"], dtype=np.float64)
    if obs is not None and p.approach_horizon > 0 and cfg.obs_neighbors:
        obs = np.asarray(obs).astype(np.float64)
        _, miss = closest_approach(
            itf.layout.get(obs, "neighbor_offsets"),
            itf.layout.get(obs, "neighbor_velocities"),
            p.approach_horizon,
        )
        miss = np.where(itf.layout.get(obs, "neighbor_mask") > 0, miss, np.inf)
        sep = np.minimum(sep, miss.min(axis=-1))
    a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
    r = -p.w_error * np.log1p(err / p.error_scale) - p.w_progress * err / p.position_scale
    r -= p.w_band * (err > p.band)
    r -= p.w_effort * np.einsum("...k,...k->...", a, a) / cfg.dim
    r -= p.w_separation * np.maximum(0.0, p.separation_distance - sep) / p.separation_distance
    r -= p.w_collision * (sep < cfg.collision_distance)
    far = np.maximum(0.0, sep - p.cohesion_distance) if cfg.n_uavs > 2 else 0.0
    r -= p.w_cohesion * far / p.position_scale
    diverged = np.asarray(info["diverged"], dtype=bool)
    r[diverged] = -DIVERGENCE_PENALTY
    return r
