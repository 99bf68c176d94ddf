"""How the env's numba kernels are compiled and how they receive their parameters.

Kernels are compiled without numba's reference counting (``jit_kernel``, ``jit_inline``): they
never allocate, and the count updates that numba adds around inlined helpers taking arrays
inside branchy loops (which its pruning pass cannot remove, numba issue #2350) cost 5-30x in
the pair loops.

Parameters travel as one float64 vector per kernel family, laid out by a
:class:`KernelParams`: its ``index`` is a namedtuple of positions that numba reads as
compile-time constants, so a kernel writes ``prm[F.attraction]`` and the Python side packs
the same names with :meth:`KernelParams.pack`. One layout, one name per quantity, from the
config to the kernel.

    >>> F = KernelParams("Demo", ("gain", "limit"))
    >>> F.pack(gain=2.0, limit=5.0)[F.index.limit]
    np.float64(5.0)
"""

from __future__ import annotations

import functools
from collections import namedtuple
from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import njit

__all__ = ["KernelParams", "jit_inline", "jit_kernel"]

jit_kernel = functools.partial(njit, cache=True, nogil=True, _nrt=False)
jit_inline = functools.partial(njit, cache=True, inline="always", _nrt=False)


class KernelParams:
    """The named scalar parameters of one kernel family, packed as a float64 vector.

    Args:
        name: the family (for messages and the index type's name).
        names: the parameters, in vector order.
    """

    def __init__(self, name: str, names: Sequence[str]) -> None:
        self.name = name
        self.names = tuple(names)
        #: positions by name; numba folds ``index.<name>`` into a constant
        self.index: Any = namedtuple(f"{name}Index", self.names)(*range(len(self.names)))

    @property
    def size(self) -> int:
        return len(self.names)

    def pack(self, **values: float) -> np.ndarray:
        """The vector of ``values`` (every parameter given, by name, nothing else)."""
        missing = [n for n in self.names if n not in values]
        extra = sorted(set(values) - set(self.names))
        if missing or extra:
            raise TypeError(
                f"{self.name} parameters: missing {missing}, unknown {extra}; "
                f"expected {list(self.names)}"
            )
        return np.array([float(values[n]) for n in self.names], dtype=np.float64)

    def unpack(self, vector: np.ndarray) -> dict[str, float]:
        """The named values of a packed vector (for tests and messages)."""
        return {n: float(vector[i]) for i, n in enumerate(self.names)}
