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
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

__all__ = [
    "BoundKernel",
    "KernelParams",
    "all_finite",
    "bits_float",
    "float_bits",
    "jit_inline",
    "jit_kernel",
    "low_bit",
]

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


@jit_kernel
def all_finite(a):
    """Whether every element of the array ``a`` is finite: ``np.isfinite(a).all()`` without
    its temporary array (a tenth of its time on the few actions of a step)."""
    ok = True
    for x in a.flat:
        ok &= np.isfinite(x)
    return ok


class BoundKernel:
    """A kernel with its arguments after the state fixed, for repeated calls on the same
    buffers: ``run(*state)`` calls ``kernel(*state, *tail)`` and returns ``out`` (what the
    kernel fills). Picklable, unlike a closure, so that an env holding one can be saved."""

    def __init__(self, kernel: Any, tail: tuple, out: Any) -> None:
        self.kernel, self.tail, self.out = kernel, tail, out

    def __call__(self, *state: Any) -> Any:
        self.kernel(*state, *self.tail)
        return self.out


# ---------------------------------------------------------------------------------------
# bit-level helpers the kernels need and numba does not offer
# ---------------------------------------------------------------------------------------
@intrinsic
def float_bits(typingctx, x):
    """The bits of a float64 as a uint64. Non-negative floats (and +inf) order like their
    bits, and every NaN (of either sign) lies above +inf as an unsigned integer, so a
    minimum of bits taken from +inf's never picks a NaN: it is the minimum of ``if d < m:
    m = d`` exactly, and it vectorises (the float comparison does not)."""
    if x != types.float64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.uint64(types.float64), codegen


@intrinsic
def bits_float(typingctx, x):
    """The float64 whose bits are the uint64 ``x`` (the inverse of :func:`float_bits`)."""
    if x != types.uint64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.uint64), codegen


@intrinsic
def low_bit(typingctx, x):
    """The index of the lowest set bit of the uint64 ``x`` (64 when x = 0), as int64."""
    if x != types.uint64:
        return None

    def codegen(context, builder, signature, args):
        return builder.cttz(args[0], ir.Constant(ir.IntType(1), 0))

    return types.int64(types.uint64), codegen
