"""A decentralised, minimally invasive safety filter for the paired UAVs (docs/safety.md).

Each paired UAV replaces its nominal pair command u_nom by the command nearest to it (in the
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

:mod:`.qp` holds the exact solver of the per-agent problem, :mod:`.barrier` the constraints
and the batched numba kernel, :mod:`.params` the parameters.
"""

from pairflock_env.safety.cbf.barrier import SafetyFilter, SafetyOutput, safety_filter
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.safety.cbf.qp import (
    STATUS_INFEASIBLE,
    STATUS_NOMINAL,
    STATUS_PROJECTED,
    max_margin,
    project,
)

__all__ = [
    "STATUS_INFEASIBLE",
    "STATUS_NOMINAL",
    "STATUS_PROJECTED",
    "SafetyFilter",
    "SafetyOutput",
    "SafetyParams",
    "max_margin",
    "project",
    "safety_filter",
]
