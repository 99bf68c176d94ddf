"""Named flat layouts: a flat vector read and written field by field, and documented from the
same object.

Three vectors of the env are such layouts: an agent's observation
(:class:`~pairflock_env.task.observations.ObsLayout`), a swarm's global state
(:class:`~pairflock_env.task.spaces.StateLayout`) and the pair interface's encoded observation
(:class:`~pairflock_env.interfaces.pair.PairInterface`). Code reads them by name
(``layout.get(obs, "partner_offset")``), never by index, and the docs tables come from
:meth:`FlatLayout.markdown_table`, so code and docs cannot drift apart.

    >>> lay = FlatLayout([Field("x", (2,), "m", "position"), Field("on", (1,), "0/1", "flag")])
    >>> lay.size, lay.slice("on")
    (3, slice(2, 3, None))
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Iterator, Mapping

import numpy as np

__all__ = ["Field", "FlatLayout"]


@dataclasses.dataclass(frozen=True)
class Field:
    """One named field of a flat layout: its shape, unit and meaning."""

    name: str
    shape: tuple[int, ...]
    unit: str
    description: str

    @property
    def size(self) -> int:
        """Number of values of the field in the flat vector."""
        return math.prod(self.shape)


class FlatLayout:
    """Ordered named fields of a flat vector; fields of size 0 are left out.

    Args:
        fields: the fields, in order.
        what: what one vector is, for messages ("observation", "state").
    """

    def __init__(self, fields: Iterable[Field], what: str = "vector") -> None:
        self.what = what
        self.fields: tuple[Field, ...] = tuple(f for f in fields if f.size > 0)
        self._slices: dict[str, slice] = {}
        offset = 0
        for f in self.fields:
            if f.name in self._slices:
                raise ValueError(f"field {f.name!r} appears twice in the {what} layout")
            self._slices[f.name] = slice(offset, offset + f.size)
            offset += f.size
        self.size = offset
        self._by_name = {f.name: f for f in self.fields}
        # what fill() needs per field, resolved once
        self._plan = tuple((f.name, self._slices[f.name], f.size) for f in self.fields)

    def __iter__(self) -> Iterator[Field]:
        return iter(self.fields)

    def __contains__(self, name: str) -> bool:
        return name in self._slices

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self._slices)

    def slice(self, name: str) -> slice:
        """Where field ``name`` lies in the flat vector (``KeyError`` naming the fields)."""
        try:
            return self._slices[name]
        except KeyError:
            raise KeyError(
                f"no {self.what} field {name!r}; fields are {', '.join(self.names)}"
            ) from None

    def _check_size(self, x: np.ndarray) -> None:
        if x.shape[-1] != self.size:
            raise ValueError(
                f"{self.what} has last dimension {x.shape[-1]}, expected {self.size}"
                f"{self._size_hint()}"
            )

    def _size_hint(self) -> str:
        return ""

    def get(self, x: np.ndarray, name: str) -> np.ndarray:
        """The named field of ``x`` (..., size) with its own shape: (..., *field.shape)."""
        x = np.asarray(x)
        self._check_size(x)
        sl = self.slice(name)  # raises KeyError with the names
        return x[..., sl].reshape(x.shape[:-1] + self._by_name[name].shape)

    def fill(
        self, lead: tuple[int, ...], values: Mapping[str, np.ndarray], dtype=np.float32
    ) -> np.ndarray:
        """A new vector (*lead, size) filled field by field by name.

        ``values`` holds an array per field, shaped (*lead, *field.shape) or broadcastable to
        it with its own leading axes (e.g. (1, M, 1) for one value per agent); names the
        layout does not hold (fields of size 0) are ignored. ``KeyError`` for a missing one.
        """
        out = np.empty((*lead, self.size), dtype)
        n = len(lead)
        lead_index = (slice(None),) * n  # out[:, :, sl] rather than out[..., sl]: faster
        for name, sl, size in self._plan:
            try:
                v = values[name]
            except KeyError:
                raise KeyError(f"no values for {self.what} field {name!r}") from None
            out[(*lead_index, sl)] = v if v.ndim == n + 1 else v.reshape((*v.shape[:n], size))
        return out

    def markdown_table(self) -> str:
        """The layout as a markdown table: slice, field, shape, unit, meaning."""
        rows = ["| slice | field | shape | unit | meaning |", "|---|---|---|---|---|"]
        for f in self.fields:
            s = self._slices[f.name]
            rows.append(
                f"| {s.start}:{s.stop} | `{f.name}` | {f.shape} | {f.unit} | {f.description} |"
            )
        return "\n".join(rows)
