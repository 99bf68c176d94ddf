"""The safety filter inside the env: config, the core's stage 2b, infos in every view."""

from __future__ import annotations

import csv
import subprocess
import sys
import warnings

import numpy as np
import pytest
from view_helpers import VIEWS, make_view, reset_view, step_view, zero_action

from baselines.controllers import make_pair_policy
from baselines.experiments.benchmark.cli import build_parser, resolve
from baselines.experiments.safety.figure import closest_pass_figure, read_rows
from pairflock_env import AGENT_INFO_KEYS, PairFlockConfig, PairFlockCore, make_config
from pairflock_env.config.sections.safety import (
    BOUND_OTHER_SHARE as QUAD_OTHER_SHARE,
)
from pairflock_env.config.sections.safety import (
    BRAKE_SHARE,
    DECAY,
    OTHER_SHARE,
)
from pairflock_env.dynamics import VEHICLES
from pairflock_env.dynamics.quadrotor.section import REACTION_CYCLES as QUAD_REACTION_CYCLES
from pairflock_env.safety import SafetyParams
from pairflock_env.safety.stage import SAFETY_INFO_KEYS

CBF = dict(safety_filter="cbf")


def _run(core, policy, steps, seeds):
    """Steps of ``policy``; yields each step's result (the reset's first)."""
    res = core.reset(seed=seeds)
    yield res
    B, M = core.num_swarms, core.n_agents
    for _ in range(steps):
        a, _ = policy.predict(res.obs.reshape(B * M, -1), deterministic=True)
        res = core.step(a.reshape(B, M, -1))
        yield res


# --------------------------------------------------------------------------- config
def test_config_section_defaults_keep_the_filter_off():
    cfg = make_config("paper")
    assert cfg.safety_filter == "none"
    assert make_config("paper", safety_filter=None).safety_filter == "none"  # --set ...=none
    sec = cfg.section("safety")
    assert set(sec) >= {"safety_filter", "safety_distance", "safety_sensing_radius"}
    # the filter's parameters follow the config: None means SafetyParams' own defaults
    on = make_config("paper", **CBF)
    assert SafetyParams.from_config(on) == SafetyParams(
        accel_limit=on.pair_accel_limit, dt=on.dt, substeps=on.substeps
    )
    p = SafetyParams.from_config(
        on.replace(safety_distance=2.0, safety_brake_accel=300.0, safety_other_accel=30.0)
    )
    assert (p.safety_distance, p.brake_accel, p.other_accel) == (2.0, 300.0, 30.0)
    assert SafetyParams.from_config(on.replace(safety_reaction_time=0.1)).reaction_time == 0.1


def test_unset_filter_parameters_follow_the_vehicle():
    """On the quadrotor the unset parameters come from the vehicle: alpha and A_o within
    quad_accel_limit, tau from the attitude loop's frequency, the quadrotor rate; set values
    and the particle model are left alone."""
    q = make_config("paper-quadrotor", **CBF)
    p = SafetyParams.from_config(q)
    L, U = q.quad_accel_limit, q.pair_accel_limit
    assert U * BRAKE_SHARE > L  # so the vehicle's bound is the one that binds here
    assert p.brake_accel == L and p.other_accel == pytest.approx(QUAD_OTHER_SHARE * L)
    assert p.reaction_time == pytest.approx(QUAD_REACTION_CYCLES / q.quad_attitude_freq)
    assert p.decay == VEHICLES["quadrotor"].safety_decay
    # what docs/safety-results.md measured on the quadrotor, to the last bit
    assert (p.brake_accel, p.other_accel, p.reaction_time, p.decay) == (6.0, 2.0, 0.1, 0.1)
    # the attitude loop sets tau: a slower loop (with the physics step it needs) waits longer
    slow = SafetyParams.from_config(q.replace(quad_attitude_freq=7.5))
    assert slow.reaction_time == pytest.approx(2 * p.reaction_time)
    # a narrow tilt cone binds before quad_accel_limit: g tan(20 deg) = 3.57 m/s^2
    narrow = SafetyParams.from_config(q.replace(quad_tilt_limit=20.0))
    bound = q.quad_gravity * np.tan(np.radians(20.0))
    assert bound < L and narrow.brake_accel == pytest.approx(bound)
    assert narrow.other_accel == pytest.approx(QUAD_OTHER_SHARE * bound)
    # a small pair budget binds before the vehicle does
    small = SafetyParams.from_config(q.replace(pair_accel_limit=2.0))
    assert (small.brake_accel, small.other_accel) == (BRAKE_SHARE * 2.0, OTHER_SHARE * 2.0)
    # the same scenario on the particle model keeps the generic defaults
    part = SafetyParams.from_config(q.replace(dynamics="particle"))
    assert (part.brake_accel, part.other_accel) == (BRAKE_SHARE * U, OTHER_SHARE * U)
    assert (part.reaction_time, part.decay) == (0.0, DECAY)
    # values that are set win on either vehicle
    mine = dict(
        safety_brake_accel=5.0, safety_other_accel=1.0, safety_reaction_time=0.0, safety_decay=0.5
    )
    for dyn in ("quadrotor", "particle"):
        s = SafetyParams.from_config(q.replace(dynamics=dyn, **mine))
        assert (s.brake_accel, s.other_accel, s.reaction_time, s.decay) == (5.0, 1.0, 0.0, 0.5)
    # the config stores None for an unset value (the vehicle resolves it)
    assert q.safety_reaction_time is None and q.safety_decay is None


