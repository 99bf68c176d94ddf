"""Property-based tests over every configuration field, generated from the declarations.

For any value of any field (valid ones, edges, values just outside, extreme floats such as
5e-324, 1e308, inf and nan, huge integers, wrong types, arrays, strings) building a config
must either raise ``TypeError``/``ValueError`` whose message names a field that was set and
says what is valid, or give a config that runs: a core is built, reset and stepped with
random (also out-of-range) actions, and its observations, rewards and infos stay finite.
Anything else (another exception type, a hang, a non-finite number) fails.

Runs are kept short (few UAVs, a few steps, a per-example hang guard) and hypothesis is
derandomised, so the module is reproducible and takes seconds.
"""

from __future__ import annotations

import contextlib
import math
import signal
import threading
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pairflock_env import PairFlockCore, make_config
from pairflock_env.config import SCHEMA
from pairflock_env.config.fields import Box, Choice, Flag, Int, Kind, OrNone, Real, Vector
from pairflock_env.config.limits import MAX_PLACEMENT_BYTES, MAX_UAVS
from pairflock_env.config.registry import Registered, RegisteredNames
from pairflock_env.config.sections.flocking import Pinning
from pairflock_env.config.sections.initial_state import placement_bytes
from pairflock_env.config.sections.leader import Turns
from pairflock_env.config.sections.pair_task import Pairs, PerPair
from pairflock_env.interfaces import make_interface
from pairflock_env.interfaces.pair_params import PAIR_INTERFACE_SCHEMA

FIELD_NAMES = tuple(SCHEMA.fields)
#: small, fast tasks the fuzzed fields are applied to (one per vehicle model)
BASES = {
    "particle": ("paper", dict(n_uavs=8, max_cycles=4)),
    "quadrotor": ("paper-quadrotor", dict(n_uavs=5, max_cycles=3)),
}
#: configs larger than this are built (config and core) but not stepped, to bound the time
RUN_LIMITS = dict(n_uavs=64, obs_neighbors=64)
HANG_SECONDS = 30
ROUTES = ("make_config", "replace")

EXTREME_FLOATS = [
    0.0,
    -0.0,
    5e-324,
    -5e-324,
    1e-310,
    1e-200,
    1e-6,
    1e308,
    -1e308,
    1.35e154,
    math.inf,
    -math.inf,
    math.nan,
    2.0**63,
]
HUGE_INTS = [2**63, -(2**63), 10**30, -(10**30), 10**400]
JUNK = st.sampled_from(
    [
        "1",
        "",
        "abc",
        None,
        True,
        b"x",
        [1.0, 2.0],
        (1, 2, 3),
        {"a": 1},
        {1, 2},
        np.array([1.0, 2.0]),
        np.zeros((2, 2)),
        np.array(3.0),
        np.float64("nan"),
        np.longdouble("1e400"),
        1j,
        [[1.0], [2.0, 3.0]],
    ]
)


def _reals(k: Real) -> st.SearchStrategy[Any]:
    edges = [k.lo, k.hi, float(np.nextafter(k.lo, -np.inf)), float(np.nextafter(k.hi, np.inf))]
    return st.one_of(
        st.floats(k.lo, k.hi, exclude_min=k.lo_open, exclude_max=k.hi_open),
        st.sampled_from(edges + EXTREME_FLOATS),
        st.integers(-(10**6), 10**6),
        st.sampled_from(HUGE_INTS),
        st.floats(k.lo, k.hi, exclude_min=k.lo_open, exclude_max=k.hi_open).map(np.float32),
    )


def _ints(k: Int) -> st.SearchStrategy[Any]:
    edges = [k.lo, k.hi, k.lo - 1, k.hi + 1]
    return st.one_of(
        st.integers(k.lo, min(k.hi, k.lo + 40)),
        st.sampled_from(edges + HUGE_INTS),
        st.integers(k.lo, k.hi).map(np.int64),
        st.sampled_from([2.5, float(k.lo), np.float64(k.lo)]),
    )


def _sequences(elem: st.SearchStrategy[Any], max_size: int = 4) -> st.SearchStrategy[Any]:
    return st.one_of(
        st.lists(elem, max_size=max_size),
        st.lists(elem, max_size=max_size).map(tuple),
        st.lists(st.floats(-10, 10), min_size=1, max_size=max_size).map(np.array),
    )


