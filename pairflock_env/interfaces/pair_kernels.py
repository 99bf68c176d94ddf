"""The pair interface's arithmetic per row, as numba kernels (:class:`PairInterface` calls
them; the equations are documented there and in :mod:`pairflock_env.interfaces`).

Each kernel gives the numbers the interface's numpy code gave, bit for bit: the same
operations in the same order, written out per component (2-D and 3-D compiled apart). Where
numpy's order is not the obvious one it is named: a dot product or a frame rotation over a
contiguous axis adds (x0 y0 + x2 y2) + x1 y1 in 3-D (einsum's two-lane loop), a transposed
rotation and a norm add in order; ``np.clip``, ``np.maximum`` and ``np.minimum`` keep the
operand they keep (signed zeros included). The logarithms (``np.log1p``, whose results differ
from the C library's in the last bit now and then) stay in numpy: the kernels hand their
arguments back.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import jit_inline, jit_kernel
from pairflock_env.task.pairing import dot_axes

__all__ = ["decode_rows", "encode_rows", "reward_rows"]


@jit_inline
def _clip(x, lo, hi):
    """``np.clip(x, lo, hi)``: x when inside (NaN and signed zeros kept)."""
    return lo if x < lo else (hi if x > hi else x)


@jit_inline
def _maximum(a, b):
    """``np.maximum(a, b)``: b when equal, NaN when either is."""
    return a if (a > b or a != a) else b


@jit_inline
def _minimum(a, b):
    """``np.minimum(a, b)``: b when equal, NaN when either is."""
    return a if (a < b or a != a) else b


@jit_inline
def _field(obs, r, at, three):
    """A dim-vector field of row r of obs (as float64)."""
    z = np.float64(obs[r, at + 2]) if three else 0.0
    return np.float64(obs[r, at]), np.float64(obs[r, at + 1]), z


@jit_inline
def _cross(a0, a1, a2, b0, b1, b2):
    """``np.cross`` of two 3-vectors (its products and differences, in its order)."""
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@jit_inline
def _frame(z0, z1, z2, three):
    """:func:`~pairflock_env.interfaces.pair.pair_basis` of one offset z: the rows e_r, e_t
    (, e_t2) as a 3 x 3 tuple (the third row and column zero in 2-D)."""
    r = np.sqrt(dot_axes(z0, z1, z2, z0, z1, z2, three))
    if r > 1e-12:
        d = _maximum(r, 1e-12)
        e0, e1, e2 = z0 / d, z1 / d, (z2 / d if three else 0.0)
    else:
        e0, e1, e2 = 1.0, 0.0, 0.0
    if not three:
        return (e0, e1, 0.0), (-e1, e0, 0.0), (0.0, 0.0, 0.0)
    t0, t1, t2 = _cross(0.0, 0.0, 1.0, e0, e1, e2)
    n1 = np.sqrt((t0 * t0 + t1 * t1) + t2 * t2)  # np.linalg.norm: in order
    if not n1 > 1e-6:
        t0, t1, t2 = _cross(1.0, 0.0, 0.0, e0, e1, e2)
    n = np.sqrt((t0 * t0 + t1 * t1) + t2 * t2)
    t0, t1, t2 = t0 / n, t1 / n, t2 / n
    return (e0, e1, e2), (t0, t1, t2), _cross(e0, e1, e2, t0, t1, t2)


@jit_inline
def _rotate(R, v0, v1, v2, three):
    """R v (a world vector in the frame; ``einsum("...ij,...j->...i")``'s order)."""
    a, b, c = R
    return (
        dot_axes(a[0], a[1], a[2], v0, v1, v2, three),
        dot_axes(b[0], b[1], b[2], v0, v1, v2, three),
        dot_axes(c[0], c[1], c[2], v0, v1, v2, three) if three else 0.0,
    )


@jit_inline
def _unrotate(R, a0, a1, a2, three):
    """R^T a (a frame vector in the world; ``einsum("...ji,...j->...i")`` adds in order)."""
    a, b, c = R
    if three:
        return (
            (a[0] * a0 + b[0] * a1) + c[0] * a2,
            (a[1] * a0 + b[1] * a1) + c[1] * a2,
            (a[2] * a0 + b[2] * a1) + c[2] * a2,
        )
    return a[0] * a0 + b[0] * a1, a[1] * a0 + b[1] * a1, 0.0


@jit_inline
def _approach(x0, x1, x2, w0, w1, w2, horizon, three):
    """:func:`~pairflock_env.interfaces.pair.closest_approach` of one relative position and
    velocity: (time in [0, horizon], distance)."""
    w2_ = dot_axes(w0, w1, w2, w0, w1, w2, three)
    tca = _clip(-dot_axes(x0, x1, x2, w0, w1, w2, three) / _maximum(w2_, 1e-9), 0.0, horizon)
    y0, y1, y2 = x0 + w0 * tca, x1 + w1 * tca, x2 + w2 * tca
    return tca, np.sqrt(dot_axes(y0, y1, y2, y0, y1, y2, three))


@jit_inline
def _put(out, r, at, v, scale, three):
    """clip(v / scale, +-5) into out[r, at:at + dim]."""
    out[r, at] = _clip(v[0] / scale, -5.0, 5.0)
    out[r, at + 1] = _clip(v[1] / scale, -5.0, 5.0)
    if three:
        out[r, at + 2] = _clip(v[2] / scale, -5.0, 5.0)


@jit_kernel
def encode_rows(obs, at, prm, n_threat, dims, out, fine, order, keys):
    """Encode rows of physical observations ``obs`` (R, obs_size) into ``out`` (R, size)
    float64, clipped to +-5, except the two symlog fields, whose arguments e / fine_position
    and v / fine_velocity go to ``fine`` (R, 1 + dim). ``at``: offsets of the obs fields
    (partner_offset, partner_velocity, target_distance, flock_accel, partner_flock_accel,
    neighbor_offsets, neighbor_velocities, neighbor_mask) then of the encoded fields (error,
    rel_velocity, flock_difference, flock_accel, neighbor_offsets, neighbor_velocities,
    neighbor_mask, neighbor_tca, neighbor_miss); ``prm``: position_scale, velocity_scale,
    fine_position, fine_velocity, max_accel, neighbor_scale, tca_horizon."""
    three = len(dims) == 3
    D = 3 if three else 2
    ps, vs, fp, fv, L, ns, th = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6]
    K = keys.shape[0]
    for r in range(obs.shape[0]):
        z0, z1, z2 = _field(obs, r, at[0], three)
        R = _frame(z0, z1, z2, three)
        e = np.sqrt(dot_axes(z0, z1, z2, z0, z1, z2, three)) - np.float64(obs[r, at[2]])
        out[r, at[8]] = _clip(e / ps, -5.0, 5.0)
        fine[r, 0] = e / fp
        v = _field(obs, r, at[1], three)
        vp = _rotate(R, v[0], v[1], v[2], three)
        _put(out, r, at[9], vp, vs, three)
        for k in range(D):
            fine[r, 1 + k] = vp[k] / fv
        fi = _field(obs, r, at[3], three)
        fj = _field(obs, r, at[4], three)
        fd = _rotate(R, fj[0] - fi[0], fj[1] - fi[1], fj[2] - fi[2], three)
        _put(out, r, at[10], fd, L, three)
        _put(out, r, at[11], _rotate(R, fi[0], fi[1], fi[2], three), L, three)
        if n_threat == 0:
            continue
        for k in range(K):  # closest approaches; the most threatening first (stable)
            x = _field(obs, r, at[5] + k * D, three)
            w = _field(obs, r, at[6] + k * D, three)
            tca, miss = _approach(x[0], x[1], x[2], w[0], w[1], w[2], th, three)
            keys[k] = miss if obs[r, at[7] + k] > 0 else np.inf
            s = k
            while s > 0 and keys[order[s - 1]] > keys[k]:
                order[s] = order[s - 1]
                s -= 1
            order[s] = k
        for s in range(n_threat):
            k = order[s]
            x = _field(obs, r, at[5] + k * D, three)
            w = _field(obs, r, at[6] + k * D, three)
            tca, miss = _approach(x[0], x[1], x[2], w[0], w[1], w[2], th, three)
            m = np.float64(obs[r, at[7] + k])
            xp = _rotate(R, x[0], x[1], x[2], three)
            wp = _rotate(R, w[0], w[1], w[2], three)
            for c in range(D):
                out[r, at[12] + s * D + c] = _clip(_clip(xp[c] / ns, -5.0, 5.0) * m, -5.0, 5.0)
                out[r, at[13] + s * D + c] = _clip(_clip(wp[c] / vs, -5.0, 5.0) * m, -5.0, 5.0)
            out[r, at[14] + s] = _clip(m, -5.0, 5.0)
            out[r, at[15] + s] = _clip(tca / th * m, -5.0, 5.0)
            out[r, at[16] + s] = _clip(_minimum(miss / ns, 5.0) * m, -5.0, 5.0)


