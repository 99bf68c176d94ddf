"""Shared fixtures. Tests that hold for every vehicle model take the ``dynamics`` fixture."""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import pytest

from pairflock_env import make_config

#: the toy plug-ins register into the env's registries when imported: only the fresh
#: interpreters of tests/test_plugins.py load them (--doctest-modules would import them here)
collect_ignore = ["plugins"]

#: every vehicle model the env offers; tests over ``dynamics`` run once per entry
DYNAMICS = ["particle", "quadrotor"]

#: a small, fast task per vehicle model (same task, both vehicles)
SMALL = {
    "particle": dict(preset="paper", n_uavs=12),
    # Sec. VI-B scenario with fewer UAVs: 3-D, 50 Hz protocol, 500 Hz physics
    "quadrotor": dict(preset="paper-quadrotor", n_uavs=6),
}


@pytest.fixture(params=DYNAMICS)
def dynamics(request) -> str:
    return request.param


@pytest.fixture
def small_kwargs(dynamics) -> dict:
    """Keyword arguments of a small env of the given vehicle model."""
    return dict(SMALL[dynamics])


@pytest.fixture
def small_config(small_kwargs):
    kw = dict(small_kwargs)
    return make_config(kw.pop("preset"), **kw)
