"""PairFlockCore: B swarms of N UAVs in one set of arrays, the engine behind every view.

One control step, in order:

1. validate the pair actions (B, M, dim) (M = 2 x pairs; before any state changes);
2. decode: clip to [-1, 1], scale by ``pair_accel_limit`` to m/s^2 (the pair term f^x);
3. a_des = flocking command of the current state (eqs. 11-19) + f^x on the paired UAVs;
4. the vehicle model integrates ``substeps`` physics steps with a_des held;
5. the clock and the leader advance; one sweep computes the flocking command of the new
   state together with separations, collisions and connectivity; observations, rewards,
   termination (divergence, optional collision) and truncation (episode length) follow.

The flocking command of step 3 was computed at the end of the previous step (or at reset),
so each step does exactly one O(N^2) sweep. Views (PettingZoo, Gymnasium, SB3) only
validate, reshape, name agents and apply their auto-reset rule.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .config import PairFlockConfig, corner_diagonals, make_config
from .dynamics import make_vehicle
from .flocking import FlockingParams, flocking_pass, pair_pass
from .leader import make_leader
from .observations import ObsLayout
from .pairing import sliding_surface
from .rewards import DIVERGENCE_PENALTY, reward_terms
from .seeding import swarm_generators

__all__ = ["AGENT_INFO_KEYS", "SWARM_INFO_KEYS", "PairFlockCore", "SeedLike", "StepResult"]

SeedLike = int | np.random.SeedSequence | None

#: per-agent info arrays, shape (B, M)
AGENT_INFO_KEYS = (
    "pair_distance",
    "pair_error",
    "sliding_surface",
    "min_separation",
    "shared_neighbors",
    "pair_accel",
    "action_clipped",
)
#: per-swarm info arrays, shape (B,)
SWARM_INFO_KEYS = (
    "sim_time",
    "collisions",
    "largest_component",
    "velocity_mismatch",
    "velocity_mismatch_max",
    "diverged",
)

_RESET_OPTIONS = ("positions", "velocities")


@dataclasses.dataclass
class StepResult:
    """What one core step (or reset) returns; every array has leading axis B."""

    obs: np.ndarray
    """(B, M, obs_size) float32, finite."""
    reward: np.ndarray
    """(B, M) float64."""
    terminated: np.ndarray
    """(B,) bool: divergence, or a collision when ``terminate_on_collision``."""
    truncated: np.ndarray
    """(B,) bool: the episode reached ``episode_steps``."""
    info: dict[str, np.ndarray]
    """Arrays named in AGENT_INFO_KEYS (B, M), SWARM_INFO_KEYS (B,) and reward terms (B, M)."""


def real_array(x: Any, name: str, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``x`` as a float64 array; ``TypeError`` naming ``name`` unless it is real (float, int or
    uint), ``ValueError`` unless it has ``shape`` (when given) and is finite. The one check
    behind every view's actions."""
    if not (isinstance(x, np.ndarray) and x.dtype.kind in "fiu"):
        try:
            x = np.asarray(x)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be a numeric array, got {type(x).__name__}") from None
        if x.dtype.kind not in "fiu":
            raise TypeError(f"{name} has dtype {x.dtype}; expected a real (float or int) dtype")
    if shape is not None:
        if x.shape != shape:
            raise ValueError(f"{name} has shape {x.shape}, expected {shape}")
        if not np.isfinite(x).all():
            bad = np.argwhere(~np.isfinite(x))[0].tolist()
            raise ValueError(
                f"{name} contains NaN or inf (first at index {bad}); it must be finite"
            )
    return x.astype(np.float64, copy=False)


