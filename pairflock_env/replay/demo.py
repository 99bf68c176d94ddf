"""A synthetic recording to try the replay without running the env (also the tests' data).

Every UAV belongs to a pair. The pairs sit on a square (2-D) or cubic (3-D) lattice of spacing
``spacing`` that flies a large circle after a leader; each pair spins about its lattice site
with its distance breathing around ``d_m``, and one pair (``squeeze``) dips to 0.2 m at
``squeeze_time``: the closest pass of the run. With ``spacing`` > 4 d_max every UAV's nearest
neighbour is its partner, so each one's closest distance is its pair distance, known without
any neighbour search. A fake safety filter is active on the pairs closer than 0.8 d_m.
"""

from __future__ import annotations

import os

import numpy as np

from pairflock_env.recording import RecordingWriter

__all__ = ["demo_positions", "write_demo"]

D_M = 1.0  # target pair distance, m
CLOSEST = 0.2  # the squeezed pair's smallest distance, m


def _lattice(num_pairs: int, dim: int, spacing: float) -> np.ndarray:
    side = int(np.ceil(num_pairs ** (1.0 / dim) - 1e-9))
    grid = np.stack(np.meshgrid(*[np.arange(side)] * dim, indexing="ij"), -1).reshape(-1, dim)
    return (grid[:num_pairs] - (side - 1) / 2.0) * spacing


def _pair_distance(t: np.ndarray | float, k: np.ndarray, squeeze: int, t_sq: float) -> np.ndarray:
    d = D_M * (1.0 + 0.3 * np.sin(0.9 * t + 0.7 * k))
    dip = np.exp(-(((t - t_sq) / 0.6) ** 2))  # the squeezed pair's dip to CLOSEST at t_sq
    return np.where(k == squeeze, d + (CLOSEST - d) * dip, d)


def demo_positions(
    t: float,
    num_uavs: int,
    dim: int,
    spacing: float = 6.0,
    squeeze: int = 0,
    squeeze_time: float = 4.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (N, dim), the leader (dim,) and the pair distances (M,) at time ``t``."""
    M = num_uavs // 2
    k = np.arange(M)
    sites = _lattice(M, dim, spacing)
    sweep = 60.0  # the formation's circle: radius (m), 0.05 rad/s
    lead = np.zeros(dim)
    lead[:2] = sweep * np.array([np.sin(0.05 * t), 1.0 - np.cos(0.05 * t)])
    if dim == 3:
        lead[2] = 10.0 + 0.5 * t
    d = _pair_distance(t, k, squeeze, squeeze_time)
    angle = 0.6 * t + 1.3 * k
    half = np.zeros((M, dim))
    half[:, 0], half[:, 1] = np.cos(angle), np.sin(angle)
    if dim == 3:
        half[:, 2] = 0.3 * np.sin(0.5 * t + k)
        half /= np.linalg.norm(half, axis=1, keepdims=True)
    half *= d[:, None] / 2.0
    centre = sites + lead - np.r_[spacing, np.zeros(dim - 1)]  # the leader ahead in x
    q = np.empty((num_uavs, dim))
    q[0 : 2 * M : 2], q[1 : 2 * M : 2] = centre - half, centre + half
    if num_uavs % 2:  # an odd UAV out flies alone, well behind the formation
        q[-1] = lead - np.r_[3.0 * spacing * M ** (1.0 / dim), np.zeros(dim - 1)]
    return q, lead, d


def write_demo(
    path: str | os.PathLike,
    num_uavs: int = 10,
    steps: int = 200,
    dim: int = 3,
    dt: float = 0.05,
    every: int = 1,
    **writer_kwargs,
) -> str:
    """Write a demo recording of ``steps`` env steps to the folder ``path``; return it."""
    M = num_uavs // 2
    pairs = np.arange(2 * M).reshape(M, 2)
    squeeze_time = min(4.0, 0.6 * steps * dt)
    kw = dict(spacing=6.0, squeeze=min(1, M - 1), squeeze_time=squeeze_time)
    config = {"demo": True, "n_uavs": num_uavs, "d_m": D_M, **kw}
    writer = RecordingWriter(path, num_uavs=num_uavs, dim=dim, dt=dt, pairs=pairs,
                             pair_target=D_M, config=config, seed=0, controller="demo",
                             every=every, **writer_kwargs)  # fmt: skip
    h = 1e-3
    with writer:
        for step in range(steps):
            if not (writer.wants(step) or step == steps - 1):
                continue
            t = step * dt
            q, lead, d = demo_positions(t, num_uavs, dim, **kw)
            qa, la, _ = demo_positions(t + h, num_uavs, dim, **kw)
            err = d - D_M
            closest = np.full(num_uavs, np.inf)
            closest[: 2 * M] = np.repeat(d, 2)
            active = err < -0.2 * D_M
            writer.append(
                step,
                force=step == steps - 1,
                time=t,
                positions=q,
                velocities=(qa - q) / h,
                leader_position=lead,
                leader_velocity=(la - lead) / h,
                pair_distance=d,
                pair_error=err,
                safety_active=active,
                safety_correction=np.where(active, 4.0 * (-err - 0.2 * D_M), 0.0),
                closest_distance=closest,
                infos={"sim_time": t, "collisions": float(np.sum(d < 0.3)), "active": active.sum()},
            )
    return os.fspath(path)
