"""``dynamics="crazyflie"``: a Crazyflie 2.x under its firmware's Mellinger controller
(docs/crazyflie.md).

The identified first-principles model of ``drone-models`` and the Mellinger controller of
``drone-controllers`` (the firmware's, with its saturations), ported to one numba kernel over
(B, N) UAVs and fed with the protocol's desired acceleration as Crazyswarm2's cmdFullState
feeds a Crazyflie. The packages are test oracles only (the ``crazyflie`` extra); the parameter
sets are data here.

* :mod:`.data` - the identified parameter sets and the firmware's constants and gains;
* :mod:`.section` - the config section ``crazyflie`` (fields, rules, the filter's defaults);
* :mod:`.kernels` - the numba kernels and their parameter layout;
* :mod:`.params` - a config packed for the kernels;
* :mod:`.model` - :class:`CrazyflieModel` (the vehicle) and :func:`quat_xyzw`.

Importing this package registers the vehicle in :data:`~pairflock_env.dynamics.VEHICLES`
(through the plug-in seam, which declares its config section).
"""

from __future__ import annotations

from pairflock_env.config.registry import VEHICLES
from pairflock_env.dynamics.crazyflie import section
from pairflock_env.dynamics.crazyflie.data import CRAZYFLIE_MODELS
from pairflock_env.dynamics.crazyflie.model import CMD_FIELDS, CrazyflieModel, quat_xyzw
from pairflock_env.dynamics.crazyflie.params import CrazyflieParams
from pairflock_env.dynamics.vehicle import Vehicle

__all__ = [
    "CMD_FIELDS",
    "CRAZYFLIE_MODELS",
    "CrazyflieModel",
    "CrazyflieParams",
    "quat_xyzw",
]

VEHICLES.register(
    Vehicle(
        name=section.NAME,
        doc="Crazyflie 2.x: identified first-principles model (drone-models) under the "
        "firmware's Mellinger controller, fed cmdFullState setpoints (docs/crazyflie.md)",
        section=section.CRAZYFLIE,
        rules=section.RULES,
        model=CrazyflieModel,
        dims=(3,),
        substeps=section.default_substeps,
        accel_bound=section.accel_bound,
        reaction_time=section.reaction_time,
        safety_decay=0.1,
        info_keys=CrazyflieModel.INFO_KEYS,
    )
)