@pytest.mark.parametrize(
    "overrides, exc, start",
    [
        (dict(safety_filter="qp"), ValueError, "safety_filter='qp' is invalid"),
        (dict(safety_filter=1), TypeError, "safety_filter=1 is invalid"),
        (dict(safety_distance=0.0), ValueError, "safety_distance=0.0 is invalid"),
        (dict(safety_distance="1"), TypeError, "safety_distance='1' is invalid"),
        (dict(safety_decay=0.0), ValueError, "safety_decay=0.0 is invalid"),
        (dict(safety_decay=1.5), ValueError, "safety_decay=1.5 is invalid"),
        (dict(safety_brake_accel=0.0), ValueError, "safety_brake_accel=0.0 is invalid"),
        (dict(safety_other_accel=-1.0), ValueError, "safety_other_accel=-1.0 is invalid"),
        (dict(safety_sensing_radius=float("nan")), ValueError, "safety_sensing_radius=nan"),
        (dict(safety_margin=-0.1), ValueError, "safety_margin=-0.1 is invalid"),
        (dict(safety_margin=[0.1]), TypeError, "safety_margin=[0.1] is invalid"),
        (dict(safety_reaction_time=-0.1), ValueError, "safety_reaction_time=-0.1 is invalid"),
        (dict(safety_reaction_time="0"), TypeError, "safety_reaction_time='0' is invalid"),
        (dict(safety_decay="0.1"), TypeError, "safety_decay='0.1' is invalid"),
    ],
)
def test_bad_safety_fields_name_field_and_range(overrides, exc, start):
    with pytest.raises(exc) as e:
        make_config("paper", **overrides)
    assert str(e.value).startswith(start), str(e.value)


def test_cross_field_rules_are_checked_at_construction():
    limit = make_config("paper").pair_accel_limit
    with pytest.raises(ValueError, match=r"^safety_brake_accel=.* must be <= pair_accel_limit"):
        make_config("paper", safety_brake_accel=2 * limit)
    with pytest.raises(ValueError, match=r"^safety_other_accel=.* below the brake"):
        make_config("paper", safety_other_accel=limit)  # default brake: 0.8 of the limit
    with pytest.raises(ValueError, match=r"^safety_other_accel=.* below the brake"):
        make_config("paper", safety_brake_accel=10.0, safety_other_accel=10.0)
    with pytest.raises(ValueError, match=r"^safety_sensing_radius=.* above safety_distance"):
        make_config("paper", safety_sensing_radius=2.0, safety_distance=2.0)
    with pytest.raises(ValueError, match=r"above safety_distance \+ safety_margin \(1 \+ 1.5 m\)"):
        make_config("paper", safety_sensing_radius=2.0, safety_margin=1.5)
    with warnings.catch_warnings():  # a stored config loads silently
        warnings.simplefilter("error")
        cfg = make_config("paper", **CBF)
        assert PairFlockConfig.from_dict(cfg.to_dict()) == cfg
    # the quadrotor's unset reaction time 1.5 / quad_attitude_freq must fit the field's range
    with pytest.raises(ValueError, match=r"^quad_attitude_freq=0.01 is invalid: .*150 s"):
        make_config("paper-quadrotor", safety_filter="cbf", quad_attitude_freq=0.01)
    assert make_config("paper-quadrotor", quad_attitude_freq=0.01).safety_filter == "none"
    # the defaults scale with pair_accel_limit, so a small budget stays valid
    assert make_config("paper", pair_accel_limit=1e-3, **CBF).safety_filter == "cbf"


