"""The flocking pass as it was written before the gather sweep: the symmetric sweep over the
pairs i < j in turn, f_ij added to i and subtracted from j. Kept as the reference the
kernels of :mod:`pairflock_env.swarm.flocking` must equal bit for bit (every sum formed in
the same order); slow and plain on purpose (tests/test_flocking_reference.py)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=False)
def _find(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=False)
def _reference(q, p, ql, pl, h, partner, prm, acc, min_d2, ncol, lcc, bad, vmis, vmax):
    a, r, inv_s2, r2, c, c1, c2, coll2, limit, floor2, floor_gain, squash, _ = prm
    B, N, D = q.shape
    ellipse = squash != 1.0 and D == 3  # the collision ellipsoid (collision_height)
    parent = np.empty(N, np.int64)
    size = np.empty(N, np.int64)
    n_unpaired = 0
    for i in range(N):
        n_unpaired += partner[i] < 0
    for b in range(B):
        vsum, vm = 0.0, 0.0
        for i in range(N):
            if n_unpaired > 0 and partner[i] >= 0:
                continue
            v2 = 0.0
            for k in range(D):
                dv = p[b, i, k] - pl[b, k]
                v2 += dv * dv
            v = np.sqrt(v2)
            vsum += v
            vm = max(vm, v)
        vmis[b] = vsum / (n_unpaired if n_unpaired > 0 else N)
        vmax[b] = vm
        bad[b] = False
        for i in range(N):
            parent[i], size[i], min_d2[b, i] = i, 1, np.inf
            for k in range(D):
                if not (abs(q[b, i, k]) <= limit and abs(p[b, i, k]) <= limit):
                    bad[b] = True
                acc[b, i, k] = h[b, i] * (
                    c1 * (ql[b, k] - q[b, i, k]) + c2 * (pl[b, k] - p[b, i, k])
                )
        nc = 0
        for i in range(N):
            for j in range(i + 1, N):
                d2 = 0.0
                for k in range(D):
                    x = q[b, j, k] - q[b, i, k]
                    d2 += x * x
                if j != partner[i]:
                    min_d2[b, i] = d2 if d2 < min_d2[b, i] else min_d2[b, i]
                    min_d2[b, j] = d2 if d2 < min_d2[b, j] else min_d2[b, j]
                if ellipse:  # dx^2 + dy^2 + squash dz^2 < collision_distance^2
                    x, y = q[b, j, 0] - q[b, i, 0], q[b, j, 1] - q[b, i, 1]
                    z = q[b, j, 2] - q[b, i, 2]
                    nc += x * x + y * y + squash * (z * z) < coll2
                else:
                    nc += d2 < coll2
                if d2 < r2:
                    w = a - r * np.exp(-d2 * inv_s2)
                    if d2 < floor2 and d2 > 0.0:  # the swarm layer's repulsion floor
                        w = min(w, -floor_gain / d2)
                    for k in range(D):
                        f = w * (q[b, j, k] - q[b, i, k]) + c * (p[b, j, k] - p[b, i, k])
                        acc[b, i, k] += f
                        acc[b, j, k] -= f
                    x, y = _find(parent, i), _find(parent, j)
                    if x != y:
                        if size[x] > size[y]:
                            x, y = y, x
                        parent[x] = y
                        size[y] += size[x]
        ncol[b] = nc
        best = 0
        for i in range(N):
            if parent[i] == i and size[i] > best:
                best = size[i]
        lcc[b] = best


def reference_flocking_pass(params, q, p, leader_q, leader_p, pinned, partner):
    """The outputs of :func:`~pairflock_env.swarm.flocking.flocking_pass` by the symmetric
    sweep (all pairs)."""
    B, N, D = q.shape
    out = {
        "acc": np.empty((B, N, D)),
        "min_d2": np.empty((B, N)),
        "collisions": np.empty(B, np.int64),
        "largest_component": np.empty(B, np.int64),
        "diverged": np.empty(B, np.bool_),
        "velocity_mismatch": np.empty(B),
        "velocity_mismatch_max": np.empty(B),
    }
    prm = tuple(float(v) for v in params)
    _reference(q, p, leader_q, leader_p, pinned, partner, prm, *out.values())
    return out
