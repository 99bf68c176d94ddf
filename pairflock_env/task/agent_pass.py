"""The agents' pass: what a core step reports per agent, from the neighbour pass, in one
kernel.

For every agent (paired UAV) m of every swarm b, one numba loop computes its pair quantities
(:func:`~pairflock_env.task.pairing.pair_quantities`), its separation, its reward terms
(:func:`~pairflock_env.task.rewards.agent_reward`), the magnitude of its pair command, and
writes its observation row, field by field at the places the layout gives by name
(:class:`~pairflock_env.task.observations.ObsLayout`, true values; the partner delay, sensor
noise and registered extra fields are applied by the core on top). Each number is the one
the separate numpy stages gave (the same operations in the same order), without their
per-stage overhead: at B = 1 that overhead, not the arithmetic, was most of a step.
"""

from __future__ import annotations

import numpy as np

from pairflock_env.kernels import jit_inline, jit_kernel
from pairflock_env.task.pairing import dot_axes, pair_quantities
from pairflock_env.task.rewards import REWARD_TERMS, agent_reward, reward_params
from pairflock_env.task.spaces import separation_bound

__all__ = ["AGENT_ROWS", "OBS_FIELDS", "AgentPass"]

#: the per-agent results (B, M) of the pass, rows of one (len, B, M) float64 array
AGENT_ROWS = (
    "pair_distance",
    "pair_error",
    "sliding_surface",
    "min_separation",
    "shared_neighbors",
    "pair_accel",
    "reward",
    *(f"reward_{k}" for k in REWARD_TERMS),
)
#: the built-in observation fields the kernel writes, in the order of its offsets
OBS_FIELDS = (
    "partner_offset",
    "partner_velocity",
    "target_distance",
    "shared_neighbors",
    "leader_offset",
    "leader_velocity",
    "flock_accel",
    "partner_flock_accel",
    "neighbor_offsets",
    "neighbor_velocities",
    "neighbor_mask",
)


@jit_inline
def _vec(obs, b, m, at, x0, x1, x2, three):
    if at >= 0:
        obs[b, m, at] = np.float32(x0)
        obs[b, m, at + 1] = np.float32(x1)
        if three:
            obs[b, m, at + 2] = np.float32(x2)