def _near(default: Any) -> st.SearchStrategy[Any]:
    """Values around a numeric default (0.5x to 2x), the ones most likely to run."""
    if isinstance(default, bool) or not isinstance(default, (int, float)) or default == 0:
        return st.nothing()
    near = st.floats(0.5, 2.0).map(lambda f: f * default)
    return near.map(round) if isinstance(default, int) else near


def strategy_for(kind: Kind, default: Any = None) -> st.SearchStrategy[Any]:
    """Values to try for a field of this kind: mostly plausible, many invalid, some junk."""
    if isinstance(kind, OrNone):
        return st.one_of(st.none(), strategy_for(kind.kind, default))
    if isinstance(kind, Real):
        base = st.one_of(_near(default), _reals(kind))
    elif isinstance(kind, Int):
        base = st.one_of(_near(default), _ints(kind))
    elif isinstance(kind, Flag):
        base = st.sampled_from([True, False, np.bool_(True), 0, 1, "yes"])
    elif isinstance(kind, Choice):
        base = st.one_of(st.sampled_from(kind.options), st.text(max_size=6))
    elif isinstance(kind, Registered):
        base = st.one_of(st.sampled_from(list(kind.registry)), st.text(max_size=6), st.none())
    elif isinstance(kind, RegisteredNames):
        name = st.one_of(st.sampled_from([*kind.registry, "none"]), st.text(max_size=6))
        base = st.one_of(name, st.lists(name, max_size=3), st.lists(name, max_size=3).map(tuple))
    elif isinstance(kind, (Vector, Box, PerPair)):
        elem = _reals(kind.elem) if not isinstance(kind, Box) else _reals(Real(0.0, kind.hi))
        if not isinstance(default, tuple):
            elem = st.one_of(_near(default), elem)
        base = st.one_of(elem, _sequences(elem))
    elif isinstance(kind, Pairs):
        idx = st.integers(-1, 10)
        plausible = st.sampled_from([(0, 1), (2, 3), (4, 5), (1, 0), (3, 2), (0, 2), (6, 7)])
        base = st.one_of(
            st.lists(plausible, min_size=1, max_size=3),
            st.lists(st.tuples(idx, idx), max_size=4),
            st.lists(st.lists(idx, max_size=3), max_size=3),
        )
    elif isinstance(kind, Pinning):
        base = st.one_of(
            st.just("all"), st.integers(-2, 12), st.lists(st.integers(-1, 12), max_size=5)
        )
    elif isinstance(kind, Turns):
        turn = st.tuples(st.floats(0, 5), st.floats(0, 3), st.floats(-900, 900))
        base = st.one_of(
            st.lists(turn, max_size=3), st.lists(st.lists(st.floats(0, 3)), max_size=2)
        )
    elif type(kind).__name__ == "_PresetName":
        base = st.one_of(st.none(), st.text(max_size=6))
    else:  # a new kind needs a strategy here
        raise AssertionError(f"no fuzz strategy for kind {type(kind).__name__}")
    return st.one_of(base, base, base, JUNK)


def field_values(schema: Any, name: str) -> st.SearchStrategy[Any]:
    f = schema.fields[name]
    return strategy_for(f.kind, f.default)


@contextlib.contextmanager
def hang_guard(seconds: int) -> Iterator[None]:
    """Fail (TimeoutError) if the block runs longer than ``seconds`` (where SIGALRM exists)."""
    if (
        not hasattr(signal, "setitimer")
        or threading.current_thread() is not threading.main_thread()
    ):
        yield
        return

    def _alarm(signum, frame):
        raise TimeoutError(f"one example ran longer than {seconds} s")

    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _assert_finite(res, what: str, n_uavs: int) -> None:
    assert np.isfinite(res.obs).all(), f"{what}: non-finite observation"
    assert np.isfinite(res.reward).all(), f"{what}: non-finite reward"
    for key, v in res.info.items():
        v = np.asarray(v, dtype=np.float64)  # n_uavs = 2 included (issue 28, 8(d))
        assert np.isfinite(v).all(), f"{what}: info {key!r} (n_uavs={n_uavs})"


