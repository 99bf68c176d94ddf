"""Invariants of the quadrotor model, its inner loop, the climb-and-turn leader and SO(3) maths.

The shared contract (PettingZoo checkers, determinism, batching, bad input, baselines) runs
over both vehicle models through the ``dynamics`` fixture in the other test files.
"""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from baselines.experiments.quadrotor.invariants import (
    hover_drift,
    hovering_model,
    orthonormality_over_scenario,
    step_response,
)
from baselines.experiments.quadrotor.runs import scenario_metrics
from baselines.quadrotor_experiment import main
from pairflock_env import PairFlockCore, make_config, parallel_env
from pairflock_env.dynamics.quadrotor import QuadrotorModel
from pairflock_env.dynamics.quadrotor import kernels as Q
from pairflock_env.math3d import (
    euler_zyx,
    hat,
    orthonormality_error,
    rotation_zyx,
    so3_exp,
    vee,
)
from pairflock_env.swarm.leader import ClimbAndTurnLeader, make_leader

G = 9.81


def _model(B=1, N=2, **overrides):
    """A bare model at the preset's rates, every UAV hovering at rest at 20 m altitude."""
    return hovering_model(B, N, **overrides)


# --------------------------------------------------------------------------- physics
def test_hover_with_the_exact_thrust_does_not_drift():
    h = hover_drift(seconds=10.0)  # 5000 physics steps, float64
    assert h["position_drift_m"] < 1e-6
    assert h["velocity_drift_mps"] < 1e-6
    assert h["orthonormality_error"] < 1e-12
    assert h["rotor_speed_change"] < 1e-9 and not h["motor_saturated"]
    cfg, model, _, _ = _model(B=2, N=3)
    np.testing.assert_allclose(model.motor_thrust, cfg.quad_mass * G / 4, rtol=1e-12)
    info = model.info()
    assert not info["vehicle_terminated"].any() and not info["motor_saturated"].any()


@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.0, 1.0), (1.0, -1.0)])
def test_acceleration_step_meets_the_tracking_criteria(direction):
    s = step_response(direction, size=2.0)
    assert s["t90_s"] <= 0.4, s["t90_s"]
    assert s["settle_10pct_s"] < 1.0, s["settle_10pct_s"]
    assert s["overshoot"] <= 0.35, s["overshoot"]
    assert not s["motor_saturated"]
    assert s["ratio"][-1] == pytest.approx(1.0, abs=1e-3)  # and it does track the command


def test_with_ideal_motors_the_attitude_loop_is_the_designed_second_order_system():
    """K_R = J wn^2, K_w = 2 zeta J wn: a small tilt step follows
    theta / theta_c = 1 - exp(-zeta wn t) (cos(wd t) + zeta / sqrt(1 - zeta^2) sin(wd t))."""
    cfg, model, q, p = _model(dt=0.002, substeps=1, quad_motor_time_constant=0.0)
    a = np.zeros_like(q)
    a[0, 0, 0] = 0.2  # pitch forward by atan(0.2 / g) = 1.17 deg
    n = 400
    pitch = np.empty(n)
    for k in range(n):
        model.advance(q, p, a)
        pitch[k] = euler_zyx(model.R[0, 0])[1]
    t = cfg.physics_dt * np.arange(1, n + 1)
    wn, zeta = cfg.quad_attitude_freq, cfg.quad_attitude_damping
    wd = wn * math.sqrt(1 - zeta**2)
    ideal = 1 - np.exp(-zeta * wn * t) * (
        np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t)
    )
    np.testing.assert_allclose(pitch / math.atan(0.2 / G), ideal, atol=0.02)