@jit_kernel
def decode_rows(obs, at, action, prm, dims, out):
    """Env actions ``out`` (R, dim) of policy actions ``action`` (R, dim) against rows of
    ``obs``; ``at``: partner_offset, flock_accel, partner_flock_accel; ``prm``:
    accel_scale, feedforward (0/1), min(max_accel, pair_accel_limit), pair_accel_limit."""
    three = len(dims) == 3
    scale, ff, bound, L = prm[0], prm[1], prm[2], prm[3]
    for r in range(obs.shape[0]):
        z0, z1, z2 = _field(obs, r, at[0], three)
        R = _frame(z0, z1, z2, three)
        a0, a1 = _clip(action[r, 0], -1.0, 1.0), _clip(action[r, 1], -1.0, 1.0)
        a2 = _clip(action[r, 2], -1.0, 1.0) if three else 0.0
        t = _unrotate(R, a0, a1, a2, three)
        u0, u1, u2 = scale * t[0], scale * t[1], scale * t[2]
        if ff:
            fi = _field(obs, r, at[1], three)
            fj = _field(obs, r, at[2], three)
            u0 = u0 + 0.5 * (fj[0] - fi[0])
            u1 = u1 + 0.5 * (fj[1] - fi[1])
            u2 = u2 + 0.5 * (fj[2] - fi[2])
        over = np.sqrt(dot_axes(u0, u1, u2, u0, u1, u2, three)) / bound
        d = L * _maximum(over, 1.0)
        out[r, 0], out[r, 1] = u0 / d, u1 / d
        if three:
            out[r, 2] = u2 / d


