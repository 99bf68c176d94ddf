"""Declared parameters of the pair learning interface (``interface="pair"``).

:class:`PairInterfaceParams` holds the parameters of
:class:`pairflock_env.interfaces.PairInterface` (given as ``interface_params={...}`` to the
learning views and stored with every trained model). It is declared like
:class:`~pairflock_env.config.PairFlockConfig` (type, unit, range, default and meaning per
field), so that validation, messages and its table in ``docs/config.md`` come from one place.
"""

from __future__ import annotations

from pairflock_env.config.fields import Field, Flag, Int, OrNone, Real
from pairflock_env.config.schema import Record, Schema, Section, declare_record

__all__ = ["PAIR_INTERFACE_SCHEMA", "PairInterfaceParams"]

_SCALE = Real(1e-6, 1e9)
_W = Real(0.0, 1e6)
_ACCEL = OrNone(Real(1e-6, 1e6), "the config's pair_accel_limit, then stored")
_SECTION = Section(
    "pair_interface",
    "Pair-frame learning interface",
    'interface="pair" (pairflock_env.interfaces); give them as interface_params={...}.',
    (
        Field(
            "decision_period",
            Int(1, 10_000),
            5,
            "steps",
            "Control steps the policy action is held (policy period = decision_period * dt).",
        ),
        Field(
            "accel_scale",
            _ACCEL,
            None,
            "m/s^2",
            "Acceleration per unit of the policy action along a pair axis; None: the config's "
            "pair_accel_limit of the env the interface is first built for (then stored).",
        ),
        Field(
            "max_accel",
            OrNone(Real(1e-6, 1e6), "accel_scale"),
            None,
            "m/s^2",
            "Bound on the magnitude of the applied pair acceleration ||u_i||, kept with the "
            "model so a policy trained under a limit obeys it in any env (the env's own "
            "pair_accel_limit applies too, whichever is smaller); None: accel_scale.",
        ),
        Field(
            "feedforward",
            Flag(),
            True,
            "",
            "Add 1/2 (f_partner - f_self), cancelling the flocking difference on the pair.",
        ),
        Field("position_scale", _SCALE, 50.0, "m", "The linear pair-error feature is e / this."),
        Field("velocity_scale", _SCALE, 50.0, "m/s", "Linear velocity features are v / this."),
        Field(
            "fine_position",
            _SCALE,
            0.05,
            "m",
            "The symlog pair-error feature is symlog(e / fine_position) / 8.",
        ),
        Field(
            "fine_velocity",
            _SCALE,
            0.1,
            "m/s",
            "The symlog velocity features are symlog(v / fine_velocity) / 8.",
        ),
        Field(
            "neighbor_scale",
            _SCALE,
            10.0,
            "m",
            "Neighbour offsets and closest-approach distances are divided by this.",
        ),
        Field(
            "tca_horizon",
            Real(1e-6, 1e3),
            1.0,
            "s",
            "Time to closest approach is clipped to [0, tca_horizon] and divided by it.",
        ),
        Field(
            "threat_neighbors",
            OrNone(Int(0, 1_000), "min(6, obs_neighbors)"),
            None,
            "UAVs",
            "How many of the config's obs_neighbors nearest UAVs the policy sees, the most "
            "threatening first (smallest distance at closest approach).",
        ),
        Field(
            "error_scale",
            _SCALE,
            0.05,
            "m",
            "Accuracy scale of the reward's log(1 + |e| / error_scale).",
        ),
        Field("w_error", _W, 0.1, "1", "Weight of log(1 + |e| / error_scale)."),
        Field("w_progress", _W, 0.1, "1", "Weight of |e| / position_scale."),
        Field("w_band", _W, 0.0, "1", "Cost per control step while |e| > band."),
        Field(
            "band",
            _SCALE,
            0.5,
            "m",
            "Half-width of the band of the band term (the reproduction's \"into the 0.5 m "
            'band" time).',
        ),
        Field("w_effort", _W, 0.05, "1", "Weight of ||a||^2 / dim (a: the policy action)."),
        Field(
            "w_separation",
            _W,
            5.0,
            "1",
            "Weight of max(0, separation_distance - s) / separation_distance.",
        ),
        Field(
            "separation_distance",
            Real(1e-3, 1e5),
            2.0,
            "m",
            "Below this distance to a non-partner UAV the separation penalty grows linearly.",
        ),
        Field(
            "approach_horizon",
            Real(0.0, 1e3),
            0.5,
            "s",
            "The separation penalty uses the smaller of the distance now and the closest "
            "approach to an observed neighbour within this time at constant velocities (0: "
            "now only).",
        ),
        Field("w_collision", _W, 5.0, "1", "Penalty per step while s < collision_distance."),
        Field(
            "w_cohesion",
            _W,
            0.1,
            "1",
            "Weight of max(0, s - cohesion_distance) / position_scale.",
        ),
        Field(
            "cohesion_distance",
            OrNone(Real(1e-3, 1e7), "the perception radius"),
            None,
            "m",
            "A UAV whose nearest non-partner UAV is farther than this has left the flock.",
        ),
    ),
)

#: the declared parameters of :class:`PairInterfaceParams`
PAIR_INTERFACE_SCHEMA = Schema("pair-interface parameter", (_SECTION,))


class _Stored(Record):
    stored_as = "interface"


PairInterfaceParams = declare_record(
    "PairInterfaceParams",
    PAIR_INTERFACE_SCHEMA,
    _Stored,
    "pairflock_env.interfaces",  # where users import it from (and old pickles find it)
    """Parameters of :class:`PairInterface` (units and ranges: docs/config.md).

    A frozen dataclass with keyword-only construction; unknown names raise ``TypeError`` with
    a did-you-mean hint, bad values ``ValueError``, each naming the parameter.
    """,
)