class PairFlockCore:
    """Vectorised pair-flocking simulator.

    Args:
        config: a :class:`PairFlockConfig`, or ``None`` to build one from ``preset`` and
            ``overrides``.
        num_envs: number of swarms B simulated side by side.
        seed: seed of the per-swarm generators (see :meth:`reset`).

    Attributes (read-only views of the state; use :meth:`reset` / :meth:`step` to change it):
        q, p: positions and velocities, (B, N, dim) float64.
        t: sim time of each swarm (B,), s.  steps: control steps since reset (B,).
    """

    def __init__(
        self,
        config: PairFlockConfig | None = None,
        num_envs: int = 1,
        seed: SeedLike = None,
        *,
        preset: str | None = "paper",
        **overrides: Any,
    ) -> None:
        if config is None:
            config = make_config(preset, **overrides)
        elif overrides:
            config = config.replace(**overrides)
        if not isinstance(config, PairFlockConfig):
            raise TypeError(f"config={config!r} is invalid: must be a PairFlockConfig")
        if (
            isinstance(num_envs, bool)
            or not isinstance(num_envs, (int, np.integer))
            or num_envs < 1
        ):
            raise ValueError(f"num_envs={num_envs!r} is invalid: must be an integer >= 1")
        self.config = cfg = config
        self.num_envs = B = int(num_envs)
        N, D = cfg.n_uavs, cfg.dim
        self.layout = ObsLayout(D, cfg.obs_neighbors)

        pairs = np.asarray(cfg.pairs, dtype=np.int64)  # (P, 2)
        self.agent_uavs = pairs.reshape(-1).copy()  # (M,) A0, B0, A1, B1, ...
        self.partner_uavs = pairs[:, ::-1].reshape(-1).copy()  # (M,)
        self.agent_pair = np.repeat(np.arange(len(pairs)), 2)  # (M,) pair index of each agent
        self.partner_of = np.full(N, -1, np.int64)
        self.partner_of[self.agent_uavs] = self.partner_uavs
        self._agent_dm = cfg.d_m_array[self.agent_pair]  # (M,)

        self._params = FlockingParams(cfg)
        self._leader = make_leader(cfg)
        self.vehicle = make_vehicle(cfg, B)
        self.q = np.zeros((B, N, D))
        self.p = np.zeros((B, N, D))
        self.t = np.zeros(B)
        self.steps = np.zeros(B, np.int64)
        self._pinned = np.zeros((B, N))
        self._flock_out: dict[str, np.ndarray] | None = None
        self._pair_out: dict[str, np.ndarray] | None = None
        M = 2 * len(pairs)
        self._obs = np.zeros((B, M, self.layout.size), np.float32)
        self._partner_col = np.arange(M) ^ 1  # agent column of each agent's partner
        # ring buffer of the agents' (q, p, flocking command) for the partner delay
        H = cfg.partner_delay + 1
        self._hist = np.zeros((3, H, B, M, D)) if cfg.partner_delay else None
        self._hist_pos = 0
        self._is_reset = np.zeros(B, bool)
        self._rngs: list[np.random.Generator] = [
            g if g is not None else np.random.default_rng() for g in self._make_rngs(seed, B)
        ]

    # ------------------------------------------------------------------ properties
    @property
    def n_agents(self) -> int:
        return self.agent_uavs.shape[0]

    @property
    def obs_size(self) -> int:
        return self.layout.size

    @property
    def action_size(self) -> int:
        return self.config.dim

    @property
    def rngs(self) -> tuple[np.random.Generator, ...]:
        """The per-swarm generators (initial states are drawn from these only)."""
        return tuple(self._rngs)

    def leader_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Virtual leader position and velocity now, each (B, dim)."""
        return self._leader.state(self.t)

    @property
    def flock_accel(self) -> np.ndarray:
        """Flocking command (eq. 11 without f^x) of the current state, (B, N, dim)."""
        self._require_reset()
        return self._flock_out["acc"]

    @property
    def pinned(self) -> np.ndarray:
        """h_i of eq. 6 as 0/1 floats, (B, N)."""
        return self._pinned

    # ------------------------------------------------------------------ seeding
    @staticmethod
    def _make_rngs(seed: Any, n: int) -> list[np.random.Generator]:
        return swarm_generators(seed, n)

    # ------------------------------------------------------------------ reset
    def reset(self, seed: Any = None, options: Mapping[str, Any] | None = None) -> StepResult:
        """Reset every swarm.

        ``seed``: ``None`` continues each swarm's generator; an int or SeedSequence s gives
        swarm b the generator of ``SeedSequence(s).spawn(B)[b]``; a sequence of B entries
        (int, SeedSequence or None) seeds each swarm with its own entry, so swarm b of a
        batch equals a 1-swarm core reset with ``seed=[that entry]``.

        ``options``: ``positions`` / ``velocities`` arrays (N, dim) or (B, N, dim) override
        the random initial state.
        """
        return self.reset_rows(np.arange(self.num_envs), seed=seed, options=options)

    def reset_rows(
        self,
        rows: Sequence[int] | np.ndarray,
        seed: Any = None,
        options: Mapping[str, Any] | None = None,
    ) -> StepResult:
        """Reset only the swarms in ``rows`` (the others keep their state).

        ``seed`` as in :meth:`reset`, with one entry per row when a sequence. Returns the
        full batch's current :class:`StepResult` (zero reward, no flags for reset rows).
        """
        rows = np.asarray(rows, dtype=np.int64).reshape(-1)
        B, D = self.num_envs, self.config.dim
        if rows.size and (rows.min() < 0 or rows.max() >= B):
            raise ValueError(f"rows={rows.tolist()} is invalid: must be in [0, {B - 1}]")
        # --- validate everything before touching state -----------------------------
        new_rngs = None if seed is None else self._make_rngs(seed, len(rows))
        q0 = p0 = None
        if options is not None:
            if not isinstance(options, Mapping):
                raise TypeError(f"options={options!r} is invalid: must be a dict or None")
            unknown = [k for k in options if k not in _RESET_OPTIONS]
            if unknown:
                warnings.warn(
                    f"ignoring unknown reset options {unknown}; known: {list(_RESET_OPTIONS)}",
                    stacklevel=2,
                )
            q0 = self._check_state_option(options, "positions", len(rows))
            p0 = self._check_state_option(options, "velocities", len(rows))
        # --- apply --------------------------------------------------------------------
        if new_rngs is not None:
            for r, g in zip(rows, new_rngs, strict=False):
                if g is not None:
                    self._rngs[r] = g
        lq0, _ = self._leader.state(np.zeros(1))
        for k, r in enumerate(rows):
            q, p = self._initial_state(self._rngs[r])
            if q0 is not None:
                q = q0[k]
            if p0 is not None:
                p = p0[k]
            self.q[r] = q
            self.p[r] = p
            self._pinned[r] = self._pinning_mask(q, lq0[0])
        self.t[rows] = 0.0
        self.steps[rows] = 0
        self.vehicle.reset_rows(rows, self.q, self.p)
        self._is_reset[rows] = True
        zeros_u = np.zeros((B, self.n_agents, D))
        res = self._refresh(zeros_u, np.zeros((B, self.n_agents), bool), reset_rows=rows)
        res.reward[rows] = 0.0
        res.terminated[rows] = False
        res.truncated[rows] = False
        return res

    def _check_state_option(self, options: Mapping[str, Any], key: str, n_rows: int):
        if key not in options or options[key] is None:
            return None
        N, D = self.config.n_uavs, self.config.dim
        try:
            arr = np.asarray(options[key], dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"options[{key!r}] must be a numeric array") from None
        if arr.shape == (N, D):
            arr = np.broadcast_to(arr, (n_rows, N, D))
        if arr.shape != (n_rows, N, D):
            raise ValueError(
                f"options[{key!r}] has shape {arr.shape}, "
                f"expected ({N}, {D}) or ({n_rows}, {N}, {D})"
            )
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"options[{key!r}] contains NaN or inf")
        return arr

    def _initial_state(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        cfg = self.config
        N, D = cfg.n_uavs, cfg.dim
        q = np.empty((N, D))
        fixed = np.zeros(N, bool)
        if cfg.init == "corners":
            diags = corner_diagonals(D) * cfg.vector("pair_corner")
            for k, (a, b) in enumerate(cfg.pairs):
                q[a] = -diags[k]
                q[b] = diags[k]
                fixed[a] = fixed[b] = True
        free = np.flatnonzero(~fixed)
        paired = np.zeros(N, bool)
        paired[self.agent_uavs] = True
        half = np.where(paired[:, None], cfg.vector("pair_corner"), cfg.vector("swarm_half_width"))
        q[free] = rng.uniform(-1.0, 1.0, (free.size, D)) * half[free]
        spacing2 = cfg.min_init_spacing**2
        if spacing2 > 0:
            for _ in range(1000):
                d2 = np.sum((q[:, None, :] - q[None, :, :]) ** 2, axis=-1)
                np.fill_diagonal(d2, np.inf)
                # a free UAV is in conflict with any fixed UAV or any earlier UAV
                earlier = np.tri(N, k=-1, dtype=bool) | fixed[None, :]
                conflict = np.any((d2 < spacing2) & earlier, axis=1) & ~fixed
                if not conflict.any():
                    break
                idx = np.flatnonzero(conflict)
                q[idx] = rng.uniform(-1.0, 1.0, (idx.size, D)) * half[idx]
            else:
                raise ValueError(
                    f"min_init_spacing={cfg.min_init_spacing!r} is invalid: cannot place "
                    f"n_uavs={N} that far apart in the start box "
                    f"(swarm_half_width={cfg.swarm_half_width})"
                )
        return q + cfg.vector("swarm_center"), np.zeros((N, D))

    def _pinning_mask(self, q: np.ndarray, leader_q: np.ndarray) -> np.ndarray:
        pin = self.config.pinning
        N = self.config.n_uavs
        h = np.zeros(N)
        if pin == "all":
            h[:] = 1.0
        elif isinstance(pin, int):
            if pin > 0:
                d = np.linalg.norm(q - leader_q, axis=1)
                h[np.argsort(d, kind="stable")[:pin]] = 1.0
        else:
            h[list(pin)] = 1.0
        return h

    # ------------------------------------------------------------------ step
    def check_actions(self, actions: Any) -> np.ndarray:
        """Validate pair actions: shape (B, M, dim) (or (M, dim) when B = 1), real, finite."""
        B, M, D = self.num_envs, self.n_agents, self.config.dim
        a = real_array(actions, "actions")
        if a.shape != (B, M, D):
            if B == 1 and a.shape == (M, D):
                a = a[None]
            else:
                raise ValueError(f"actions have shape {a.shape}, expected ({B}, {M}, {D})")
        if not np.isfinite(a).all():
            bad = np.argwhere(~np.isfinite(a).all(axis=-1))[0]
            raise ValueError(
                f"actions contain NaN or inf (swarm {bad[0]}, agent {bad[1]}, UAV "
                f"{self.agent_uavs[bad[1]]}); actions must be finite"
            )
        return a

    def step(self, actions: Any) -> StepResult:
        """Advance every swarm by one control period under the given pair actions.

        ``actions`` (B, M, dim): each paired UAV's pairwise acceleration f^x_i in units of
        ``pair_accel_limit``; components outside [-1, 1] are clipped (reported as
        ``action_clipped``). NaN/inf raise ``ValueError`` and leave the state unchanged.
        Swarms whose episode has ended keep integrating; views reset them.
        """
        self._require_reset()
        a = self.check_actions(actions)
        clipped = np.any(np.abs(a) > 1.0, axis=-1)
        u = np.clip(a, -1.0, 1.0) * self.config.pair_accel_limit
        a_des = self._flock_out["acc"].copy()
        a_des[:, self.agent_uavs] += u
        if self.config.disturbance_std > 0:
            a_des += self.config.disturbance_std * self._draw_normal(a_des.shape[1:])
        self.vehicle.advance(self.q, self.p, a_des)
        self.steps += 1
        np.multiply(self.steps, self.config.dt, out=self.t)  # no drift from repeated sums
        return self._refresh(u, clipped)

    def _draw_normal(self, shape: tuple[int, ...]) -> np.ndarray:
        """Standard normal draws (B, *shape), swarm b from its own generator."""
        return np.stack([g.standard_normal(shape) for g in self._rngs])

    def _require_reset(self) -> None:
        if not self._is_reset.all():
            rows = np.flatnonzero(~self._is_reset).tolist()
            raise RuntimeError(f"call reset() before step(): swarms {rows} were never reset")

    # ------------------------------------------------------------------ observation etc.
    def _refresh(
        self, u: np.ndarray, clipped: np.ndarray, reset_rows: np.ndarray | None = None
    ) -> StepResult:
        cfg = self.config
        q, p = self.q, self.p
        lq, lp = self._leader.state(self.t)
        fl = self._flock_out = flocking_pass(
            self._params, q, p, lq, lp, self._pinned, self.partner_of, out=self._flock_out
        )
        pp = self._pair_out = pair_pass(
            q,
            p,
            self.agent_uavs,
            self.partner_uavs,
            cfg.radius,
            cfg.obs_neighbors,
            out=self._pair_out,
        )
        ia, ip = self.agent_uavs, self.partner_uavs
        qa, pa = q[:, ia], p[:, ia]
        off = q[:, ip] - qa
        vel = p[:, ip] - pa
        dist = np.sqrt(np.einsum("bmk,bmk->bm", off, off))
        err = dist - self._agent_dm
        surf = sliding_surface(off, vel, self._agent_dm, cfg.surface_slope)
        min_sep = np.sqrt(fl["min_d2"][:, ia])
        shared = pp["shared"][:, self.agent_pair]
        diverged = fl["diverged"]

        # what the agents perceive of their partner: delayed and/or noisy
        acc = fl["acc"]
        acc_partner = acc[:, ip]
        off_obs, vel_obs = off, vel
        if self._hist is not None:
            H = self._hist.shape[1]
            if reset_rows is None:
                self._hist_pos = (self._hist_pos + 1) % H
            now = np.stack([qa, pa, acc[:, ia]])  # (3, B, M, D)
            self._hist[:, self._hist_pos] = now
            if reset_rows is not None:  # a fresh episode has no older samples
                self._hist[:, :, reset_rows] = now[:, None, reset_rows]
            old = self._hist[:, (self._hist_pos + 1) % H][:, :, self._partner_col]
            off_obs, vel_obs, acc_partner = old[0] - qa, old[1] - pa, old[2]
        if cfg.obs_noise_position > 0 or cfg.obs_noise_velocity > 0:
            z = self._draw_normal((2, *off.shape[1:]))
            off_obs = off_obs + cfg.obs_noise_position * z[:, 0]
            vel_obs = vel_obs + cfg.obs_noise_velocity * z[:, 1]

        # observation, field by field (names from the layout)
        B, M = qa.shape[:2]
        obs = np.empty((B, M, self.layout.size), np.float32)
        sl = self.layout.slice
        obs[..., sl("partner_offset")] = off_obs
        obs[..., sl("partner_velocity")] = vel_obs
        obs[..., sl("target_distance")] = self._agent_dm[None, :, None]
        obs[..., sl("shared_neighbors")] = shared[..., None]
        obs[..., sl("leader_offset")] = lq[:, None, :] - qa
        obs[..., sl("leader_velocity")] = lp[:, None, :] - pa
        obs[..., sl("flock_accel")] = acc[:, ia]
        obs[..., sl("partner_flock_accel")] = acc_partner
        if cfg.obs_neighbors:
            obs[..., sl("neighbor_offsets")] = pp["nbr_pos"].reshape(B, M, -1)
            obs[..., sl("neighbor_velocities")] = pp["nbr_vel"].reshape(B, M, -1)
            obs[..., sl("neighbor_mask")] = pp["nbr_mask"]
        # a diverged swarm keeps its last finite observation
        bad_obs = diverged | ~np.isfinite(obs).all(axis=(1, 2))
        if bad_obs.any():
            obs[bad_obs] = self._obs[bad_obs]
            diverged = diverged | bad_obs
        self._obs = obs

        terms = reward_terms(cfg, err, u, min_sep)
        reward = terms["error"] + terms["effort"] + terms["separation"] + terms["collision"]
        reward[diverged] = -DIVERGENCE_PENALTY
        vinfo = self.vehicle.info()
        terminated = diverged.copy()
        if "vehicle_terminated" in vinfo:  # e.g. a crashed quadrotor
            terminated |= vinfo["vehicle_terminated"]
        if cfg.terminate_on_collision:
            terminated |= np.any(min_sep < cfg.collision_distance, axis=1)
        truncated = (self.steps >= cfg.episode_steps) & ~terminated

        info = {
            "pair_distance": dist,
            "pair_error": err,
            "sliding_surface": surf,
            "min_separation": min_sep,
            "shared_neighbors": shared,
            "pair_accel": np.sqrt(np.einsum("bmk,bmk->bm", u, u)),
            "action_clipped": clipped,
            "sim_time": self.t.copy(),
            "collisions": fl["collisions"].copy(),
            "largest_component": fl["largest_component"].copy(),
            "velocity_mismatch": fl["velocity_mismatch"].copy(),
            "velocity_mismatch_max": fl["velocity_mismatch_max"].copy(),
            "diverged": diverged,
        }
        for k, v in terms.items():
            info[f"reward_{k}"] = v
        info.update(vinfo)
        return StepResult(obs, reward, terminated, truncated, info)

    def observe(self) -> np.ndarray:
        """The current observation (B, M, obs_size), float32 (a copy)."""
        self._require_reset()
        return self._obs.copy()
