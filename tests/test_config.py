"""Configuration: presets, overrides and the invalid-configuration matrix."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import json
import math
import pickle
import warnings
import zipfile
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from pairflock_env import ENV_ID, PRESETS, PairFlockConfig, PairFlockCore, make_config, parallel_env
from pairflock_env.compat import upgrade_stored
from pairflock_env.config import LIMITS, SCHEMA, ConfigSection, UnknownFieldError, field_names
from pairflock_env.config.docs import render
from pairflock_env.config.sections import safety
from pairflock_env.config.sections.initial_state import start_density
from pairflock_env.config.sections.observation import base_obs_size as obs_size
from pairflock_env.interfaces import PairInterfaceParams, interface_from_dict, make_interface
from pairflock_env.task.observations import ObsLayout
from train.mix.tasks import training_tasks
from train.settings import RunSettings


def test_paper_preset_matches_the_notes_table():
    cfg = make_config("paper")
    assert cfg.preset == "paper"
    assert (cfg.dim, cfg.d_m, cfg.spacing, cfg.radius) == (2, (5.0,), 7.0, 8.4)
    assert (cfg.attraction, cfg.repulsion, cfg.consensus) == (1.0, 10.0, 1.0)
    assert (cfg.pinning, cfg.pin_position_gain, cfg.pin_velocity_gain) == ("all", 0.1, 0.632)
    assert cfg.leader_position == (25.0, 25.0) and cfg.leader_velocity == (0.5, 0.5)
    assert cfg.dt == 0.01 and cfg.episode_steps == 5000
    # g_r(d) = a defines sigma: 10 exp(-d^2/sigma^2) = 1

    assert 10.0 * math.exp(-(7.0**2) / cfg.repulsion_sigma2) == pytest.approx(1.0)


def test_overrides_and_replace():
    cfg = make_config("paper", n_uavs=100, d_m=4.0)
    assert cfg.n_uavs == 100 and cfg.d_m == (4.0,)
    cfg3 = cfg.replace(dim=3)
    assert cfg3.leader_velocity == (0.5, 0.5, 0.5)  # broadcast scalars follow dim
    two = cfg.replace(pairs=((0, 1), (2, 3)))
    assert two.d_m == (4.0, 4.0)
    assert make_config("paper", max_cycles=7).episode_steps == 7
    assert make_config("paper", horizon=2.0, dt=0.02).episode_steps == 100
    assert set(PRESETS) >= {"paper"}


@pytest.mark.parametrize(
    "overrides, field",
    [
        (dict(n_uavs=1), "n_uavs"),
        (dict(n_uavs=2.5), "n_uavs"),
        (dict(d_m=0.0), "d_m"),
        (dict(d_m=-1.0), "d_m"),
        (dict(d_m=(5.0, 4.0)), "d_m"),
        (dict(radius=0.0), "radius"),
        (dict(radius=-2.0), "radius"),
        (dict(radius=6.0), "radius"),  # must exceed the spacing d
        (dict(dt=0.0), "dt"),
        (dict(dt=-0.01), "dt"),
        (dict(dt=float("nan")), "dt"),
        (dict(substeps=0), "substeps"),
        (dict(pairs=((0, 20),)), "pairs"),
        (dict(pairs=((0, -1),)), "pairs"),
        (dict(pairs=((0, 1), (1, 2))), "pairs"),
        (dict(pairs=((3, 3),)), "pairs"),
        (dict(pairs=()), "pairs"),
        (dict(dim=4), "dim"),
        (dict(repulsion=0.5), "repulsion"),
        (dict(integrator="rk4"), "integrator"),
        (dict(dynamics="blimp"), "dynamics"),
        (dict(pinning=(0, 0)), "pinning"),
        (dict(pinning=99), "pinning"),
        (dict(leader_velocity=(1.0, 2.0, 3.0)), "leader_velocity"),
        (dict(pair_accel_limit=0.0), "pair_accel_limit"),
        (dict(obs_neighbors=-1), "obs_neighbors"),
        (dict(partner_delay=-1), "partner_delay"),
        (dict(obs_noise_position=-0.1), "obs_noise_position"),
        (dict(pairs=((0, 1), (2, 3), (4, 5))), "init"),  # 2-D has two diagonals
    ],
)
def test_invalid_config_names_field_and_range(overrides, field):
    with pytest.raises((ValueError, TypeError)) as exc:
        make_config("paper", **{"n_uavs": 20, **overrides})
    msg = str(exc.value)
    assert field in msg
    assert "must" in msg  # says what is valid


def test_unknown_keyword_suggests_the_right_one():
    with pytest.raises(TypeError, match="Did you mean 'n_uavs'"):
        make_config("paper", n_uav=20)
    with pytest.raises(TypeError, match="unknown configuration field 'bogus'"):
        parallel_env(bogus=1)
    with pytest.raises(ValueError, match="preset"):
        make_config("nope")


def test_config_is_frozen_and_serialisable():
    cfg = make_config("paper")
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.n_uavs = 3  # type: ignore[misc]
    d = cfg.to_dict()
    assert PairFlockConfig(**{**d, "pairs": [tuple(p) for p in d["pairs"]]}) == cfg


# ------------------------------------------------------------------ declarations
def test_every_field_is_declared_with_type_unit_range_and_meaning():

    cfg = PairFlockConfig()
    names = [n for n in vars(cfg) if not n.startswith("_")]  # the values a config holds
    assert names == list(field_names()) == list(SCHEMA.fields)
    in_sections = [f.name for sec in SCHEMA.sections for f in sec.fields]
    assert sorted(in_sections) == sorted(names)  # each field in exactly one section
    for f in SCHEMA.fields.values():
        assert f.doc and f.kind.valid() and f.kind.type_name, f.name
        assert PairFlockConfig.schema.fields[f.name] is f
    # the declared defaults are valid: the default config is the paper's
    assert PairFlockConfig() == make_config(None) == make_config("paper").replace(preset=None)
    sig = inspect.signature(PairFlockConfig)
    assert list(sig.parameters) == names
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in sig.parameters.values())


def test_presets_list_only_what_differs_from_the_defaults():

    assert PRESETS["paper"] == {}  # the defaults are the paper's values
    for name, entries in PRESETS.items():
        cfg = make_config(name)
        ctx = {n: getattr(cfg, n) for n in SCHEMA.fields}
        for key in entries:
            f = SCHEMA.fields[key]
            default = f.kind.check(key, f.default, ctx)
            assert getattr(cfg, key) != default, f"preset {name!r} repeats the default {key}"


def test_stored_model_configs_load_to_the_same_values(tmp_path):
    """A config stored in a model zip by the previous release (with safe_distance) loads
    silently, and the same task built today has exactly the stored values."""

    models = sorted((Path(__file__).parent.parent / "models").glob("*.zip"))
    assert models
    for path in models:
        meta = json.loads(zipfile.ZipFile(path).read("data"))["pairflock"]
        stored = meta["config"]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            cfg = PairFlockConfig.from_dict(stored)
        renamed = {
            ("reward_separation_distance" if k == "safe_distance" else k): v
            for k, v in stored.items()
        }
        now = cfg.to_dict()
        assert {k: now[k] for k in renamed} == renamed
        # fields added since the model was stored take their defaults (today's behaviour)
        new = set(now) - set(renamed)
        assert all(now[k] == PairFlockConfig().to_dict()[k] for k in new)
        assert all(getattr(cfg, k) == SCHEMA.fields[k].default for k in new)
        # the run's own task resolution (dynamics key, a task mix's first task) rebuilds it

        run = RunSettings.from_dict(meta["settings"])
        tasks = training_tasks(run)
        rebuilt = (
            tasks[0].config(run.preset)
            if tasks
            else make_config(run.preset, **run.config_overrides())
        )
        # safety_reaction_time and safety_decay became vehicle defaults (None) after some
        # models were stored with the particle model's values: those must be what the
        # rebuilt config resolves to
        resolved = {
            "safety_reaction_time": safety.reaction_time(rebuilt),
            "safety_decay": safety.decay(rebuilt),
        }
        was, now_ = cfg.to_dict(), rebuilt.to_dict()
        moved = {k: was[k] for k in resolved if was[k] != now_[k] and now_[k] is None}
        assert moved == {k: resolved[k] for k in moved}, path.name
        # defaults changed since: the stored value is the old default, the rebuilt one today's
        changed = {k: was[k] for k, old in CHANGED_DEFAULTS.items() if was[k] != now_[k]}
        assert changed == {k: CHANGED_DEFAULTS[k] for k in changed}, path.name
        assert all(now_[k] == SCHEMA.fields[k].default for k in changed), path.name
        assert rebuilt.replace(**moved, **changed) == cfg, path.name


#: defaults changed after a committed model was stored: field -> the default it had then
CHANGED_DEFAULTS = {"safety_sensing_radius": 20.0}  # 100 m since the chattering fix


def test_values_are_normalised():

    cfg = make_config(
        "paper",
        n_uavs=np.int32(20),
        dt=np.float32(0.02),
        pinning=[5, 1, 3],
        pairs=[[0, 1], [2, 3]],
        d_m=np.array([4, 5]),
        leader_position=np.array([1, 2]),
        terminate_on_collision=np.bool_(True),
    )
    assert type(cfg.n_uavs) is int and type(cfg.dt) is float and cfg.dt == float(np.float32(0.02))
    assert cfg.pinning == (1, 3, 5) and cfg.pairs == ((0, 1), (2, 3))
    assert cfg.d_m == (4.0, 5.0) and cfg.leader_position == (1.0, 2.0)
    assert cfg.terminate_on_collision is True
    assert cfg.vector("leader_velocity").shape == (2,) and cfg.d_m_array.dtype == np.float64
    assert hash(cfg) == hash(PairFlockConfig(**cfg.to_dict()))


def test_sections_group_the_flat_fields():

    cfg = make_config("paper-quadrotor")
    sec = cfg.section("flocking")
    assert isinstance(sec, ConfigSection) and sec.radius == cfg.radius == sec["radius"]
    assert dict(sec) == {f.name: getattr(cfg, f.name) for f in SCHEMA.section("flocking").fields}
    assert cfg.section("quadrotor").quad_mass == cfg.quad_mass
    every = [name for s in cfg.sections().values() for name in s]
    assert every == list(SCHEMA.fields)
    with pytest.raises(KeyError, match="sections: meta, swarm"):
        cfg.section("nope")
    with pytest.raises(AttributeError, match="has no field"):
        _ = sec.quad_mass


def test_unknown_keywords_are_type_errors_everywhere():

    cfg = make_config("paper", n_uavs=8)
    calls = [
        lambda: make_config("paper", n_uav=8),
        lambda: PairFlockConfig(n_uav=8),
        lambda: cfg.replace(n_uav=8),
        lambda: PairFlockConfig.from_dict({**cfg.to_dict(), "n_uav": 8}),
        lambda: PairFlockCore(n_uav=8),
        lambda: PairFlockCore(cfg, n_uav=8),
        lambda: parallel_env(n_uav=8),
        lambda: gym.make(ENV_ID, n_uav=8),
    ]
    for call in calls:
        with pytest.raises(TypeError, match="Did you mean 'n_uavs'") as e:
            call()
        assert isinstance(e.value, UnknownFieldError) and isinstance(e.value, ValueError)
    # a wrapper's keyword the env does not know (TorchRL's GymEnv passes frameskip)
    with pytest.raises(TypeError, match="unknown configuration field 'frameskip'"):
        gym.make(ENV_ID, frameskip=4)
    with pytest.raises(TypeError, match="Did you mean 'w_error'"):
        make_interface("pair", cfg, w_eror=1.0)
    with pytest.raises(TypeError, match="Did you mean 'w_error'"):
        PairInterfaceParams(w_eror=1.0)
    with pytest.raises(TypeError, match="world-interface parameter 'w_error'"):
        make_interface("world", cfg, w_error=1.0)


def test_choosing_the_quadrotor_picks_dim_and_substeps():

    cfg = make_config("paper", dynamics="quadrotor")
    assert cfg.dim == 3 and cfg.leader_position == (25.0, 25.0, 25.0)
    assert cfg.substeps == 3  # the fewest with dt / substeps <= 0.1 / 27 s
    assert make_config("paper", dynamics="quadrotor", dt=0.02).substeps == 6
    assert make_config("paper", dynamics="quadrotor", quad_attitude_freq=30.0).substeps == 6
    # replace() derives them again; values the user set stay
    assert make_config("paper").replace(dynamics="quadrotor") == cfg
    assert (
        cfg.replace(dynamics="particle").dim == 2 and cfg.replace(dynamics="particle").substeps == 1
    )
    assert make_config("paper", substeps=4).replace(dynamics="quadrotor").substeps == 4
    with pytest.raises(ValueError, match=r"^dim=2 is invalid: must be 3"):
        make_config("paper", dynamics="quadrotor", dim=2)
    with pytest.raises(ValueError, match=r"^substeps=1 is invalid: .*substeps >= 3"):
        make_config("paper", dynamics="quadrotor", substeps=1)
    # the preset's own values are kept (its particle variant flies the same 3-D scenario)
    assert make_config("paper-quadrotor", dynamics="particle").dim == 3
    env = gym.make(ENV_ID, dynamics="quadrotor", n_uavs=6)
    obs, _ = env.reset(seed=0)
    obs, reward, *_ = env.step(env.action_space.sample())
    assert np.isfinite(obs).all() and np.isfinite(reward)
    env.close()
    penv = parallel_env(dynamics="quadrotor", n_uavs=6)
    assert penv.config.dim == 3
    penv.close()


def test_rule_errors_name_the_field_the_user_set():
    cases = [
        (dict(quad_mass=10), "quad_mass=10.0 is invalid: the hover thrust"),
        (dict(quad_motor_thrust_max=1.0), "quad_motor_thrust_max=1.0 is invalid: the hover"),
        (dict(quad_gravity=50.0), "quad_gravity=50.0 is invalid: the hover thrust"),
        (dict(quad_attitude_freq=200.0), "quad_attitude_freq=200.0 is invalid: the physics step"),
        (dict(substeps=2), "substeps=2 is invalid: the physics step"),
        (dict(dt=0.05), "dt=0.05 is invalid: the physics step"),
        (dict(quad_tilt_limit=80.0, quad_crash_tilt=60.0), "quad_crash_tilt=60.0 is invalid"),
    ]
    for overrides, start in cases:
        with pytest.raises(ValueError) as e:
            make_config("paper-quadrotor", **overrides)
        msg = str(e.value)
        assert msg.startswith(start), msg
        assert "[with " in msg  # and the values of the other fields of the rule
    # a rule none of whose fields the user set names its first field
    with pytest.raises(ValueError, match=r"^radius=6.0 is invalid: must exceed spacing"):
        make_config("paper", radius=6.0)
    with pytest.raises(ValueError, match=r"^spacing=9.0 is invalid: .*\[with radius=8.4\]"):
        make_config("paper", spacing=9.0)


def test_placement_that_cannot_succeed_is_refused_at_construction():
    for preset, overrides, field in [
        ("paper", dict(min_init_spacing=200.0), "min_init_spacing"),
        ("paper", dict(swarm_half_width=2.0), "swarm_half_width"),
        ("paper-quadrotor", dict(n_uavs=300), "n_uavs"),
        ("paper", dict(init="random", pairs=((0, 1), (2, 3)), pair_corner=1.0), "pair_corner"),
        ("paper", dict(divergence_limit=80.0), "divergence_limit"),
    ]:
        with pytest.raises(ValueError, match=f"^{field}=.* is invalid: .*must") as e:
            make_config(preset, **overrides)
        assert "[with " in str(e.value)
    # as dense as allowed still places (2-D: 0.3, 3-D: 0.15 of the start box)

    cfg = make_config("paper", n_uavs=60, swarm_half_width=18.0, min_init_spacing=3.0)
    assert 0.2 < start_density(cfg) <= 0.3
    core = PairFlockCore(cfg, num_swarms=4)
    core.reset(seed=[0, 1, 2, 3])


def test_obs_size_formula_matches_the_layout():

    for dim in (2, 3):
        for k in (0, 1, 6, 1000):
            assert obs_size(dim, k) == ObsLayout(dim, k).size


# ------------------------------------------------------------------ the rename
def test_old_names_live_only_in_stored_data():
    """Before the first release no old name is kept as a keyword; the keys that committed
    model files store (``safe_distance``) load through pairflock_env.compat alone."""

    with pytest.raises(UnknownFieldError, match="'safe_distance'"):
        make_config("paper", safe_distance=1.5)
    with pytest.raises(TypeError, match="'safe_distance'"):
        PairInterfaceParams(safe_distance=3.0)
    cfg = make_config("paper", reward_separation_distance=1.5)
    stored = cfg.to_dict()
    stored["safe_distance"] = stored.pop("reward_separation_distance")
    itf = make_interface("pair", cfg, separation_distance=3.0)
    stored_itf = {**itf.to_dict()}
    stored_itf["safe_distance"] = stored_itf.pop("separation_distance")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # stored model metadata loads silently
        assert PairFlockConfig.from_dict(stored) == cfg
        assert interface_from_dict(stored_itf, cfg).params == itf.params
    with pytest.raises(ValueError, match="both 'safe_distance'"):
        PairFlockConfig.from_dict({**stored, "reward_separation_distance": 1.5})
    with pytest.raises(ValueError, match="kind='model'"):
        upgrade_stored("model", {})


def test_an_unpickled_config_is_validated_again():
    """Issue 28, 8(e): a pickle is data; one holding an invalid value does not load."""

    cfg = make_config("paper", n_uavs=20)
    assert pickle.loads(pickle.dumps(cfg)) == cfg
    tampered = copy.copy(cfg)
    object.__setattr__(tampered, "dt", -0.01)  # what a pickle written by other code may hold
    bad = pickle.dumps(tampered)
    with pytest.raises(ValueError, match=r"^dt=-0.01 is invalid"):
        pickle.loads(bad)
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.dt = 0.02


def test_docs_config_md_is_current():

    path = Path(__file__).parent.parent / "docs" / "config.md"
    assert path.read_text(encoding="utf-8") == render(), (
        "docs/config.md is stale: run `python -m pairflock_env.config.docs docs/config.md`"
    )
    text = render()

    for name in SCHEMA.fields:
        assert f"| `{name}` |" in text
    for lim in LIMITS:
        assert f"`{lim.name}`" in text