def run_briefly(cfg, steps: int = 3) -> None:
    """Build a 1-swarm core; unless it is large, reset it and step it with random actions."""
    core = PairFlockCore(cfg, num_swarms=1, seed=0)
    if any(getattr(cfg, name) > most for name, most in RUN_LIMITS.items()):
        return
    res = core.reset(seed=0)
    _assert_finite(res, "reset", cfg.n_uavs)
    rng = np.random.default_rng(0)
    for k in range(steps):
        res = core.step(rng.uniform(-2.0, 2.0, (1, core.n_agents, cfg.dim)))
        _assert_finite(res, f"step {k}", cfg.n_uavs)
        if res.terminated.any() or res.truncated.any():
            res = core.reset()
            _assert_finite(res, "reset after the episode ended", cfg.n_uavs)


def check(base: str, overrides: dict[str, Any], route: str) -> None:
    """The property: a clear error naming a field that was set, or a config that runs.

    ``route``: the overrides go to ``make_config`` with the base task's, or to ``replace`` of
    the base task (``preset`` is make_config's own argument, so it always takes replace)."""
    preset, kw = BASES[base]
    with hang_guard(HANG_SECONDS):
        try:
            if route == "make_config" and "preset" not in overrides:
                cfg = make_config(preset, **{**kw, **overrides})
            else:
                cfg = make_config(preset, **kw).replace(**overrides)
        except (TypeError, ValueError) as e:
            msg = str(e)
            assert any(name in msg for name in overrides), (overrides, msg)
            assert "must" in msg, msg
            return
        run_briefly(cfg)


@pytest.fixture(scope="module", autouse=True)
def _compiled_kernels():
    """Compile the numba kernels each base task reaches before any example is timed.

    The hang guard is for configs that hang, not for JIT compilation: on a clean clone
    (no numba cache) the first grid or safety-filter run of a dimension compiles for tens
    of seconds on a 2-core machine, so whichever example came first would be timed on it."""
    for preset, kw in BASES.values():
        for dim in {make_config(preset, **kw).dim, 3}:
            for search in ("all_pairs", "grid"):
                for safety in ("none", "cbf"):
                    over = dict(dim=dim, neighbor_search=search, safety_filter=safety)
                    run_briefly(make_config(preset, **{**kw, **over}))