# --------------------------------------------------------------------------- core
def test_filter_off_passes_the_command_through_and_reports_zeros():
    core = PairFlockCore(preset="paper", n_uavs=8, num_swarms=2)
    res = core.reset(seed=0)
    u = np.ones((2, core.n_agents, 2))
    assert core.safety.apply(core.q, core.p, core.flock_accel, u) is u
    res = core.step(np.full((2, core.n_agents, 2), 0.3))
    for k in SAFETY_INFO_KEYS:
        assert res.info[k].shape == (2, core.n_agents) and not res.info[k].any()
    assert set(SAFETY_INFO_KEYS) <= set(AGENT_INFO_KEYS)


def test_filter_changes_nothing_while_no_uav_is_within_the_sensing_radius():
    """At the paper's start the pair is in the corners, far from everyone: the filtered run
    is bit-identical to the unfiltered one until a UAV enters an agent's sensing radius."""
    cfg = make_config("paper", n_uavs=20)
    runs = []
    for c in (cfg, cfg.replace(**CBF)):
        core = PairFlockCore(c, num_swarms=2)
        pol = make_pair_policy("smc", c)
        qs = []
        for res in _run(core, pol, 300, [1, 2]):
            d = np.linalg.norm(core.q[:, :, None] - core.q[:, None, core.agent_uavs], axis=-1)
            d[:, core.agent_uavs, np.arange(core.n_agents)] = np.inf
            qs.append((core.q.copy(), d.min(), res.info["safety_active"].any()))
        runs.append(qs)
    for (q0, dmin, _), (q1, _, active) in zip(*runs, strict=True):
        if dmin < cfg.safety_sensing_radius:
            break
        assert not active and np.array_equal(q0, q1)
    else:
        pytest.fail("no UAV came within the sensing radius: the test checks nothing")


def test_smc_with_the_filter_keeps_the_safety_distance_at_n20_corners():
    """Every paired UAV keeps >= safety_distance from every other UAV (partner included)
    over a whole episode, unless the filter reports an infeasible step."""
    cfg = make_config("paper", n_uavs=20, **CBF)
    seeds = [30000, 30001, 30002]
    core = PairFlockCore(cfg, num_swarms=len(seeds))
    closest = np.full(len(seeds), np.inf)
    infeasible = np.zeros(len(seeds), int)
    active = 0
    for res in _run(core, make_pair_policy("smc", cfg), cfg.episode_steps, seeds):
        near = np.minimum(res.info["min_separation"], res.info["pair_distance"])
        closest = np.minimum(closest, near.min(axis=1))
        infeasible += res.info["safety_infeasible"].sum(axis=1)
        active += int(res.info["safety_active"].sum())
        assert (res.info["safety_correction"] >= 0).all()
    tol = 1e-9 * cfg.safety_distance
    assert active > 0  # the filter had something to do
    assert ((closest >= cfg.safety_distance - tol) | (infeasible > 0)).all(), closest


def test_filtered_command_is_the_applied_one():
    cfg = make_config("paper", n_uavs=20, pair_accel_limit=50.0, **CBF)
    core = PairFlockCore(cfg, num_swarms=2)
    pol = make_pair_policy("smc", cfg)
    changed = False
    for k, res in enumerate(_run(core, pol, 300, [3, 4])):
        if k == 0:
            continue
        u = core.safety.output.u
        assert np.allclose(res.info["pair_accel"], np.linalg.norm(u, axis=-1), rtol=1e-12)
        assert (np.linalg.norm(u, axis=-1) <= cfg.pair_accel_limit * (1 + 1e-12)).all()
        # the core's effort term charges the applied (filtered) command
        effort = -cfg.reward_effort_weight * (u * u).sum(-1) / cfg.pair_accel_limit**2
        assert np.allclose(res.info["reward_effort"], effort, rtol=1e-12, atol=0)
        changed |= bool(res.info["safety_active"].any())
    assert changed


