"""Configuration: presets, overrides and the invalid-configuration matrix."""

from __future__ import annotations

import dataclasses

import pytest

from pairflock_env import PRESETS, PairFlockConfig, make_config, parallel_env


def test_paper_preset_matches_the_notes_table():
    cfg = make_config("paper")
    assert cfg.preset == "paper"
    assert (cfg.dim, cfg.d_m, cfg.spacing, cfg.radius) == (2, (5.0,), 7.0, 8.4)
    assert (cfg.attraction, cfg.repulsion, cfg.consensus) == (1.0, 10.0, 1.0)
    assert (cfg.pinning, cfg.pin_position_gain, cfg.pin_velocity_gain) == ("all", 0.1, 0.632)
    assert cfg.leader_position == (25.0, 25.0) and cfg.leader_velocity == (0.5, 0.5)
    assert cfg.dt == 0.01 and cfg.episode_steps == 5000
    # g_r(d) = a defines sigma: 10 exp(-d^2/sigma^2) = 1
    import math

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
    with pytest.raises(ValueError, match="Did you mean 'n_uavs'"):
        make_config("paper", n_uav=20)
    with pytest.raises(ValueError, match="unknown configuration field 'bogus'"):
        parallel_env(bogus=1)
    with pytest.raises(ValueError, match="preset"):
        make_config("nope")


def test_config_is_frozen_and_serialisable():
    cfg = make_config("paper")
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.n_uavs = 3  # type: ignore[misc]
    d = cfg.to_dict()
    assert PairFlockConfig(**{**d, "pairs": [tuple(p) for p in d["pairs"]]}) == cfg
