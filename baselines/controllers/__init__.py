"""Pair controllers: everything that fills the env's pair action slot.

* :mod:`~baselines.controllers.base` - :class:`PairPolicy` (SB3's ``predict`` over named
  observations), :class:`ZeroPolicy`, :func:`resolve_env`;
* :mod:`~baselines.controllers.sliding_mode` - eq. 28; :mod:`~baselines.controllers.proportional`
  - eq. 44; :mod:`~baselines.controllers.braking` - a braking-curve law within a ball (not in
  the paper; the small-budget reference); :mod:`~baselines.controllers.sb3` - the
  ``"sb3:<model.zip>"`` loader (SB3/torch, imported only when asked for);
  :mod:`~baselines.controllers.zoo` - the packaged policies (``"sb3:pair_n20_a50"``) and the
  lookup of packaged files by name;
* :mod:`~baselines.controllers.registry` - :data:`POLICIES` and :func:`make_pair_policy`.

This layer imports only :mod:`pairflock_env` (never evaluation, reporting or training code).
"""

from __future__ import annotations

from baselines.controllers.base import PairPolicy, ZeroPolicy, resolve_env
from baselines.controllers.braking import BrakingCurveController
from baselines.controllers.proportional import ProportionalController
from baselines.controllers.registry import POLICIES, make_pair_policy
from baselines.controllers.sliding_mode import SlidingModeController

__all__ = [
    "POLICIES",
    "BrakingCurveController",
    "PairPolicy",
    "ProportionalController",
    "SlidingModeController",
    "ZeroPolicy",
    "make_pair_policy",
    "resolve_env",
]
