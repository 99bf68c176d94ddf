"""Every form of action value, through the core and every view: what is accepted (and then
clipped as documented), and what is rejected with a clear error and no state change.

Each accepted form is compared with the plain float64 actions it stands for: a finite value
too large for float64 (a huge Python int, a longdouble, a fraction) must act exactly like
the value 1 (the action box edge), a masked array without masked entries like its data.
"""

from __future__ import annotations

import fractions
import math

import gymnasium as gym
import numpy as np
import pytest

from pairflock_env import ENV_ID, PairFlockCore, make_config, parallel_env
from pairflock_env.config.arrays import real_array
from pairflock_env.envs import PairFlockSB3VecEnv
from pairflock_env.envs.vector import PairFlockGymVectorEnv
from pairflock_env.task.actions import check_pair_actions, decode_pair_actions

KW = dict(n_uavs=6, pair_accel_limit=20.0)
#: the plain actions every form below stands for: signs, zeros and in-range values
TEMPLATE = np.array([[1.0, -1.0], [0.0, 0.5]])


def _elementwise(x: np.ndarray, f) -> list:
    """Nested lists of ``f(v)`` over the elements of ``x`` (Python objects, not an array)."""
    return np.vectorize(f, otypes=[object])(x).tolist()


def _huge(v, big):
    # +-1 become +-big (beyond the box); the in-range values stay as they are
    return v if abs(v) != 1.0 else (big if v > 0 else -big)


ACCEPTED = {
    "python int beyond int64": lambda x: _elementwise(x, lambda v: _huge(v, 10**30)),
    "python int beyond float64": lambda x: _elementwise(x, lambda v: _huge(v, 10**400)),
    "fraction beyond float64": lambda x: _elementwise(
        x, lambda v: _huge(v, fractions.Fraction(10**400, 3))
    ),
    "longdouble beyond float64": lambda x: np.where(
        np.abs(x) == 1.0, x.astype(np.longdouble) * np.longdouble("1e400"), x
    ).astype(np.longdouble),
    "masked array, nothing masked": lambda x: np.ma.array(x, mask=np.zeros(x.shape, bool)),
    "masked array, no mask": lambda x: np.ma.array(x),
    "float16": lambda x: x.astype(np.float16),
    "float32": lambda x: x.astype(np.float32),
    "list of numpy scalars": lambda x: _elementwise(x, np.float32),
}

REJECTED = {
    "masked entry": (lambda x: np.ma.array(x, mask=x == 0.0), ValueError, "masked"),
    "longdouble inf": (
        lambda x: np.where(x == 1.0, np.longdouble("inf"), x).astype(np.longdouble),
        ValueError,
        "NaN or inf",
    ),
    "nan next to a huge int": (
        lambda x: _elementwise(x, lambda v: math.nan if v == 1.0 else _huge(v, 10**400)),
        ValueError,
        "NaN or inf",
    ),
    "python float inf": (
        lambda x: _elementwise(x, lambda v: math.inf if v == 0.5 else float(v)),
        ValueError,
        "NaN or inf",
    ),
    "bool array": (lambda x: x > 0, TypeError, "dtype bool"),
    "bool among ints": (lambda x: _elementwise(x, lambda v: v == 1.0 or 10**30), TypeError, "bool"),
    "complex": (lambda x: x.astype(complex), TypeError, "complex"),
    "string": (lambda x: x.astype(str), TypeError, "dtype"),
    "None entry": (lambda x: _elementwise(x, lambda v: None if v == 0 else v), TypeError, "None"),
}


# --------------------------------------------------------------------------- real_array
@pytest.mark.parametrize("form", ACCEPTED)
def test_real_array_accepts_every_real_form_and_saturates_beyond_float64(form):
    got = real_array(ACCEPTED[form](TEMPLATE), "a", TEMPLATE.shape)
    assert type(got) is np.ndarray and got.dtype == np.float64
    assert np.isfinite(got).all()
    inside = np.abs(TEMPLATE) != 1.0
    np.testing.assert_array_equal(got[inside], TEMPLATE[inside].astype(got.dtype))
    # the box edges are either themselves or the same sign, at least as far out
    assert np.all(got[~inside] * TEMPLATE[~inside] >= 1.0)
    assert np.all(np.abs(got) <= np.finfo(np.float64).max)


@pytest.mark.parametrize("form", REJECTED)
def test_real_array_rejects_with_the_documented_error(form):
    make, exc, match = REJECTED[form]
    with pytest.raises(exc, match=match) as err:
        real_array(make(TEMPLATE), "action of uav_0", TEMPLATE.shape)
    assert "action of uav_0" in str(err.value)