@pytest.mark.parametrize("tau", [0.0, 0.1, None])
def test_quadrotor_gets_the_filter_too(tau):
    cfg = make_config("paper-quadrotor", **CBF, safety_reaction_time=tau)
    core = PairFlockCore(cfg, num_swarms=1)
    assert core.safety.filter.params.reaction_time == (0.1 if tau is None else tau)
    pol = make_pair_policy("smc", cfg)
    for res in _run(core, pol, 20, [0]):
        assert all(res.info[k].shape == (1, core.n_agents) for k in SAFETY_INFO_KEYS)
    assert core.safety.output.u.shape == (1, core.n_agents, 3)


# --------------------------------------------------------------------------- views
def _agent_infos(kind, out, env):
    """One per-agent info dict of a view's step (or reset) output."""
    if kind == "parallel":
        return out[-1][env.agents[0]]
    if kind == "aec":
        return out[-1]
    if kind == "sb3":
        return out[-1][0]
    return out[-1]  # gym single and vector: dict of (per-agent) values


@pytest.mark.parametrize("kind", VIEWS)
@pytest.mark.parametrize("mode", ["none", "cbf"])
def test_safety_infos_in_every_view(kind, mode):
    kw = dict(safety_filter=mode)
    if kind == "sb3":
        kw["info_keys"] = "all"
    env = make_view(kind, **kw)
    reset_view(env, kind, seed=0)
    for _ in range(3):
        out = step_view(env, kind, zero_action(env, kind))
    info = _agent_infos(kind, out, env)
    for k in SAFETY_INFO_KEYS:
        v = np.asarray(info[k])
        assert v.dtype.kind in "biuf" and np.isfinite(v).all(), (k, v)
        if mode == "none":
            assert not v.any()
    env.close()


# --------------------------------------------------------------------------- benchmark
def test_benchmark_safety_suite_runs_filter_off_and_on(tmp_path):

    out = tmp_path / "safety"
    cmd = [sys.executable, "-m", "baselines.benchmark", "--suite", "safety", "--seeds", "1"]
    cmd += ["--n-uavs", "20", "--set", "init=corners", "-p", "smc", "--workers", "2"]
    cmd += ["--no-figures", "--quiet", "--out", str(out)]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert sorted(r["safety_filter"] for r in rows) == ["cbf", "none"]
    assert all(r["seed"] == "30000" for r in rows)  # the suite's held-out seeds
    for r in rows:
        assert {"closest_pass", "safety_infeasible_steps", "peak_correction"} <= set(r)
        on = r["safety_filter"] == "cbf"
        assert (int(r["safety_active_steps"]) > 0) == on
    summary = (out / "summary.md").read_text()
    assert "## Safety filter" in summary and "runs >= safety_distance" in summary
    assert "runs >= safety_distance" in done.stdout
    # the paired comparison reads the benchmark's own columns: one smc run off and on
    paired = subprocess.run(
        [sys.executable, "-m", "baselines.safety_compare", str(out), "--bootstrap", "10"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "| smc | ss_mean_error | 1 |" in paired and "| smc | band_time | 1 |" in paired

    fig = closest_pass_figure(read_rows([out]), tmp_path / "closest.png")
    assert fig.stat().st_size > 0
    with pytest.raises(ValueError, match="no closest_pass"):
        (tmp_path / "plain").mkdir()
        (tmp_path / "plain" / "results.csv").write_text("scenario,policy\nx,smc\n")
        read_rows([tmp_path / "plain"])


def test_benchmark_set_safety_filter_adds_the_safety_columns_to_every_run():

    parser = build_parser()
    args = parser.parse_args(["--suite", "quick", "--set", "safety_filter=none,cbf"])
    plan = resolve(args, parser)
    assert [c.safety_filter for c in plan.configs] == ["none", "cbf"]
    assert plan.metric_kwargs.get("safety_metrics") is True
    args = parser.parse_args(["--suite", "quick"])
    assert "safety_metrics" not in resolve(args, parser).metric_kwargs
    args = parser.parse_args(["--suite", "safety"])
    assert resolve(args, parser).seeds[0] == 30000  # the suite's held-out seeds