@jit_kernel
def reward_rows(log_err, err, sep, action, diverged, obs, at, prm, flags, dims, out):
    """The pair interface's reward of each row, given its ``log_err`` = log1p(|e| /
    error_scale) (numpy's), |e| ``err``, separation ``sep``, policy action, ``diverged`` (per
    row) and physical observation (``at``: neighbour offsets, velocities, mask, and the
    number of slots). ``prm``: w_error, w_progress, position_scale, w_band, band, w_effort,
    dim, w_separation, separation_distance, collision_distance, w_collision, w_cohesion,
    cohesion_distance, approach_horizon, penalty; ``flags``: use the approach, n_uavs > 2."""
    three = len(dims) == 3
    D = 3 if three else 2
    w_e, w_p, ps, w_b, band, w_u, dim = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6]
    w_s, sd, coll, w_c, w_h, coh, hor = prm[7], prm[8], prm[9], prm[10], prm[11], prm[12], prm[13]
    for r in range(err.shape[0]):
        s = sep[r]
        if flags[0]:
            m = np.inf
            for k in range(at[3]):  # np.where(mask > 0, miss, inf).min(): NaN kept
                x = _field(obs, r, at[0] + k * D, three)
                w = _field(obs, r, at[1] + k * D, three)
                miss = _approach(x[0], x[1], x[2], w[0], w[1], w[2], hor, three)[1]
                m = _minimum(m, miss if obs[r, at[2] + k] > 0 else np.inf)
            s = _minimum(s, m)
        a0, a1 = _clip(action[r, 0], -1.0, 1.0), _clip(action[r, 1], -1.0, 1.0)
        a2 = _clip(action[r, 2], -1.0, 1.0) if three else 0.0
        e = err[r]
        v = -w_e * log_err[r] - w_p * e / ps
        v -= w_b * (1.0 if e > band else 0.0)
        v -= w_u * dot_axes(a0, a1, a2, a0, a1, a2, three) / dim
        v -= w_s * _maximum(0.0, sd - s) / sd
        v -= w_c * (1.0 if s < coll else 0.0)
        far = _maximum(0.0, s - coh) if flags[1] else 0.0
        v -= w_h * far / ps
        out[r] = -prm[14] if diverged[r] else v
