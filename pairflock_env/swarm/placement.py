"""Initial placement and pinning of one swarm: pure functions of the config, the swarm's
generator and the paired UAVs.

Placement (``config.init``):

* ``"corners"``: the members of pair k start at -/+ the k-th corner diagonal scaled by
  ``pair_corner`` (fixed, no random draw); ``"random"``: they are drawn like the others;
* every other UAV is drawn uniformly in the start box: +-``pair_corner`` per axis for paired
  UAVs, +-``swarm_half_width`` for unpaired ones, one ``rng.uniform(-1, 1, (n, dim))`` call;
* with ``min_init_spacing`` > 0, every free UAV closer than that to a fixed UAV or to a UAV of
  lower index is redrawn (all such UAVs in one call per round), for at most 1,000 rounds; a
  neighbour grid finds the conflicts (:mod:`~pairflock_env.swarm.spacing`), so a round
  costs O(N) time and memory;
* the whole swarm is then shifted by ``swarm_center``; velocities start at zero.

Pinning (h_i of eq. 6, ``config.pinning``): ``"all"``, an int k (the k UAVs nearest the
leader's initial position, ties by index, found in O(N)) or a sequence of UAV indices.

The random draws are made in exactly this order, so a seed gives the same swarm every time.

Reset options (:func:`check_reset_options`) replace the drawn positions and/or velocities:
arrays (N, dim) for every reset swarm, or (n_rows, N, dim), finite.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from pairflock_env.config import PairFlockConfig, corner_diagonals
from pairflock_env.config.arrays import real_array
from pairflock_env.swarm.grid import nearest_indices
from pairflock_env.swarm.spacing import redraw_conflicts

__all__ = [
    "MAX_PLACEMENT_ROUNDS",
    "RESET_OPTIONS",
    "check_reset_options",
    "initial_state",
    "pinning_mask",
]

#: rounds of redraws before placement under ``min_init_spacing`` gives up
MAX_PLACEMENT_ROUNDS = 1000
#: the keys of reset options that set the initial state
RESET_OPTIONS = ("positions", "velocities")


def initial_state(
    cfg: PairFlockConfig, rng: np.random.Generator, agent_uavs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Initial positions and velocities (N, dim) of one swarm.

    Args:
        cfg: the configuration (placement fields as in the module docstring).
        rng: the swarm's generator; only it is drawn from.
        agent_uavs: indices of the paired UAVs (M,).

    Raises:
        ValueError: the UAVs cannot be placed ``min_init_spacing`` apart in the start box.
    """
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
    paired[agent_uavs] = True
    half = np.where(paired[:, None], cfg.vector("pair_corner"), cfg.vector("swarm_half_width"))
    q[free] = rng.uniform(-1.0, 1.0, (free.size, D)) * half[free]
    if cfg.min_init_spacing > 0:
        _spread_out(cfg, rng, q, fixed, half)
    return q + cfg.vector("swarm_center"), np.zeros((N, D))


def _spread_out(
    cfg: PairFlockConfig,
    rng: np.random.Generator,
    q: np.ndarray,
    fixed: np.ndarray,
    half: np.ndarray,
) -> None:
    """Redraw free UAVs in place until no two are closer than ``min_init_spacing`` (a grid
    finds the conflicts: O(N) memory and work per round, same draws as an N x N test)."""
    if not redraw_conflicts(rng, q, half, fixed, cfg.min_init_spacing, MAX_PLACEMENT_ROUNDS):
        raise ValueError(
            f"min_init_spacing={cfg.min_init_spacing!r} is invalid: cannot place "
            f"n_uavs={q.shape[0]} that far apart in the start box "
            f"(swarm_half_width={cfg.swarm_half_width})"
        )


def pinning_mask(cfg: PairFlockConfig, q: np.ndarray, leader_q: np.ndarray) -> np.ndarray:
    """h_i of eq. 6 as 0/1 floats (N,) for positions ``q`` (N, dim) and the leader at
    ``leader_q`` (dim,)."""
    pin = cfg.pinning
    h = np.zeros(cfg.n_uavs)
    if pin == "all":
        h[:] = 1.0
    elif isinstance(pin, int):
        if pin > 0:
            h[nearest_indices(q, leader_q, pin)] = 1.0
    else:
        h[list(pin)] = 1.0
    return h


def check_reset_options(
    options: Mapping[str, Any] | None, n_rows: int, n_uavs: int, dim: int, name: str = "options"
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Validated ``positions`` and ``velocities`` of reset options, each (n_rows, N, dim) or
    ``None`` when not given: the one check of reset options, for every view.

    Values go through the same check as actions
    (:func:`~pairflock_env.task.actions.real_array`): real numbers only (no bools, complex
    numbers, strings or masked entries), finite. Raises ``TypeError`` (options not a dict,
    values not real numbers) or ``ValueError`` (a wrong shape, masked entries, NaN or inf),
    naming ``name``; unknown keys are ignored with a warning.
    """
    if options is None:
        return None, None
    if not isinstance(options, Mapping):
        raise TypeError(f"{name}={options!r} is invalid: must be a dict or None")
    unknown = [k for k in options if k not in RESET_OPTIONS]
    if unknown:
        warnings.warn(
            f"ignoring unknown reset options {unknown}; known: {list(RESET_OPTIONS)}",
            stacklevel=3,
        )
    q0 = _state_option(options, "positions", n_rows, n_uavs, dim, name)
    p0 = _state_option(options, "velocities", n_rows, n_uavs, dim, name)
    return q0, p0


def _state_option(
    options: Mapping[str, Any], key: str, n_rows: int, N: int, D: int, name: str
) -> np.ndarray | None:
    if key not in options or options[key] is None:
        return None
    what = f"{name}[{key!r}]"
    arr = real_array(options[key], what)
    if arr.shape == (N, D):
        arr = np.broadcast_to(arr, (n_rows, N, D))
    if arr.shape != (n_rows, N, D):
        raise ValueError(
            f"{what} has shape {arr.shape}, expected ({N}, {D}) or ({n_rows}, {N}, {D})"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} contains NaN or inf")
    return arr