@jit_kernel
def _agents_kernel(
    state, neighbors, agents, partners, pairs, d_m, u, prm, fixed_sep, at, dims, out
):
    """Every agent of every swarm; ``fixed_sep``: the separation when no UAV but the partner
    exists (n_uavs = 2), else NaN."""
    three = len(dims) == 3
    q, p, acc, min_d2, ql, pl = state
    shared, nbr_pos, nbr_vel, nbr_mask = neighbors
    obs, res, finite, closest = out
    c, rprm = prm[0], prm[1:]
    K = nbr_mask.shape[2]
    D = 3 if three else 2
    for b in range(q.shape[0]):
        for m in range(agents.shape[0]):
            i, j = agents[m], partners[m]
            y0, y1 = q[b, j, 0] - q[b, i, 0], q[b, j, 1] - q[b, i, 1]
            v0, v1 = p[b, j, 0] - p[b, i, 0], p[b, j, 1] - p[b, i, 1]
            y2 = q[b, j, 2] - q[b, i, 2] if three else 0.0
            v2 = p[b, j, 2] - p[b, i, 2] if three else 0.0
            dist, err, surface = pair_quantities(y0, y1, y2, v0, v1, v2, d_m[m], c, three)
            sep = np.sqrt(min_d2[b, i]) if np.isnan(fixed_sep) else fixed_sep
            u0, u1 = u[b, m, 0], u[b, m, 1]
            u2 = u[b, m, 2] if three else 0.0
            uu = dot_axes(u0, u1, u2, u0, u1, u2, three)
            terms = agent_reward(rprm, err, uu, sep)
            nshared = shared[b, pairs[m]]
            row = (dist, err, surface, sep, nshared, np.sqrt(uu), terms[4])
            for k in range(7):
                res[k, b, m] = row[k]
            for k in range(4):
                res[7 + k, b, m] = terms[k]
            # the observation row, field by field (at[f] < 0: no such field)
            _vec(obs, b, m, at[0], y0, y1, y2, three)
            _vec(obs, b, m, at[1], v0, v1, v2, three)
            obs[b, m, at[2]] = np.float32(d_m[m])
            obs[b, m, at[3]] = np.float32(nshared)
            qz = ql[b, 2] - q[b, i, 2] if three else 0.0
            pz = pl[b, 2] - p[b, i, 2] if three else 0.0
            _vec(obs, b, m, at[4], ql[b, 0] - q[b, i, 0], ql[b, 1] - q[b, i, 1], qz, three)
            _vec(obs, b, m, at[5], pl[b, 0] - p[b, i, 0], pl[b, 1] - p[b, i, 1], pz, three)
            _vec(obs, b, m, at[6], acc[b, i, 0], acc[b, i, 1], acc[b, i, 2 if three else 0], three)
            _vec(obs, b, m, at[7], acc[b, j, 0], acc[b, j, 1], acc[b, j, 2 if three else 0], three)
            for s in range(K):
                for k in range(D):
                    obs[b, m, at[8] + s * D + k] = np.float32(nbr_pos[b, m, s, k])
                    obs[b, m, at[9] + s * D + k] = np.float32(nbr_vel[b, m, s, k])
                obs[b, m, at[10] + s] = np.float32(nbr_mask[b, m, s])
        ok = True
        for m in range(obs.shape[1]):
            for k in range(obs.shape[2]):
                ok &= np.isfinite(obs[b, m, k])
        finite[b] = ok
        # the closest two UAVs: the separations leave each partner out, the pair distance adds
        # it (np.min and np.minimum, NaN kept)
        d = np.inf
        for i in range(min_d2.shape[1]):
            v = min_d2[b, i]
            d = v if (v < d or v != v) else d
        d = np.sqrt(d)
        if agents.shape[0] > 0:
            e = res[0, b, 0]
            for m in range(1, agents.shape[0]):
                v = res[0, b, m]
                e = v if (v < e or v != v) else e
            d = d if (d < e or d != d) else e
        closest[b] = d


class AgentPass:
    """The agents' pass of one config and batch: the kernel's constants, resolved once.

    Args:
        cfg: the configuration; layout: its observation layout; agent_uavs, partner_uavs,
        agent_pair, agent_dm: (M,) the agents' indexing (as the core holds it).
    """

    def __init__(self, cfg, layout, agent_uavs, partner_uavs, agent_pair, agent_dm) -> None:
        self.agents, self.partners = agent_uavs, partner_uavs
        self.pairs = np.asarray(agent_pair, dtype=np.int64)
        self.d_m = np.asarray(agent_dm, dtype=np.float64)
        self.prm = np.concatenate([[cfg.surface_slope], reward_params(cfg)])
        self.fixed_sep = np.nan
        if cfg.n_uavs == 2:  # no non-partner UAV at all: the largest finite separation
            self.fixed_sep = separation_bound(cfg)
        self.at = np.array(
            [layout.slice(f).start if f in layout else -1 for f in OBS_FIELDS], np.int64
        )
        self.size = layout.size
        self.dims = (0,) * cfg.dim

    def run(self, q, p, acc, min_d2, leader_q, leader_p, u, pair_out):
        """Observation (B, M, obs_size) float32, the results ``AGENT_ROWS`` (len, B, M)
        float64, whether each swarm's observation is finite (B,) and the distance of its
        closest two UAVs, partners included (B,) (new arrays)."""
        B, M = q.shape[0], self.agents.shape[0]
        obs = np.empty((B, M, self.size), np.float32)
        res = np.empty((len(AGENT_ROWS), B, M))
        finite = np.empty(B, np.bool_)
        closest = np.empty(B)
        pp = pair_out
        state = (q, p, acc, min_d2, leader_q, leader_p)
        neighbors = (pp["shared"], pp["nbr_pos"], pp["nbr_vel"], pp["nbr_mask"])
        args = (self.agents, self.partners, self.pairs, self.d_m, u, self.prm, self.fixed_sep)
        _agents_kernel(state, neighbors, *args, self.at, self.dims, (obs, res, finite, closest))
        return obs, res, finite, closest
