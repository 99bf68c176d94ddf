"""The exponential of eq. 16 as the C library computes it, in a form that vectorises.

The flocking weight ``a - b_r exp(-rho^2 / sigma^2)`` needs one exponential per neighbour
pair, and libm's ``exp`` is a call the compiler can neither inline nor vectorise: in a
packed flock of 10,000 UAVs those calls were about 40 % of the flocking sweep. This module
evaluates the same function with the same operations, so that a loop of them vectorises and
every result keeps its bits.

The method is the table-driven one of the GNU C library's ``exp`` (since glibc 2.28):
x = k ln2 / 128 + r with k an integer and |r| <= ln2 / 256, exp(x) = 2^(k / 128) exp(r),
2^(k / 128) from a table of 128 entries split into a double H_k and a small correction
T_k (2^(k/128) ~ H_k (1 + T_k)), exp(r) - 1 from a degree-5 polynomial. The fused
multiply-adds are placed where that library's x86-64 build for CPUs with FMA places them
(read off its machine code), so on such a CPU every result in the fast range below is libm's
bit for bit: :func:`exp_lane` against ``math.exp`` is tested on millions of arguments
(tests/test_exp.py). The table is computed here from exact integer arithmetic; its bits
equal the library's.

Outside 2^-54 <= |x| < 512 (where the library takes its special paths: zero, tiny and huge
arguments, NaN), callers fall back to ``np.exp``, which numba compiles to the library call:
:func:`in_fast_range` says which.

Elsewhere (another C library, another architecture, an x86-64 CPU without FMA, where
glibc picks a build without fused operations) the results are still these, the same on
every machine (LLVM's ``fma`` is exact even where it is not one instruction), but that
library's own ``exp`` may differ from them in the last bit now and then; the test is skipped
there.
"""

from __future__ import annotations

from fractions import Fraction
from math import isqrt

import numpy as np
from numba import types
from numba.extending import intrinsic

from pairflock_env.kernels import bits_float, float_bits, jit_inline

__all__ = ["exp_lane", "in_fast_range"]

_BITS = 7  # 2^7 = 128 table entries
#: 128 / ln 2, and ln 2 / 128 split in a high part (exact products with k) and the rest
_INV_LN2_N = float.fromhex("0x1.71547652b82fep+7")
_NEG_LN2_HI_N = float.fromhex("-0x1.62e42fefa0000p-8")
_NEG_LN2_LO_N = float.fromhex("-0x1.cf79abc9e3b3ap-47")
#: 1.5 * 2^52: adding it rounds to an integer held in the low bits
_SHIFT = float.fromhex("0x1.8p52")
#: exp(r) - 1 - r ~ C2 r^2 + C3 r^3 + C4 r^4 + C5 r^5 on |r| <= ln2 / 256 (the library's
#: minimax coefficients)
_C2 = float.fromhex("0x1.ffffffffffdbdp-2")
_C3 = float.fromhex("0x1.555555555543cp-3")
_C4 = float.fromhex("0x1.55555cf172b91p-5")
_C5 = float.fromhex("0x1.1111167a4d017p-7")
_TINY, _HUGE = 2.0**-54, 512.0


def _table() -> tuple[np.ndarray, np.ndarray]:
    """T_k (float64) and the bits of H_k less k 2^45 (uint64), k = 0..127: H_k the double
    nearest 2^(k/128), T_k = (2^(k/128) - H_k) / H_k rounded; 2^(k/128) to 160 bits by
    seven integer square roots (floors of floors are the floor of the root)."""
    prec = 160
    tail = np.empty(1 << _BITS)
    scale = np.empty(1 << _BITS, np.uint64)
    for k in range(1 << _BITS):
        y = 1 << (k + (prec << _BITS))  # 2^k scaled by 2^(128 prec)
        for _ in range(_BITS):
            y = isqrt(y)  # floor(2^(k/128) 2^prec) at the end
        v = Fraction(y, 1 << prec)
        h = float(v)  # correctly rounded
        tail[k] = float((v - Fraction(h)) / Fraction(h))
        bits = int(np.float64(h).view(np.uint64))
        scale[k] = (bits - (k << (52 - _BITS))) % (1 << 64)
    return tail, scale


_TAIL, _SCALE = _table()


@intrinsic
def fma(typingctx, a, b, c):
    """a * b + c rounded once (LLVM's fma: one instruction on CPUs that have it)."""
    if not (a == b == c == types.float64):
        return None

    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return types.float64(types.float64, types.float64, types.float64), codegen


@jit_inline
def in_fast_range(x):
    """Whether :func:`exp_lane` gives libm's exp(x): 2^-54 <= |x| < 512 (False for NaN)."""
    a = abs(x)
    return (a >= _TINY) & (a < _HUGE)


@jit_inline
def exp_lane(x):
    """exp(x) for x :func:`in_fast_range`, libm's bits; no branch, no call, so a loop of
    them vectorises (arguments outside the range give a wrong value, not a fault)."""
    kd = fma(x, _INV_LN2_N, _SHIFT)
    ki = float_bits(kd)
    kd -= _SHIFT
    r = fma(kd, _NEG_LN2_HI_N, x)
    r = fma(kd, _NEG_LN2_LO_N, r)
    idx = ki & np.uint64((1 << _BITS) - 1)
    sbits = _SCALE[idx] + (ki << np.uint64(52 - _BITS))
    r2 = r * r
    t = fma(fma(r, _C3, _C2), r2, _TAIL[idx] + r)
    t = fma(r2 * r2, fma(r, _C5, _C4), t)
    scale = bits_float(sbits)
    return fma(scale, t, scale)
