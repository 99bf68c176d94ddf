"""The record :class:`PairFlockConfig`, generated from the declared sections."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from pairflock_env.config.registry import FILTERS, LEADERS, OBSERVATIONS, VEHICLES, Plugin
from pairflock_env.config.schema import Record, Schema, declare_record, refresh_signature
from pairflock_env.config.sections import DERIVED, RULES, SECTIONS
from pairflock_env.config.sections.flocking import repulsion_sigma2
from pairflock_env.config.sections.swarm import uses_grid
from pairflock_env.config.sections.timing import episode_steps, physics_dt

__all__ = ["SCHEMA", "ConfigSection", "PairFlockConfig", "field_names"]

SCHEMA = Schema("configuration field", SECTIONS, RULES, DERIVED)


class ConfigSection(Mapping[str, Any]):
    """The values of one section of a config: read-only, by attribute or by key.

    >>> from pairflock_env import make_config
    >>> make_config("paper").section("flocking").radius
    8.4
    """

    def __init__(self, name: str, title: str, values: Mapping[str, Any]) -> None:
        self._name, self._title, self._values = name, title, dict(values)

    @property
    def name(self) -> str:
        return self._name

    @property
    def title(self) -> str:
        return self._title

    def __getattr__(self, key: str) -> Any:
        try:
            return self.__dict__["_values"][key]
        except KeyError:
            raise AttributeError(f"section {self._name!r} has no field {key!r}") from None

    def __getitem__(self, key: str) -> Any:
        return self._values[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        body = ", ".join(f"{k}={v!r}" for k, v in self._values.items())
        return f"ConfigSection({self._name!r}: {body})"


class _PairFlockConfigMethods(Record):
    """Derived quantities and section views of :class:`PairFlockConfig`."""

    stored_as = "config"

    @property
    def n_pairs(self) -> int:
        """Number of pairs."""
        return len(self.pairs)

    @property
    def n_agents(self) -> int:
        """Number of paired UAVs (the PettingZoo agents)."""
        return 2 * len(self.pairs)

    @property
    def episode_steps(self) -> int:
        """Control steps per episode (``max_cycles`` or ``round(horizon / dt)``)."""
        return episode_steps(self)

    @property
    def uses_grid(self) -> bool:
        """Whether the neighbour search is the grid (``neighbor_search``, "auto" resolved
        by ``n_uavs``)."""
        return uses_grid(self)

    @property
    def physics_dt(self) -> float:
        """Physics step dt / substeps (s)."""
        return physics_dt(self)

    @property
    def repulsion_sigma2(self) -> float:
        """sigma^2 of the repulsion, chosen so that g_r(spacing) = attraction."""
        return repulsion_sigma2(self)

    @property
    def d_m_array(self) -> np.ndarray:
        """d_m per pair, shape (n_pairs,)."""
        return np.asarray(self.d_m, dtype=np.float64)

    def vector(self, name: str) -> np.ndarray:
        """A vector field as a float64 array (a box given as one number stays 0-d)."""
        return np.asarray(getattr(self, name), dtype=np.float64)

    def section(self, name: str) -> ConfigSection:
        """The values of one section (``"swarm"``, ``"flocking"``, ...; see
        ``docs/config.md``), e.g. ``cfg.section("flocking").radius``."""
        sec = self.schema.section(name)
        return ConfigSection(
            sec.name, sec.title, {f.name: getattr(self, f.name) for f in sec.fields}
        )

    def sections(self) -> dict[str, ConfigSection]:
        """Every section, by name, in the order of the docs."""
        return {s.name: self.section(s.name) for s in self.schema.sections}


_DOC = """All parameters of one pair-flocking task, in sections (docs/config.md).

A frozen record with one flat field per declared parameter, so that every view
(PettingZoo, Gymnasium, SB3) accepts the same keyword overrides, and ``cfg.n_uavs``,
``cfg.quad_mass`` ... read the values. ``cfg.section("flocking")`` groups one section's values.
The constructor takes keywords only; it validates every field against its declared type and
range, then the rules between fields and the derived quantities, and raises ``TypeError``
(wrong type, unknown keyword, with a did-you-mean hint) or ``ValueError`` (bad value) naming
the field, the value and what is valid. ``dim`` and ``substeps`` follow ``dynamics`` unless
given. Values are normalised: vectors are tuples of floats (a scalar broadcast to ``dim``),
``d_m`` holds one value per pair, numbers are Python ints and floats.

Build configs with :func:`make_config` (a preset plus overrides); change one with
:meth:`replace`; store one with :meth:`to_dict` and load it back with :meth:`from_dict`
(stored dicts of older releases go through :func:`pairflock_env.compat.upgrade_stored`).
"""

PairFlockConfig = declare_record(
    "PairFlockConfig", SCHEMA, _PairFlockConfigMethods, "pairflock_env.config", _DOC
)


def field_names() -> tuple[str, ...]:
    """Every field of :class:`PairFlockConfig`, in section order."""
    return tuple(SCHEMA.fields)


def _declare(entry: Plugin) -> None:
    """Declare a registered plug-in's own config section (a built-in one is declared
    already) and re-derive the order the fields are checked in."""
    sec = entry.section
    new = sec is not None and all(s.name != sec.name for s in SCHEMA.sections)
    if new:
        SCHEMA.add((sec,), entry.rules, entry.derived)
        refresh_signature(PairFlockConfig)
    else:
        SCHEMA.add()


for _registry in (VEHICLES, FILTERS, LEADERS, OBSERVATIONS):
    _registry.declare = _declare
