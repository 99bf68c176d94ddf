"""Safety filters between the decoded pair command and the vehicle model, and their registry
:data:`FILTERS` (``safety_filter``: ``"none"``, ``"cbf"``, or a registered plug-in).

``"cbf"`` is a decentralised, minimally invasive filter for the paired UAVs (docs/safety.md):
each paired UAV replaces its nominal pair command u_nom by the command nearest to it (in the
Euclidean norm, within ``||u|| <= accel_limit``) that satisfies one discrete-time
braking-distance barrier constraint per UAV it senses, so that it keeps ``safety_distance``
from every other UAV under the stated assumptions:

>>> import numpy as np
>>> from pairflock_env.safety import SafetyFilter, SafetyParams
>>> filt = SafetyFilter(SafetyParams(accel_limit=50.0), agents=[0, 1], n_uavs=3)
>>> q = np.array([[[0.0, 0.0], [30.0, 0.0], [3.0, 0.0]]])  # UAV 2 is 3 m ahead of UAV 0
>>> p = np.array([[[20.0, 0.0], [0.0, 0.0], [0.0, 0.0]]])  # ... and UAV 0 closes at 20 m/s
>>> u_nom = np.array([[[50.0, 0.0], [0.0, 0.0]]])  # UAV 0 is told to speed up
>>> out = filt.apply(q, p, np.zeros((1, 2, 2)), u_nom)
>>> bool(out.active[0, 0]), bool(out.u[0, 0, 0] < 0)  # the filter brakes instead
(True, True)

With ``safety_scope="swarm"`` every UAV, paired or not, filters its whole command the same
way (:class:`SwarmFilter`, docs/swarm-safety.md).

:mod:`.cbf.qp` holds the exact solver of the per-agent problem, :mod:`.cbf.barrier` the
constraints and the batched numba kernel, :mod:`.cbf.swarm` the swarm layer,
:mod:`.cbf.params` the parameters, :mod:`.stage` what the core holds.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from pairflock_env.config.registry import FILTERS, Plugin
from pairflock_env.safety.cbf.barrier import SafetyFilter, SafetyOutput, safety_filter
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.safety.cbf.qp import (
    STATUS_INFEASIBLE,
    STATUS_NOMINAL,
    STATUS_PROJECTED,
    max_margin,
    project,
)
from pairflock_env.safety.cbf.swarm import SwarmFilter, SwarmOutput
from pairflock_env.safety.stage import (
    SAFETY_INFO_KEYS,
    SAFETY_SWARM_INFO_KEYS,
    CBFStage,
    NoFilterStage,
    SwarmStage,
    cbf_stage,
)

__all__ = [
    "FILTERS",
    "SAFETY_INFO_KEYS",
    "SAFETY_SWARM_INFO_KEYS",
    "STATUS_INFEASIBLE",
    "STATUS_NOMINAL",
    "STATUS_PROJECTED",
    "CBFStage",
    "Filter",
    "NoFilterStage",
    "SafetyFilter",
    "SafetyOutput",
    "SafetyParams",
    "SwarmFilter",
    "SwarmOutput",
    "SwarmStage",
    "make_safety_stage",
    "max_margin",
    "project",
    "safety_filter",
]


@dataclasses.dataclass(frozen=True, kw_only=True)
class Filter(Plugin):
    """A registered safety filter.

    Attributes (besides :class:`~pairflock_env.config.registry.Plugin`'s):
        stage: builds what the core holds, ``stage(config, agent_uavs, num_swarms,
            partner_uavs)``, with ``apply(q, p, flock_acc, u, grid) -> u`` (B, M, dim) and
            ``info(reset=False)`` -> arrays (B, M) or (B,) that include ``SAFETY_INFO_KEYS``
            (and, optionally, the per-swarm counts ``SAFETY_SWARM_INFO_KEYS``; else the
            core counts the agents). A stage that filters every UAV's whole command sets
            ``whole_command`` (B, N, dim) in ``apply``; the core applies it.
        info_keys: the keys its ``info`` adds to ``SAFETY_INFO_KEYS``.
        scopes: the values of ``safety_scope`` it supports ("pairs": the paired UAVs'
            commands; "swarm": every UAV's).
    """

    stage: Callable[..., Any]
    info_keys: tuple[str, ...] = ()
    scopes: tuple[str, ...] = ("pairs",)


def make_safety_stage(config: Any, agent_uavs: Any, num_swarms: int, partner_uavs: Any) -> Any:
    """The stage of the filter ``config.safety_filter`` for a core."""
    return FILTERS[config.safety_filter].stage(config, agent_uavs, num_swarms, partner_uavs)


FILTERS.register(
    Filter(name="none", doc="the pair command is applied as decoded", stage=NoFilterStage)
)
FILTERS.register(
    Filter(
        name="cbf",
        doc="every paired UAV (safety_scope='swarm': every UAV) keeps safety_distance from "
        "every UAV it senses (docs/safety.md, docs/swarm-safety.md)",
        stage=cbf_stage,
        scopes=("pairs", "swarm"),
    )
)
