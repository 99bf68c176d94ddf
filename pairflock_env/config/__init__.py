"""Frozen, validated configuration of a pair-flocking swarm, declared field by field.

Every quantity is in SI units (m, s, m/s, m/s^2). Equation numbers refer to Liu et al.,
"Pairwise Control in Unmanned Aerial Vehicle Swarm Flocking" (see ``docs/paper-notes.md``
for the errata this project follows).

A configuration is one flat frozen dataclass, :class:`PairFlockConfig`, so that every view
(PettingZoo, Gymnasium, SB3) accepts the same keyword overrides::

    cfg = make_config("paper", n_uavs=100, d_m=4.0)
    cfg.radius, cfg.section("flocking").radius       # flat, or by section

Its fields are *declared* in sections (swarm, timing, flocking, leader, pair task, initial
state, reward, observation, robustness, quadrotor, safety; :mod:`.sections`): each declaration
gives the type and valid range (a :class:`~.fields.Kind`), the default, the unit and the meaning.
Validation, error messages, the tables of ``docs/config.md`` and the derived checks are all
generated from the declarations. An unknown keyword raises ``TypeError`` with a did-you-mean
hint; a wrong type ``TypeError``; a bad value ``ValueError``; each names the field, the value
and what is valid. Rules between fields (``radius > spacing``, ...) and derived quantities
(sigma^2, episode steps, the physics step, the memory of the delay buffer, the largest reward
penalty, ...) are checked at construction, so an accepted config runs: the documented limits
(:mod:`.limits`) keep every step finite and bounded in time and memory.

How to add a config field
-------------------------
Add one :class:`~.fields.Field` to the section it belongs to in :mod:`.sections`, e.g. in
``sections/swarm.py``::

    Field("neighbor_search", Choice(("all_pairs", "grid")), "all_pairs", "",
          "How neighbours are found: ...")

That single declaration makes ``cfg.neighbor_search``, the keyword override
``parallel_env(neighbor_search="grid")``, its validation, its did-you-mean entry and its row in
``docs/config.md``. If its valid values depend on another field, give the kind ``needs`` (see
``Vector``) or add a :class:`~.schema.Rule`; if a product or ratio of fields must stay finite,
add a :class:`~.schema.Derived`. Regenerate the docs with
``python -m pairflock_env.config.docs docs/config.md`` (a test fails while they are stale). A
renamed field keeps no old keyword; if files already store the old name (a trained model's
config), add it to :data:`pairflock_env.compat.STORED_RENAMES`, which ``from_dict`` reads.
"""

from __future__ import annotations

from pairflock_env.config.fields import UnknownFieldError
from pairflock_env.config.limits import LIMITS
from pairflock_env.config.model import SCHEMA, ConfigSection, PairFlockConfig, field_names
from pairflock_env.config.presets import PRESETS, make_config, preset_names
from pairflock_env.config.sections.initial_state import corner_diagonals

__all__ = [
    "LIMITS",
    "PRESETS",
    "SCHEMA",
    "ConfigSection",
    "PairFlockConfig",
    "UnknownFieldError",
    "corner_diagonals",
    "field_names",
    "make_config",
    "preset_names",
]