_SETTINGS = dict(
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@pytest.mark.parametrize("name", FIELD_NAMES)
@settings(max_examples=20, **_SETTINGS)
@given(data=st.data())
def test_each_field_alone_is_rejected_clearly_or_runs(name, data):
    base = data.draw(st.sampled_from(sorted(BASES)), label="base")
    route = data.draw(st.sampled_from(ROUTES), label="route")
    value = data.draw(field_values(SCHEMA, name), label=name)
    check(base, {name: value}, route)


@st.composite
def _overrides(draw) -> dict[str, Any]:
    names = draw(st.lists(st.sampled_from(FIELD_NAMES), min_size=2, max_size=4, unique=True))
    return {n: draw(field_values(SCHEMA, n), label=n) for n in names}


@settings(max_examples=400, **_SETTINGS)
@given(base=st.sampled_from(sorted(BASES)), route=st.sampled_from(ROUTES), overrides=_overrides())
def test_field_combinations_are_rejected_clearly_or_run(base, route, overrides):
    check(base, overrides, route)


@pytest.mark.parametrize("name", tuple(PAIR_INTERFACE_SCHEMA.fields))
@settings(max_examples=8, **_SETTINGS)
@given(data=st.data())
def test_each_frame_parameter_is_rejected_clearly_or_works(name, data):
    value = data.draw(field_values(PAIR_INTERFACE_SCHEMA, name), label=name)
    cfg = make_config("paper", n_uavs=8, max_cycles=4, obs_neighbors=4, pair_accel_limit=50.0)
    try:
        itf = make_interface("pair", cfg, **{name: value})
    except (TypeError, ValueError) as e:
        assert name in str(e) and "must" in str(e), str(e)
        return
    core = PairFlockCore(cfg, num_swarms=1, seed=0)
    res = core.reset(seed=0)
    a = np.random.default_rng(0).uniform(-1, 1, (1, core.n_agents, cfg.dim))
    for _ in range(2):
        obs = itf.encode(res.obs)
        u = itf.decode(res.obs, a)
        assert np.isfinite(obs).all() and np.abs(obs).max() <= itf.observation_bound
        assert np.isfinite(u).all()
        res = core.step(u)
        assert np.isfinite(itf.reward(res.reward, res.info, a, res.obs)).all()


# ------------------------------------------------------------------ regressions
#: the examples of the hardening issue (accepted configs that crashed or gave NaN later,
#: unbounded sizes, errors naming the wrong field, placements failing only at reset):
#: (preset, overrides, exception type, field the message must start with)
REGRESSIONS = [
    ("paper", dict(spacing=1e-200, radius=2e-200), ValueError, "spacing"),
    ("paper", dict(attraction=5e-324), ValueError, "attraction"),
    ("paper", dict(radius=1.35e154), ValueError, "radius"),
    ("paper", dict(collision_distance=1e200), ValueError, "collision_distance"),
    ("paper", dict(dt=1e-310), ValueError, "dt"),
    ("paper", dict(horizon=1e300, dt=1e-10), ValueError, "dt"),
    ("paper", dict(horizon=1e300), ValueError, "horizon"),
    ("paper", dict(horizon=1e9, dt=1e-6), ValueError, "horizon"),
    ("paper", dict(pair_accel_limit=1.35e154), ValueError, "pair_accel_limit"),
    ("paper", dict(pair_accel_limit=5e-324), ValueError, "pair_accel_limit"),
    ("paper", dict(reward_error_weight=1e308), ValueError, "reward_error_weight"),
    ("paper", dict(reward_effort_weight=1e308), ValueError, "reward_effort_weight"),
    ("paper", dict(reward_separation_weight=1e308), ValueError, "reward_separation_weight"),
    ("paper", dict(reward_collision_weight=1e308), ValueError, "reward_collision_weight"),
    ("paper", dict(reward_error_weight=1e6, divergence_limit=1e9), ValueError, "reward_error"),
    ("paper-quadrotor", dict(quad_attitude_freq=1e308), ValueError, "quad_attitude_freq"),
    ("paper-quadrotor", dict(quad_yaw_freq=1e308), ValueError, "quad_yaw_freq"),
    ("paper-quadrotor", dict(quad_attitude_damping=1e308), ValueError, "quad_attitude_damping"),
    ("paper-quadrotor", dict(quad_attitude_freq=1e4), ValueError, "quad_attitude_freq"),
    ("paper", dict(substeps=10**9), ValueError, "substeps"),
    ("paper", dict(substeps=2**63), ValueError, "substeps"),
    ("paper", dict(partner_delay=10**8), ValueError, "partner_delay"),
    ("paper", dict(n_uavs=10**30), ValueError, "n_uavs"),
    ("paper", dict(obs_neighbors=10**30), ValueError, "obs_neighbors"),
    ("paper", dict(dynamics=np.array(["particle"])), TypeError, "dynamics"),
    ("paper", dict(integrator=np.array(["exact", "exact"])), TypeError, "integrator"),
    ("paper", dict(init=np.array(["random"])), TypeError, "init"),
    ("paper", dict(leader=np.array(["constant_velocity"])), TypeError, "leader"),
    ("paper-quadrotor", dict(quad_mixer=np.array(["clip"])), TypeError, "quad_mixer"),
    ("paper-quadrotor", dict(quad_mass=10), ValueError, "quad_mass"),
    ("paper", dict(min_init_spacing=200), ValueError, "min_init_spacing"),
    ("paper", dict(swarm_half_width=1.0), ValueError, "swarm_half_width"),
    ("paper-quadrotor", dict(n_uavs=300), ValueError, "n_uavs"),
]


@pytest.mark.parametrize(("preset", "overrides", "exc", "field"), REGRESSIONS)
def test_hardening_examples_fail_at_construction_naming_the_field(preset, overrides, exc, field):
    with pytest.raises(exc) as info:
        make_config(preset, **overrides)
    msg = str(info.value)
    assert msg.startswith(field) and "is invalid" in msg and "must" in msg, msg


def test_memory_and_placement_limits_name_the_field():
    pairs = tuple((2 * i, 2 * i + 1) for i in range(200))
    big = dict(n_uavs=1000, pairs=pairs, init="random", swarm_half_width=1e3, pair_corner=1e3)
    with pytest.raises(ValueError, match=r"^partner_delay=100000 is invalid: .*delay buffer"):
        make_config("paper", partner_delay=100_000, **big)
    # the placement is linear in N (a neighbour grid, no N x N arrays): the largest swarm
    # allowed, spaced apart, stays within the placement memory limit

    largest = make_config("paper", n_uavs=MAX_UAVS)
    assert largest.min_init_spacing > 0
    assert placement_bytes(largest) < MAX_PLACEMENT_BYTES
    half = largest.replace(n_uavs=MAX_UAVS // 2)
    assert placement_bytes(largest) <= 2 * placement_bytes(half)  # linear, not quadratic