def test_rigid_body_and_mixer_conventions():
    """With frozen rotors (huge motor time constant) one physics step from rest must give
    w = h J^-1 A[1:] T and dv = h (R e3 sum(T) / m - g e3), A the documented mixer matrix."""
    cfg, model, q, p = _model(dt=0.002, substeps=1, quad_motor_time_constant=1e9)
    prm = model.params
    T = np.array([1.0, 1.2, 0.9, 1.3])
    model.rotor_speed[0, 0] = np.sqrt(T / prm.k_f)
    model.advance(q, p, np.zeros_like(q))
    A = prm.mixer_matrix()
    f, *M = A @ T
    h = cfg.physics_dt
    np.testing.assert_allclose(
        model.omega[0, 0], h * np.asarray(M) / prm.inertia, rtol=1e-9, atol=1e-12
    )
    np.testing.assert_allclose(p[0, 0], [0.0, 0.0, h * (f / prm.mass - G)], atol=1e-9)
    # the mixer's rows are orthogonal: A^-1 = A^T diag(1 / row norms^2)
    inv = A.T / np.sum(A * A, axis=1)
    np.testing.assert_allclose(A @ inv, np.eye(4), atol=1e-12)


def test_mixer_inverts_the_rotor_map_and_desaturates_thrust_before_attitude():
    cfg, model, _, _ = _model()
    prm = model.params
    A = prm.mixer_matrix()
    hover = cfg.quad_mass * G
    f = np.array([hover, 3.0 * hover, hover, 0.0])
    M = np.array(
        [
            [0.01, -0.02, 0.003],  # fits
            [0.05, 0.0, 0.0],  # too much thrust: the collective gives way
            [2.0, -1.0, 0.1],  # moments beyond the rotors: scaled, direction kept
            [0.0, 0.0, 0.0],
        ]
    )  # below idle thrust
    T, sat = prm.mix(f, M)
    assert sat.tolist() == [False, True, True, True]
    assert T.min() >= cfg.quad_motor_thrust_min - 1e-12
    assert T.max() <= cfg.quad_motor_thrust_max + 1e-12
    out = T @ A.T  # [f, Mx, My, Mz] actually produced
    np.testing.assert_allclose(out[0], np.r_[f[0], M[0]], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(out[1, 1:], M[1], rtol=1e-12, atol=1e-15)
    assert out[1, 0] < f[1]
    cos = out[2, 1:] @ M[2] / np.linalg.norm(out[2, 1:]) / np.linalg.norm(M[2])
    assert cos == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(T[3], cfg.quad_motor_thrust_min)
    # plain clipping (quad_mixer="clip") keeps thrust but bends the moments
    clip = make_config("paper-quadrotor", quad_mixer="clip")
    Tc, sat_c = QuadrotorModel(clip, 1).params.mix(f, M)
    assert sat_c.tolist() == sat.tolist()
    np.testing.assert_array_equal(Tc[0], T[0])
    bent = Tc[2] @ A.T
    assert bent[1:] @ M[2] / np.linalg.norm(bent[1:]) / np.linalg.norm(M[2]) < 0.999


def test_acceleration_limit_and_tilt_cone_hold():
    cfg, model, q, p = _model(N=3)
    a = np.zeros_like(q)
    a[0, 0] = (50.0, 0.0, 0.0)  # cut to 6 m/s^2 by the acceleration limit (tilt 31.4 deg)
    a[0, 1] = (4.5, 0.0, -4.0)  # within 6 m/s^2 but would need 37.7 deg: the cone cuts it
    max_tilt = np.zeros(3)
    for _ in range(100):  # 2 s
        model.advance(q, p, a)
        max_tilt = np.maximum(max_tilt, model.tilt()[0])
    assert model.accel_limited[0, 0] and model.accel_limited[0, 1]
    assert not model.accel_limited[0, 2]
    assert max_tilt[0] == pytest.approx(math.degrees(math.atan(6.0 / G)), abs=0.5)
    assert 34.0 < max_tilt[1] <= cfg.quad_tilt_limit + 0.5
    assert max_tilt[2] < 1e-9
    info = model.info()
    assert info["accel_limited_uavs"][0] == 2 and info["accel_limited"][0].all()


def test_heading_is_held_during_manoeuvres():
    _, model, q, p = _model(N=2, quad_yaw=30.0)
    np.testing.assert_allclose(euler_zyx(model.R)[..., 2], math.radians(30.0))
    rng = np.random.default_rng(0)
    for _ in range(150):  # 3 s of random commands, changed every control period
        model.advance(q, p, rng.uniform(-4.0, 4.0, q.shape))
    # the commanded attitude has exactly the fixed heading as its ZYX yaw; the actual one
    # stays close while roll and pitch move
    np.testing.assert_allclose(euler_zyx(model.R_des)[..., 2], math.radians(30.0), atol=1e-12)
    yaw = euler_zyx(model.R)[..., 2]
    assert np.abs(yaw - math.radians(30.0)).max() < math.radians(1.0)
    assert model.tilt().max() > 5.0  # it really manoeuvred


def test_drag_is_compensated():
    _, model, q, p = _model(quad_drag=0.25)
    p[0, 0] = (5.0, 0.0, 0.0)
    a = np.zeros_like(q)
    for _ in range(50):  # 1 s: the attitude settles to balance the drag
        model.advance(q, p, a)
    v1 = p[0, 0].copy()
    for _ in range(200):  # 4 s more
        model.advance(q, p, a)
    assert np.linalg.norm(p[0, 0] - v1) < 0.01
    assert model.tilt()[0, 0] > 1.0  # leaning into the drag


def test_motor_saturation_is_reported_and_thrusts_stay_in_limits():
    cfg, model, q, p = _model()
    model.R[0, 0] = rotation_zyx(math.radians(80.0), 0.0, 0.0)  # badly upset
    saturated = False
    for _ in range(100):
        model.advance(q, p, np.zeros_like(q))
        saturated |= bool(model.motor_saturated[0, 0])
        T = model.motor_thrust
        assert T.min() >= cfg.quad_motor_thrust_min - 1e-12
        assert T.max() <= cfg.quad_motor_thrust_max + 1e-12
    assert saturated and not model.crashed.any()
    assert model.tilt()[0, 0] < 2.0  # recovered


# --------------------------------------------------------------------------- crashes
def test_a_flipped_uav_crashes_and_stops():
    _, model, q, p = _model(N=2)
    model.R[0, 1] = rotation_zyx(math.pi, 0.0, 0.0)  # upside down
    model.advance(q, p, np.zeros_like(q))
    assert model.crashed[0].tolist() == [False, True]
    q_crash = q[0, 1].copy()
    for _ in range(10):
        model.advance(q, p, np.zeros_like(q))
    np.testing.assert_array_equal(q[0, 1], q_crash)
    assert np.all(p[0, 1] == 0.0) and np.all(model.rotor_speed[0, 1] == 0.0)
    info = model.info()
    assert info["vehicle_terminated"][0] and info["crashed_uavs"][0] == 1
    assert info["crashed"][0].tolist() == [False, True]
    model.reset_rows(np.arange(1), q, p)
    assert not model.crashed.any() and not model.info()["vehicle_terminated"].any()


def test_a_non_finite_command_crashes_only_that_uav():
    _, model, q, p = _model(N=3)
    a = np.zeros_like(q)
    a[0, 2, 1] = np.nan
    model.advance(q, p, a)
    assert model.crashed[0].tolist() == [False, False, True]
    assert np.isfinite(q).all() and np.isfinite(p).all() and np.isfinite(model.R).all()


def test_hitting_the_ground_ends_the_episode_in_every_view():
    # push paired UAV 0 down with its own action: the 6 m/s^2 limit lets it fall 2 m in ~0.8 s
    env = parallel_env(preset="paper-quadrotor", n_uavs=6, quad_ground_altitude=18.0)
    env.reset(seed=0)
    down = np.array([0.0, 0.0, -1.0])
    for _ in range(200):
        _, _, terms, truncs, infos = env.step({"uav_0": down, "uav_1": np.zeros(3)})
        if any(terms.values()):
            break
    assert all(terms.values()) and not any(truncs.values()) and env.agents == []
    assert 0.5 < infos["uav_0"]["sim_time"] < 1.5
    assert infos["uav_0"]["crashed"] and not infos["uav_1"]["crashed"]
    assert infos["uav_0"]["vehicle_terminated"] and infos["uav_0"]["crashed_uavs"] == 1
    assert env.core.q[0, 0, 2] <= 18.0 + 1e-9
    env.reset(seed=0)  # a reset clears the crash
    assert env.agents and not env.core.vehicle.crashed.any()


def test_core_reports_the_vehicle_diagnostics_per_agent_and_per_swarm():
    core = PairFlockCore(make_config("paper-quadrotor"), num_swarms=2, seed=0)
    res = core.reset()
    M = core.n_agents
    res = core.step(np.zeros((2, M, 3)))
    for key in ("crashed", "motor_saturated", "accel_limited", "tilt"):
        assert res.info[key].shape == (2, M)
    for key in ("vehicle_terminated", "crashed_uavs", "motor_saturated_uavs", "accel_limited_uavs"):
        assert res.info[key].shape == (2,)
    assert np.all(res.info["tilt"] > 0)  # the pair starts 14 m from its flock and leans in


# --------------------------------------------------------------------------- paper scenario
def test_rotation_stays_orthonormal_over_the_65_s_scenario():
    o = orthonormality_over_scenario(seed=0)
    assert o["sim_time_s"] == pytest.approx(65.0) and not o["terminated"]
    assert o["max_orthonormality_error"] < 1e-9, o
    assert o["max_tilt_deg"] > 20.0  # the attitude did move a lot


# --------------------------------------------------------------------------- leader
def test_climb_and_turn_leader_matches_the_scenario():
    leader = make_leader(make_config("paper-quadrotor"))
    t = np.array([0.0, 20.0, 22.0, 50.0, 52.0, 65.0])
    q, p = leader.state(t)
    np.testing.assert_allclose(q[0], [0.0, 0.0, 20.0])
    np.testing.assert_allclose(p[0], [5.0, 0.0, 1.0])
    np.testing.assert_allclose(q[1], [100.0, 0.0, 40.0])  # 20 s of climb at 1 m/s
    np.testing.assert_allclose(p[2], [0.0, 5.0, 0.0], atol=1e-12)  # left turn, level
    np.testing.assert_allclose(q[2, 2], 41.0)  # + half a second's worth while levelling off
    np.testing.assert_allclose(p[4], [-5.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 5.0)
    # the two turns are the same manoeuvre rotated by 90 degrees
    d1, d2 = q[2, :2] - q[1, :2], q[4, :2] - q[3, :2]
    np.testing.assert_allclose(d2, [-d1[1], d1[0]], atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_leader_velocity_is_the_derivative_of_its_position(dim):
    v0 = (3.0, 4.0, -0.5)[:dim]
    leader = ClimbAndTurnLeader(
        np.zeros(dim),
        np.array(v0),
        climb_time=5.0,
        level_time=3.0,
        turns=[(2.0, 4.0, 2.0), (6.5, 1.0, -1.0)],
    )
    t = np.linspace(0.0, 10.0, 2001)
    h = 1e-5
    qp, _ = leader.state(t + h)
    qm, _ = leader.state(t - h)
    _, p = leader.state(t)
    np.testing.assert_allclose((qp - qm) / (2 * h), p, atol=1e-6)
    # evaluating one time at a time gives the same as the batch
    one = np.array([leader.state(np.array([x]))[0][0] for x in t[::97]])
    np.testing.assert_array_equal(one, leader.state(t[::97])[0])


@pytest.mark.parametrize(
    "overrides, field",
    [
        (dict(leader_turns=((20.0, 2.0, 90.0), (21.0, 2.0, 90.0))), "leader_turns"),
        (dict(leader_turns=((20.0, 0.0, 90.0),)), "duration"),
        (dict(leader_turns=((20.0, 2.0),)), "leader_turns"),
        (dict(leader_velocity=(0.0, 0.0, 1.0)), "leader_velocity"),
        (dict(leader_level_time=-1.0), "leader_level_time"),
    ],
)
def test_bad_leader_paths_are_rejected(overrides, field):
    with pytest.raises(ValueError, match=field):
        make_config("paper-quadrotor", **overrides)


# --------------------------------------------------------------------------- config
@pytest.mark.parametrize(
    "overrides, exc, field",
    [
        (dict(quad_mass=0.0), ValueError, "quad_mass"),
        (dict(quad_mass="heavy"), TypeError, "quad_mass"),
        (dict(quad_inertia=(1e-2, 1e-2)), ValueError, "quad_inertia"),
        (dict(quad_inertia=(1e-2, -1e-2, 1e-2)), ValueError, "quad_inertia"),
        (dict(quad_motor_thrust_max=1.0), ValueError, "quad_motor_thrust_max"),
        (dict(quad_motor_thrust_min=1.2), ValueError, "quad_motor_thrust_min"),
        (dict(quad_motor_time_constant=-0.01), ValueError, "quad_motor_time_constant"),
        (dict(quad_tilt_limit=90.0), ValueError, "quad_tilt_limit"),
        (dict(quad_crash_tilt=30.0), ValueError, "quad_crash_tilt"),
        (dict(quad_ground_altitude="low"), TypeError, "quad_ground_altitude"),
        (dict(quad_mixer="priority"), ValueError, "quad_mixer"),
        (dict(substeps=2), ValueError, "substeps"),
        (dict(dim=2), ValueError, "dim"),
        (dict(pair_corner=(0.0, 0.0, 0.0)), ValueError, "pair_corner"),
        (dict(pairs=((0, 1), (2, 3))), ValueError, "pair_corner"),  # both pairs on z = 20
        (dict(swarm_center=(0.0, 1.0)), ValueError, "swarm_center"),
    ],
)
def test_bad_quadrotor_configs_name_the_field(overrides, exc, field):
    with pytest.raises(exc, match=field):
        make_config("paper-quadrotor", **overrides)


def test_quadrotor_overrides_and_preset():
    cfg = make_config("paper-quadrotor", quad_mass=0.5, quad_inertia=0.01)
    assert cfg.quad_mass == 0.5 and cfg.quad_inertia == (0.01, 0.01, 0.01)
    assert (cfg.n_uavs, cfg.dim, cfg.dt, cfg.physics_dt) == (10, 3, 0.02, 0.002)
    assert cfg.episode_steps == 3250 and cfg.d_m == (2.5,) and cfg.surface_slope == 1.0
    # the particle model flies the same scenario; its quad_* fields are unused
    part = cfg.replace(dynamics="particle")
    assert PairFlockCore(part).vehicle.name == "particle"
    # the error message says how many substeps the attitude loop needs
    with pytest.raises(ValueError, match="substeps >= 6"):
        make_config("paper-quadrotor", substeps=5)


# --------------------------------------------------------------------------- SO(3)
def test_so3_exp_hat_vee_and_euler_angles():
    rng = np.random.default_rng(1)
    phi = np.concatenate(
        [rng.normal(size=(50, 3)), 1e-7 * rng.normal(size=(5, 3)), np.zeros((1, 3))]
    )
    R = so3_exp(phi)
    assert orthonormality_error(R).max() < 1e-14
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", R, phi), phi, atol=1e-14)  # axis fixed
    # matches the matrix exponential's series for a small rotation
    small = 1e-3 * rng.normal(size=3)
    S = hat(small)
    series = np.eye(3) + S + S @ S / 2 + S @ S @ S / 6
    np.testing.assert_allclose(so3_exp(small), series, atol=1e-12)
    np.testing.assert_allclose(vee(hat(phi)), phi)
    np.testing.assert_allclose(hat(phi[0]) @ phi[1], np.cross(phi[0], phi[1]))
    ang = np.stack([rng.uniform(-3, 3, 20), rng.uniform(-1.5, 1.5, 20), rng.uniform(-3, 3, 20)], 1)
    np.testing.assert_allclose(euler_zyx(rotation_zyx(*ang.T)), ang, atol=1e-12)
    with pytest.raises(ValueError, match="phi"):
        so3_exp(np.zeros(4))


# --------------------------------------------------------------------------- experiment CLI
def test_experiment_cli_writes_table_csv_and_figures(tmp_path):

    out = tmp_path / "q"
    rc = main(
        [
            "--seeds",
            "2",
            "--horizon",
            "16",
            "--policies",
            "smc",
            "zero",
            "--workers",
            "1",
            "--out",
            str(out),
            "--quiet",
            "--dpi",
            "40",
        ]
    )
    assert rc == 0
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert {(r["dynamics"], r["policy"]) for r in rows} == {
        (d, p) for d in ("quadrotor", "particle") for p in ("smc", "zero")
    }
    smc = [r for r in rows if r["dynamics"] == "quadrotor" and r["policy"] == "smc"]
    zero = [r for r in rows if r["dynamics"] == "quadrotor" and r["policy"] == "zero"]
    assert all(
        float(a["straight_max_error"]) < float(b["straight_max_error"])
        for a, b in zip(smc, zero, strict=False)
    )
    summary = (out / "summary.md").read_text()
    assert "| quadrotor | smc |" in summary and "Criteria" in summary
    for name in ("snapshots", "trajectories_3d", "sliding_surface", "pair_error", "euler_angles"):
        assert (out / f"{name}.png").stat().st_size > 1000
    # 4 s cannot show the criteria's windows: --check must fail rather than pass vacuously
    assert (
        main(
            [
                "--seeds",
                "1",
                "--horizon",
                "4",
                "--policies",
                "smc",
                "--dynamics",
                "quadrotor",
                "--workers",
                "1",
                "--out",
                str(out / "c"),
                "--quiet",
                "--no-figures",
                "--check",
            ]
        )
        == 1
    )
    with pytest.raises(SystemExit, match="quad_mass"):
        main(["--set", "quad_mass=-1", "--out", str(out / "bad"), "--quiet"])


def test_turn_peak_since_filter_is_the_time_from_the_last_filter_action_to_the_peak():

    t = np.arange(0.0, 65.0, 0.02)
    err = np.where(np.abs(t - 22.0) < 1e-9, 0.9, 0.1)  # the turn peak at 22 s
    err[np.abs(t - 40.0) < 1e-9] = 2.0  # larger, but in straight flight
    flat = np.zeros_like(t)
    active = np.zeros(t.shape, bool)

    def since(act):
        return scenario_metrics(t, err, flat + 3, flat, flat, filter_active=act)[
            "turn_peak_since_filter"
        ]

    assert np.isnan(since(None))  # the filter is off
    assert np.isnan(since(active))  # it never acted before the peak
    active[(t > 30.0)] = True  # ...only after it
    assert np.isnan(since(active))
    active[np.abs(t - 20.5) < 1e-9] = True
    assert since(active) == pytest.approx(1.5)
    active[np.abs(t - 22.0) < 1e-9] = True  # acting at the peak
    assert since(active) == 0.0


def test_experiment_gains_reach_sliding_mode_and_bad_ones_name_their_flag(tmp_path):

    common = ["--policies", "smc", "--dynamics", "quadrotor", "--seeds", "1", "--horizon", "2"]
    common += ["--workers", "1", "--no-figures", "--quiet"]
    chatter = {}
    for name, extra in (("sign", []), ("layer", ["--smc-boundary-layer", "50"])):
        assert main([*common, *extra, "--out", str(tmp_path / name)]) == 0
        (row,) = csv.DictReader((tmp_path / name / "results.csv").open())
        chatter[name] = float(row["chattering"])
    assert chatter["layer"] < chatter["sign"]  # a wide layer smooths the switching term
    for flag, value in (("--smc-boundary-layer", "0"), ("--smc-k", "-1"), ("--kp", "nan")):
        pol = ["--policies", "proportional"] if flag == "--kp" else []
        with pytest.raises(SystemExit, match=f"^{flag}: .* is invalid"):
            main([*common, *pol, flag, value, "--out", str(tmp_path / "bad")])
    assert not (tmp_path / "bad").exists()


# --------------------------------------------------------------------------- kernel stages
def test_kernel_stages_match_their_documented_formulas():
    """The scalar stages the kernel is built from, one by one, against numpy."""

    prm = QuadrotorModel(make_config("paper-quadrotor"), 1).params
    # 1. acceleration limit, and a non-finite command
    a, cut, ok = Q._limit_command(3.0, 4.0, 0.0, 2.5)
    np.testing.assert_allclose(a, (1.5, 2.0, 0.0))
    assert cut and ok
    assert Q._limit_command(0.1, 0.0, 0.0, 2.5)[1:] == (False, True)
    assert not Q._limit_command(np.nan, 0.0, 0.0, 2.5)[2]
    # 3. desired attitude: orthonormal, b3 along F, heading psi
    psi = math.radians(30.0)
    F = np.array([1.0, -2.0, 9.0])
    b1, b2, b3 = (np.array(c) for c in Q._desired_attitude(tuple(F), math.cos(psi), math.sin(psi)))
    Rd = np.stack([b1, b2, b3], axis=1)
    np.testing.assert_allclose(Rd.T @ Rd, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(b3, F / np.linalg.norm(F), rtol=1e-15)
    assert euler_zyx(Rd)[2] == pytest.approx(psi, abs=1e-12)
    # 4. at the desired attitude and at rest the moments vanish
    M, gyro = Q._attitude_moments(
        tuple(Rd.reshape(-1)),
        (tuple(b1), tuple(b2), tuple(b3)),
        (0.0, 0.0, 0.0),
        tuple(prm.inertia),
        tuple(prm.k_R),
        tuple(prm.k_w),
    )
    np.testing.assert_allclose(M, 0.0, atol=1e-12)
    assert gyro == (0.0, 0.0, 0.0)
    # 6. motor lag: alpha = 1 reaches the commanded speed, alpha = 0 keeps the old one
    T = (1.0, 2.0, 3.0, 4.0)
    np.testing.assert_allclose(
        Q._motor_lag((0.0,) * 4, T, 1.0, prm.k_f), np.sqrt(np.array(T) / prm.k_f), rtol=1e-15
    )
    assert Q._motor_lag((5.0,) * 4, T, 0.0, prm.k_f) == (5.0,) * 4
    # rotor wrench = the documented mixer matrix times the rotor thrusts
    o = (300.0, 310.0, 290.0, 305.0)
    ft, tau = Q._rotor_wrench(o, prm.k_f, prm.d, prm.kappa)
    np.testing.assert_allclose(
        [ft, *tau], prm.mixer_matrix() @ (prm.k_f * np.square(o)), rtol=1e-12, atol=1e-12
    )
    # 7b. a rotation step stays on SO(3)
    R, w = Q._rotate(
        tuple(np.eye(3).reshape(-1)),
        (0.1, -0.2, 0.3),
        tau,
        (0.0, 0.0, 0.0),
        0.002,
        tuple(prm.inertia),
    )
    R = np.array(R).reshape(3, 3)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-15)
    w0 = np.array([0.1, -0.2, 0.3])
    np.testing.assert_allclose(w, w0 + 0.002 * np.asarray(tau) / prm.inertia, rtol=1e-14)
