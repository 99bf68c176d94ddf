"""The vectorisable exponential (pairflock_env.exp) gives the C library's exp bit for bit."""

from __future__ import annotations

import math
import platform
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from pairflock_env.exp import exp_lane, in_fast_range


def _glibc_fma() -> bool:
    """Whether numba's exp is glibc's x86-64 build for FMA CPUs, the one exp.py follows."""
    cpu = Path("/proc/cpuinfo")
    return (
        platform.machine() == "x86_64"
        and platform.libc_ver()[0] == "glibc"
        and cpu.exists()
        and " fma " in cpu.read_text()
    )


pytestmark = pytest.mark.skipif(
    not _glibc_fma(), reason="the bits are those of glibc's exp on x86-64 CPUs with FMA"
)


@njit(cache=False)
def _lanes(x, out):
    slow = 0
    for i in range(x.shape[0]):
        out[i] = exp_lane(x[i])
        slow += not in_fast_range(x[i])
    return slow


@njit(cache=False)
def _libm(x, out):
    for i in range(x.shape[0]):
        out[i] = np.exp(x[i])  # numba compiles this to the C library's exp


@pytest.mark.parametrize(
    "lo, hi",
    [(-3.5, 0.0), (-40.0, 40.0), (-511.0, 511.0), (-1e-3, 1e-3), (-1e-15, 1e-15)],
)
def test_exp_lane_is_libm_bit_for_bit(lo, hi):
    """Two million arguments per range (the first is the flocking's: -r^2 / sigma^2 of the
    paper's parameters is -3.3): every one in the fast range gives libm's bits, as the
    C library's exp and Python's math.exp compute them."""
    x = np.random.default_rng(int(1e3 * hi)).uniform(lo, hi, 2_000_000)
    mine, libm = np.empty_like(x), np.empty_like(x)
    slow = _lanes(x, mine)
    _libm(x, libm)
    fast = (np.abs(x) >= 2.0**-54) & (np.abs(x) < 512.0)
    assert slow == np.count_nonzero(~fast)
    assert np.array_equal(mine[fast].view(np.uint64), libm[fast].view(np.uint64))
    for i in np.flatnonzero(fast)[:2000]:
        assert mine[i] == math.exp(x[i])


def test_fast_range_bounds():
    x = np.array([0.0, -0.0, 2.0**-54, -(2.0**-55), 511.9, -512.0, np.nan, np.inf, -np.inf])
    out = np.empty_like(x)
    _lanes(x, out)
    want = [False, False, True, False, True, False, False, False, False]
    got = [bool(njit(lambda v: in_fast_range(v))(v)) for v in x]
    assert got == want
    assert out[2] == math.exp(x[2]) and out[4] == math.exp(x[4])