def test_masked_entries_are_named():
    x = np.ma.array(np.zeros((2, 3)), mask=[[0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match=r"masked entries at \[\[0, 1\], \[1, 2\]\]"):
        real_array(x, "actions")


def test_plain_float64_input_is_returned_as_is():
    x = np.zeros((2, 2))
    assert real_array(x, "a", (2, 2)) is x


class _Subclass(np.ndarray):
    pass


def test_ndarray_subclasses_become_plain_arrays():
    got = real_array(np.array([[0.5, -0.5]]).view(_Subclass), "a", (1, 2))
    assert type(got) is np.ndarray


def test_decode_clips_scales_and_flags():
    a = np.array([[[2.0, 0.5], [-0.25, -7.0], [0.0, 1.0]]])
    u, clipped = decode_pair_actions(a, 10.0)
    np.testing.assert_array_equal(u, [[[10.0, 5.0], [-2.5, -10.0], [0.0, 10.0]]])
    assert clipped.tolist() == [[True, True, False]]


def test_check_pair_actions_names_swarm_agent_and_uav():
    a = np.zeros((2, 4, 2))
    a[1, 3, 0] = np.nan
    with pytest.raises(ValueError, match=r"swarm 1, agent 3, UAV 7"):
        check_pair_actions(a, 2, 4, 2, np.array([0, 1, 6, 7]))
    assert check_pair_actions(np.zeros((4, 2)), 1, 4, 2, np.arange(4)).shape == (1, 4, 2)


# --------------------------------------------------------------------------- every view
class _View:
    """A view, its core, and how one form of the template becomes that view's action."""

    def __init__(self, name: str) -> None:
        self.name = name
        if name == "core":
            self.env = self.core = PairFlockCore(make_config("paper", **KW))
            self.env.reset(seed=3)
        elif name == "parallel":
            self.env = parallel_env(**KW)
            self.env.reset(seed=3)
            self.core = self.env.core
        elif name == "gym":
            self.env = gym.make(ENV_ID, interface="world", **KW).unwrapped
            self.env.reset(seed=3)
            self.core = self.env.core
        elif name == "vector":
            self.env = PairFlockGymVectorEnv(num_envs=1, interface="world", **KW)
            self.env.reset(seed=3)
            self.core = self.env.core
        else:
            self.env = PairFlockSB3VecEnv(num_swarms=1, interface="world", **KW)
            self.env.seed(3)
            self.env.reset()
            self.core = self.env.core

    def action(self, form):
        """The template in this view's layout, every row through ``form``."""
        M = self.core.n_agents
        if self.name == "parallel":
            agents = self.env.possible_agents
            return {a: form(TEMPLATE[m]) for m, a in enumerate(agents[:M])}
        shape = {"core": (1, M, 2), "gym": (M * 2,), "vector": (1, M * 2), "sb3": (M, 2)}
        return form(TEMPLATE.reshape(shape[self.name]))

    def step(self, action):
        return self.env.step(action)


VIEWS = ["core", "parallel", "gym", "vector", "sb3"]


@pytest.fixture(params=VIEWS)
def view_name(request):
    if request.param == "sb3":
        pytest.importorskip("stable_baselines3")
    return request.param


@pytest.mark.parametrize("form", ACCEPTED)
def test_every_view_accepts_every_real_form_as_its_clipped_value(view_name, form):
    got, want = _View(view_name), _View(view_name)
    got.step(got.action(ACCEPTED[form]))
    want.step(want.action(lambda x: np.clip(x, -1.0, 1.0).astype(np.float64)))
    np.testing.assert_array_equal(got.core.q, want.core.q)
    np.testing.assert_array_equal(got.core.p, want.core.p)


@pytest.mark.parametrize("form", REJECTED)
def test_every_view_rejects_bad_forms_and_changes_nothing(view_name, form):
    make, exc, match = REJECTED[form]
    v = _View(view_name)
    before = (v.core.q.copy(), v.core.p.copy(), v.core.t.copy(), v.core.steps.copy())
    with pytest.raises(exc, match=match):
        v.step(v.action(make))
    after = (v.core.q, v.core.p, v.core.t, v.core.steps)
    for x, y in zip(before, after, strict=True):
        np.testing.assert_array_equal(x, y)


def test_clipping_of_a_huge_int_is_reported_like_any_clipping():
    core = PairFlockCore(make_config("paper", **KW))
    core.reset(seed=0)
    res = core.step([[[10**30, 0], [0, 0]]])
    assert res.info["action_clipped"].tolist() == [[True, False]]
    assert res.info["pair_accel"][0, 0] == KW["pair_accel_limit"]
