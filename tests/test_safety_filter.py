"""The CBF safety filter: its exact solver against reference solvers, the derivation's
inequalities, forward invariance in a sampled-data double-integrator simulation, batching
and edge cases (docs/safety.md)."""

from __future__ import annotations

import clarabel
import numpy as np
import pytest
import scipy.sparse as sp
from qpsolvers import solve_qp
from scipy.optimize import minimize, nnls

from pairflock_env import PairFlockCore, make_config
from pairflock_env.safety import (
    STATUS_INFEASIBLE,
    STATUS_NOMINAL,
    STATUS_PROJECTED,
    SafetyFilter,
    SafetyParams,
    max_margin,
    project,
    safety_filter,
)
from pairflock_env.safety.cbf.kernels import (
    BARRIER,
    WS_DIRECT,
    _far,
    _far_terms,
    _sigma_min,
    _solve,
    _solve_ws,
)

# ----------------------------------------------------------------------------- references


def _clarabel(P, q, A, h, cones):
    s = clarabel.DefaultSettings()
    s.verbose = False
    s.tol_gap_abs = s.tol_gap_rel = s.tol_feas = 1e-10
    sol = clarabel.DefaultSolver(sp.csc_matrix(P), q, sp.csc_matrix(A), h, cones, s).solve()
    assert str(sol.status) in ("Solved", "AlmostSolved")
    return np.array(sol.x)


def _ball_rows(K, D):
    """Constraint rows of G u >= b (as -G u + s = -b, s >= 0) and of ||u|| <= U (SOC)."""
    return [clarabel.NonnegativeConeT(K), clarabel.SecondOrderConeT(D + 1)]


def ref_qcqp(un, G, b, U):
    """Clarabel (conic interior point), then SciPy's SQP started there: an interior point
    solution is accurate to about sqrt(gap) along the sphere, the SQP polish to ~1e-9."""
    K, D = G.shape
    A = np.vstack([-G, np.zeros((1, D)), -np.eye(D)])
    h = np.concatenate([-b, [U], np.zeros(D)])
    x = _clarabel(np.eye(D), -un, A, h, _ball_rows(K, D))
    cons = [
        {"type": "ineq", "fun": lambda z: G @ z - b, "jac": lambda z: G},
        {"type": "ineq", "fun": lambda z: np.array([U * U - z @ z]), "jac": lambda z: -2 * z[None]},
    ]
    r = minimize(
        lambda z: 0.5 * np.sum((z - un) ** 2),
        x,
        jac=lambda z: z - un,
        constraints=cons,
        method="SLSQP",
        options={"ftol": 1e-15, "maxiter": 200},
    )
    return r.x


def ref_margin(G, b, U):
    """max t s.t. G u - t >= b, ||u|| <= U, by Clarabel (an SOCP with a linear objective)."""
    K, D = G.shape
    A = np.vstack(
        [
            np.hstack([-G, np.ones((K, 1))]),
            np.zeros((1, D + 1)),
            np.hstack([-np.eye(D), np.zeros((D, 1))]),
        ]
    )
    h = np.concatenate([-b, [U], np.zeros(D)])
    q = np.zeros(D + 1)
    q[-1] = -1.0
    return _clarabel(np.zeros((D + 1, D + 1)), q, A, h, _ball_rows(K, D))[-1]


def check_kkt(u, un, G, b, U, tol=1e-8):
    """Primal feasibility and nonnegative multipliers with zero stationarity residual."""
    assert (G @ u - b).min() >= -tol and np.linalg.norm(u) <= U * (1 + 1e-12)
    act = np.abs(G @ u - b) <= tol
    cols = [G[act].T] + ([-u[:, None]] if abs(np.linalg.norm(u) - U) <= tol else [])
    lam, res = nnls(np.hstack(cols), u - un)  # u - u_nom = sum lam_k g_k - mu u
    assert res <= 1e-7, (res, lam)


def random_instance(rng, degenerate=0.2):
    D = int(rng.integers(2, 4))
    K = int(rng.integers(1, 8))
    G = rng.normal(size=(K, D))
    G /= np.linalg.norm(G, axis=1, keepdims=True)
    if rng.random() < degenerate:  # opposite or repeated normals (UAVs on both sides)
        G[-1] = -G[0] if rng.random() < 0.5 else G[0]
    return rng.normal(size=D) * 3, G, rng.normal(size=K) * 2, rng.uniform(0.5, 5.0)


# ----------------------------------------------------------------------------- the solver


def test_polytope_instances_match_qpsolvers():
    rng = np.random.default_rng(1)
    n = 0
    while n < 300:
        un, G, b, _ = random_instance(rng)
        u_feas = rng.normal(size=un.size)  # make the polytope non-empty
        b = np.minimum(b, G @ u_feas - rng.uniform(0.0, 0.1, b.size))
        U = 1e6  # ball far away: projection onto the polytope only
        u, status, _ = project(un, G, b, U)
        if status == STATUS_NOMINAL:
            assert np.array_equal(u, un)
            continue
        assert status == STATUS_PROJECTED
        for solver in ("daqp", "quadprog"):
            ref = solve_qp(np.eye(un.size), -un, -G, -b, solver=solver)
            np.testing.assert_allclose(u, ref, atol=1e-6, rtol=0)
        check_kkt(u, un, G, b, U)
        n += 1


def test_ball_instances_match_clarabel():
    rng = np.random.default_rng(2)
    n_ball = 0
    for _ in range(900):
        un, G, b, U = random_instance(rng)
        U *= 0.5  # the bound active more often
        u, status, _ = project(un, G, b, U)
        if status != STATUS_PROJECTED:
            continue
        np.testing.assert_allclose(u, ref_qcqp(un, G, b, U), atol=1e-6, rtol=0)
        check_kkt(u, un, G, b, U)
        n_ball += abs(np.linalg.norm(u) - U) < 1e-9
    assert n_ball >= 200  # the bound was active in a few hundred of them


def test_infeasible_instances_maximise_the_smallest_margin():
    rng = np.random.default_rng(3)
    n = 0
    for _ in range(600):
        un, G, b, U = random_instance(rng)
        u, status, t = project(un, G, b, U)
        if status != STATUS_INFEASIBLE:
            continue
        n += 1
        t_ref = ref_margin(G, b, U)
        assert t < 0 and t == pytest.approx(t_ref, abs=1e-6)
        assert max_margin(G, b, U)[0] == t
        # the output achieves t* within the bound, and is the nearest such command (the
        # max-margin set is often a single point, where an interior point solver is only
        # accurate to ~1e-6)
        assert (G @ u - b).min() >= t - 1e-8 and np.linalg.norm(u) <= U * (1 + 1e-12)
        K, D = G.shape
        A = np.vstack([-G, np.zeros((1, D)), -np.eye(D)])
        h = np.concatenate([-(b + t), [U], np.zeros(D)])
        ref = _clarabel(np.eye(D), -un, A, h, _ball_rows(K, D))
        assert np.linalg.norm(u - un) <= np.linalg.norm(ref - un) + 1e-5
    assert n >= 200


def test_solver_examples_and_bad_input():
    # two halfspaces u_x >= 1 and u_x <= -1: infeasible, best margin -1 on the line u_x = 0
    u, status, t = project([3.0, 2.0], [[1, 0], [-1, 0]], [1, 1], 10.0)
    assert status == STATUS_INFEASIBLE and t == -1.0
    np.testing.assert_allclose(u, [0.0, 2.0])
    # nominal outside the ball only: radial projection
    u, status, _ = project([30.0, 40.0], np.zeros((0, 2)), [], 5.0)
    assert status == STATUS_PROJECTED
    np.testing.assert_allclose(u, [3.0, 4.0])
    with pytest.raises(ValueError, match="unit vectors"):
        project([0.0, 0.0], [[2.0, 0.0]], [1.0], 1.0)
    with pytest.raises(ValueError, match="U="):
        project([0.0, 0.0], [[1.0, 0.0]], [1.0], -1.0)


def test_many_constraints_are_solved_on_a_working_set_exactly():
    # K > WS_DIRECT: the working set (16 least satisfied, then the most violated) gives the
    # optimum of the full problem, feasible or not, against the references

    rng = np.random.default_rng(9)
    seen = {STATUS_PROJECTED: 0, STATUS_INFEASIBLE: 0}
    for i in range(40):
        D = int(rng.integers(2, 4))
        K = int(rng.integers(WS_DIRECT + 1, 60))
        G = rng.normal(size=(K, D))
        G /= np.linalg.norm(G, axis=1, keepdims=True)
        un, U = rng.normal(size=D) * 5, rng.uniform(0.5, 5.0)
        u_in = rng.normal(size=D) * 0.3  # inside every constraint (odd i: pushed out by 0.5)
        b = G @ u_in - rng.uniform(0.0, 2.0, K) + 0.5 * (i % 2)
        u, status, t = project(un, G, b, U)
        assert np.linalg.norm(u) <= U * (1 + 1e-12)
        if status == STATUS_PROJECTED:
            np.testing.assert_allclose(u, ref_qcqp(un, G, b, U), atol=1e-6, rtol=0)
        elif status == STATUS_INFEASIBLE:
            assert t == pytest.approx(ref_margin(G, b, U), abs=1e-6)
            assert (G @ u - b).min() >= t - 1e-8
        seen[status] = seen.get(status, 0) + 1
    assert seen[STATUS_PROJECTED] >= 10 and seen[STATUS_INFEASIBLE] >= 3


def _ws_call(un, G, b, U, cap):

    K, D = G.shape
    Gp, up = np.zeros((K, 3)), np.zeros(3)
    Gp[:, :D], up[:D] = G, un
    out = np.zeros(3)
    work = [np.zeros((cap + 4, 3)), np.zeros(cap + 4), np.zeros(cap + 4, np.int64), np.zeros(K)]
    scratch = [np.zeros((4, 4, 4)), np.zeros(5, np.int64), np.zeros(3), np.zeros(3)]
    status, t = _solve_ws(up, Gp, b, K, U, D, *scratch, out, *work, cap)
    return out[:D], status, t


def test_the_working_set_gives_the_full_enumerations_answer():
    # the working set against the enumeration over all K (what the filter ran before it)

    rng = np.random.default_rng(10)
    statuses = set()
    for _ in range(300):
        D, K = int(rng.integers(2, 4)), int(rng.integers(17, 31))
        G = rng.normal(size=(K, D))
        G /= np.linalg.norm(G, axis=1, keepdims=True)
        un, U = rng.normal(size=D) * 5, rng.uniform(0.5, 5.0)
        b = G @ (rng.normal(size=D) * 0.3) - rng.uniform(0, 2, K) + rng.choice([0, 0.8])
        Gp, up, full = np.zeros((K, 3)), np.zeros(3), np.zeros(3)
        Gp[:, :D], up[:D] = G, un
        scratch = [np.zeros((4, 4, 4)), np.zeros(5, np.int64), np.zeros(3), np.zeros(3)]
        s1, t1 = _solve(up, Gp, b.copy(), K, U, D, *scratch, full)
        ws, s2, t2 = _ws_call(un, G, b.copy(), U, K)
        assert s1 == s2 and (t1 == t2 or abs(t1 - t2) <= 1e-9)
        np.testing.assert_allclose(ws, full[:D], atol=1e-9, rtol=0)
        statuses.add(s1)
    assert statuses == {STATUS_PROJECTED, STATUS_INFEASIBLE}


def test_a_capped_working_set_reports_the_step_infeasible_with_its_true_margin():
    # the filter stops the working set at WS_MAX: such a step is flagged (no guarantee), its
    # command stays in the ball and its margin is the one over all constraints

    rng = np.random.default_rng(11)
    capped = 0
    for _ in range(200):
        D, K = 2, 40
        G = rng.normal(size=(K, D))
        G /= np.linalg.norm(G, axis=1, keepdims=True)
        b = G @ (rng.normal(size=D) * 0.3) - rng.uniform(0, 2, K)  # feasible
        un, U = rng.normal(size=D) * 5, 3.0
        u_full, s_full, _ = _ws_call(un, G, b.copy(), U, K)
        b0 = b.copy()
        u, status, t = _ws_call(un, G, b, U, WS_DIRECT)  # no room for a second round
        assert np.array_equal(b, b0) and np.linalg.norm(u) <= U * (1 + 1e-12)
        if status != s_full or not np.array_equal(u, u_full):  # it needed more rounds
            capped += 1
            assert s_full == STATUS_PROJECTED and status == STATUS_INFEASIBLE
            assert t == pytest.approx((G @ u - b).min(), abs=1e-12) and t < 0
    assert capped >= 5


def test_the_working_set_keeps_the_whole_problems_tolerance():
    # x >= 1 and x <= 1 - 1e-5 conflict by less than the tolerance set by a far constraint
    # (b = -9e5): the full problem counts them as met, and so must every working set
    G = np.array([[1.0, 0.0], [-1.0, 0.0]] + [[0.0, 1.0]] * 15 + [[0.0, -1.0]])
    b = np.array([1.0, -(1.0 - 1e-5)] + [-2.0] * 15 + [-9e5])
    u, status, t = project([0.0, 0.0], G, b, 10.0)
    assert status == STATUS_PROJECTED and t == 0.0
    np.testing.assert_allclose(u, [1.0, 0.0], atol=1e-9)


def test_the_max_margin_point_stays_in_the_ball():
    # nearly parallel normals with full-rank differences: the candidate of three constraints
    # in 2-D is a single point, and rounding once scaled a zero direction out of the ball
    G = np.array(
        [
            [0.6997030869383228, 0.7144337548919295],
            [0.997565210064089, 0.06973988578847748],
            [0.9975712160119825, 0.069653922964714],
            [0.9975664944458416, 0.06972151145116208],
        ]
    )
    G /= np.linalg.norm(G, axis=1, keepdims=True)
    b = np.array([1029.1763092892359, 990.759292390874, 990.743633275431, 990.7525252972929])
    U = 1000.0
    t, u = max_margin(G, b, U)
    assert np.linalg.norm(u) <= U * (1 + 1e-12)
    assert t <= U - b.max() and (G @ u - b).min() == pytest.approx(t, abs=1e-9)
    assert t == pytest.approx(ref_margin(G, b, U), abs=1e-5)
    u, status, t2 = project([-1000.0, -1000.0], G, b, U)  # b[0] > U: no command meets it
    assert status == STATUS_INFEASIBLE and t2 == t and np.linalg.norm(u) <= U * (1 + 1e-12)


def test_a_dense_crowd_steps_with_every_command_in_the_ball():
    # 200 UAVs in a 6 m box, a 1 m/s^2 budget, 3-D: every UAV binds. The enumeration's
    # K^4 once took seconds to minutes per step; the working set caps it, and the agents
    # whose set would grow past WS_MAX report the step infeasible

    cfg = make_config(
        "paper", n_uavs=200, dim=3, safety_filter="cbf", pair_accel_limit=1.0, init="random",
        min_init_spacing=0.0, swarm_half_width=3.0, pair_corner=3.0,
    )  # fmt: skip
    core = PairFlockCore(cfg, seed=0)
    core.reset(seed=0)
    for _ in range(3):
        res = core.step(np.zeros((1, core.n_agents, 3)))
        assert res.info["safety_infeasible"].all()
        assert np.isfinite(res.info["pair_accel"]).all() and (res.info["pair_accel"] <= 1.0).all()


@pytest.mark.parametrize("kw", [dict(substeps=2), dict(integrator="exact")])
def test_coincident_uavs_step_with_substeps_and_the_exact_integrator(kw):
    # the rotation bound of n divides by d + min(d, D_s): 0 for coincident UAVs

    core = PairFlockCore(make_config("paper", n_uavs=2, safety_filter="cbf", **kw), seed=0)
    core.reset(seed=0, options={"positions": np.zeros((2, 2))})
    res = core.step(np.zeros((1, 2, 2)))
    assert np.isfinite(core.q).all() and np.isfinite(res.info["pair_accel"]).all()


def test_a_subnormal_brake_acceleration_at_the_barrier_stays_finite():

    cfg = make_config(
        "paper", n_uavs=2, safety_filter="cbf", safety_brake_accel=5e-324, safety_other_accel=0.0
    )
    core = PairFlockCore(cfg, seed=0)
    core.reset(seed=0, options={"positions": np.array([[0.0, 0.0], [1.01, 0.0]])})
    assert np.isfinite(core.step(np.zeros((1, 2, 2))).info["pair_accel"]).all()


# ----------------------------------------------------------------------------- the barrier


def _next_ok(s, e, v, eps, a, T, c, lam, H, slack, tau=0.0):
    """The discrete barrier condition for the projected next state under sigma = s."""
    beta = (c - 0.5) * a * T
    e1, v1 = e + T * v + c * T * T * s, v + T * s - eps
    g0, g1 = e + tau * v, e1 + tau * v1  # E and E+
    H1 = np.sign(g1) * np.sqrt(2 * a * abs(g1)) + v1 + beta
    gaps = e1 >= min(e, 0) - slack and g1 >= min(g0, 0) - slack
    return gaps and (1 - lam) * H - slack <= H1


def test_sigma_min_is_the_exact_threshold():
    """sigma_min is the smallest sigma whose projected next state keeps H+ >= (1-lam) H,
    E+ >= min(E, 0) and e+ >= min(e, 0) (E = e + tau v; tau = 0: E = e); full braking
    satisfies it whenever H >= 0 (recursive feasibility)."""
    rng = np.random.default_rng(4)
    for _ in range(3000):
        e = rng.choice([0.0, rng.exponential(5.0), -rng.exponential(0.5)])
        v, eps = rng.normal(0, 30), rng.choice([0.0, rng.exponential(1.0)])
        a, T, c, lam = rng.uniform(1, 500), 0.01, rng.choice([1.0, 0.75, 0.5]), rng.uniform(0.1, 1)
        tau = rng.choice([0.0, rng.uniform(0.0, 0.3)])
        H, smin = _sigma_min(e, v, eps, a, T, c, lam, tau)
        E = e + tau * v
        H_ref = np.sign(E) * np.sqrt(2 * a * abs(E)) + v + (c - 0.5) * a * T
        assert np.isfinite(smin) and abs(H - H_ref) <= 1e-12 * (1 + abs(H_ref))
        tol = 1e-9 * (1 + abs(smin) * T * T + abs(v) + a * T)
        assert _next_ok(smin, e, v, eps, a, T, c, lam, H, tol, tau)
        assert not _next_ok(smin - 1e-6 * (1 + abs(smin)), e, v, eps, a, T, c, lam, H, -tol, tau)
        if H >= 0 and E >= 0 and e >= 0 and eps == 0:
            assert smin <= a * (1 + 1e-12)


@pytest.mark.parametrize("S", [1, 3])
def test_projection_bounds_of_the_next_state(S):
    """d+ >= d + T v + c T^2 sigma always; v+ >= v + T sigma for one semi-implicit step."""
    rng = np.random.default_rng(5)
    T, h = 0.01, 0.01 / S
    for _ in range(2000):
        D = int(rng.integers(2, 4))
        x, w, da = rng.normal(0, 3, D), rng.normal(0, 50, D), rng.normal(0, 500, D)
        d = np.linalg.norm(x)
        n = x / d
        x1, w1 = x.copy(), w.copy()
        for _ in range(S):
            w1 += da * h
            x1 += w1 * h
        c = (S + 1) / (2 * S)
        sig = n @ da
        assert np.linalg.norm(x1) >= d + T * (n @ w) + c * T * T * sig - 1e-12
        if S == 1:
            assert (x1 @ w1) / np.linalg.norm(x1) >= n @ w + T * sig - 1e-9


# ----------------------------------------------------------------------------- invariance


def simulate(
    seed,
    *,
    D=2,
    n_agents=1,
    n_obs=3,
    S=1,
    exact=False,
    factor=1.0,
    steps=300,
    rand=False,
    tau=0.0,
):
    """Agents push at the bound straight at the nearest UAV; obstacles (unpaired) accelerate
    at factor * other_accel towards the nearest agent (or, ``rand``, in a random direction
    with a random magnitude up to that); zero-order hold, the env's integrator.
    Returns per-swarm: min distance of an agent to any UAV over the run, whether the start
    was safe (every H >= 0), and the step of the first report (infeasible or H < 0)."""
    rng = np.random.default_rng(seed)
    B, U, T = 48, 100.0, 0.01
    integ = "exact" if exact else "semi_implicit"
    P = SafetyParams(accel_limit=U, sensing_radius=1e3, substeps=S, integrator=integ)
    P = P.replace(decay=float(rng.uniform(0.1, 1.0)), reaction_time=tau)
    N = n_agents + n_obs
    ag = np.arange(n_agents)
    filt = SafetyFilter(P, ag, N)
    q, p = rng.uniform(-20, 20, (B, N, D)), rng.normal(0, 5, (B, N, D))
    out = filt.allocate(B, D)
    dmin = np.full(B, np.inf)
    report = np.full(B, steps + 1)
    first_bad = np.full(B, steps + 1)
    for k in range(steps + 1):
        x = q[:, None] - q[:, ag, None]  # (B, M, N, D) agent -> every UAV
        dist = np.linalg.norm(x, axis=-1)
        dist[:, ag, ag] = np.inf
        dmin = np.minimum(dmin, dist.min(axis=(1, 2)))
        first_bad = np.where((dist.min(axis=(1, 2)) < 1.0) & (first_bad > k), k, first_bad)
        tgt = np.take_along_axis(x, dist.argmin(-1)[..., None, None], axis=2)[:, :, 0]
        un = U * tgt / np.linalg.norm(tgt, axis=-1, keepdims=True)
        f = rng.normal(size=(B, n_agents, D))  # own flocking part, |f| <= U - alpha
        f *= (U - P.brake_accel) * rng.uniform(0, 1, (B, n_agents, 1))
        f /= np.linalg.norm(f, axis=-1, keepdims=True)
        filt.apply(q, p, f, un, out)
        if k == 0:
            safe0 = (out.barrier.min(axis=1) >= 0) & (dmin >= 1.0)
        flagged = out.infeasible.any(1) | (out.barrier.min(1) < 0)
        report = np.where(flagged & (report > k), k, report)
        a = np.zeros((B, N, D))
        a[:, ag] = f + out.u
        xo = q[:, None, ag] - q[:, n_agents:, None]  # obstacle -> agents
        towards = np.take_along_axis(
            xo, np.linalg.norm(xo, axis=-1).argmin(-1)[..., None, None], axis=2
        )[:, :, 0]
        if rand:
            towards = rng.normal(size=towards.shape)
        size = rng.uniform(0, 1, (B, n_obs, 1)) if rand else 1.0
        unit = towards / np.linalg.norm(towards, axis=-1, keepdims=True)
        a[:, n_agents:] = factor * P.other_accel * size * unit
        if exact:
            q += p * T + 0.5 * T * T * a
            p += a * T
        else:
            for _ in range(S):
                p += a * (T / S)
                q += p * (T / S)
    return dmin, safe0, report, first_bad


@pytest.mark.parametrize(
    "kw",
    [
        dict(n_obs=1),
        dict(n_agents=2, n_obs=0),
        dict(D=3, n_obs=1),
        dict(n_obs=3),
        dict(n_obs=3, rand=True),
        dict(D=3, n_agents=2, n_obs=3),
        dict(D=3, n_agents=2, n_obs=2, rand=True),
        dict(n_obs=2, S=4),
        dict(n_obs=2, exact=True),
        dict(n_obs=1, tau=0.2),
        dict(D=3, n_agents=2, n_obs=3, tau=0.1),
    ],
    ids=lambda kw: ",".join(f"{k}={v}" for k, v in kw.items()),
)
def test_forward_invariance_under_the_assumptions(kw):
    """Every swarm that starts safe keeps >= D_s for as long as the filter stays feasible;
    with one obstacle or only the pair (c = 1) it is always feasible."""
    dmin, safe0, report, _ = simulate(7, **kw)
    kept = safe0 & (report > 300)
    assert kept.sum() >= 24  # not vacuous
    assert dmin[kept].min() >= 1.0 - 1e-9
    if kw.get("n_obs", 0) + kw.get("n_agents", 1) == 2 and not {"S", "exact", "tau"} & set(kw):
        assert not (safe0 & (report <= 300)).any()
        assert dmin[safe0].min() >= 1.0 - 1e-9


def test_violated_assumption_is_reported():
    """Obstacles accelerating at 3x other_accel break the guarantee: every swarm that gets
    closer than D_s was flagged (infeasible or a negative barrier) no later than that."""
    dmin, safe0, report, first_bad = simulate(8, n_obs=2, factor=3.0)
    hit = safe0 & (dmin < 1.0)
    assert hit.sum() >= 5
    assert (report[hit] <= first_bad[hit]).all()


# ----------------------------------------------------------------------------- batching, edges


def _random_params(rng):
    """SafetyParams over the valid ranges: substeps, the exact integrator, a reaction time."""
    U = float(rng.uniform(5, 1000))
    alpha = U * float(rng.uniform(0.05, 1))
    return SafetyParams(
        accel_limit=U,
        brake_accel=alpha,
        other_accel=alpha * float(rng.uniform(0, 0.99)),
        dt=float(rng.choice([0.001, 0.01, 0.05])),
        substeps=int(rng.choice([1, 2, 5])),
        integrator=str(rng.choice(["semi_implicit", "exact"])),
        reaction_time=float(rng.choice([0.0, rng.uniform(0, 0.5)])),
        decay=float(rng.uniform(0.02, 1)),
        margin=float(rng.choice([0.0, 0.01])),
        sensing_radius=1e6,
    )


def test_a_skipped_far_uav_has_a_constraint_the_bound_implies():
    """_far's claim (docs/safety.md, "Skipping far UAVs"): a UAV it skips would get a
    right-hand side <= -U (sigma_min + A_o - n . f_i for an unpaired UAV, sigma_min / 2 -
    n . f_i for a filtered one) for every range rate |v| <= ||w||,
    every rotation term eps within its bound and every direction of f_i, and its
    H >= T S / lambda > 0."""
    rng = np.random.default_rng(21)
    skipped = 0
    for _ in range(4000):
        P = _random_params(rng)
        pr = SafetyFilter(P, [0], 2)._pr
        fn = float(rng.choice([0.0, rng.uniform(0, 3 * P.accel_limit)]))
        coop = bool(rng.integers(2))  # against an unpaired or a filtered UAV
        far = _far_terms(pr, fn, coop)
        W = float(rng.choice([0.0, rng.exponential(20.0)]))
        Db = P.barrier_distance
        e = float(rng.exponential(rng.choice([0.1, 5.0, 100.0])))
        if rng.random() < 0.3 and _far((Db + 1e7) ** 2, W * W, far):  # the threshold itself
            lo, e = 0.0, 1e7
            for _ in range(60):
                mid = 0.5 * (lo + e)
                lo, e = (lo, mid) if _far((Db + mid) ** 2, W * W, far) else (mid, e)
        d = Db + e
        if not _far(d * d, W * W, far):
            continue
        skipped += 1
        a, c, T, U = P.barrier_accel(coop), P.position_gain, P.dt, P.accel_limit
        A_o = P.other_accel
        S = 2 * (fn + U) if coop else fn + U + A_o  # dropped: sigma_min <= -S
        for v in (-W, rng.uniform(-W, W), W):
            for eps in (0.0, 2 * (1 - c) * T * S):
                H, smin = _sigma_min(e, v, eps, a, T, c, P.decay, P.reaction_time)
                assert smin <= -S, (P, coop, fn, W, e, v, eps, smin)
                H_low = T * S / P.decay * (1 - 1e-9)
                assert H_low <= H, (P, fn, W, e, v, H)
    assert skipped > 500


def test_skipping_far_uavs_changes_no_command():
    """The filter with the skip and without it (the kernel's switch, pr[9]) gives the same
    commands and flags bit for bit; only ``barrier`` omits skipped UAVs, whose H is > 0."""
    rng = np.random.default_rng(22)
    changed = 0
    for _ in range(150):
        P = _random_params(rng).replace(sensing_radius=float(rng.uniform(3, 200)))
        B, N, D = 3, int(rng.integers(2, 30)), int(rng.integers(2, 4))
        M = min(N, int(rng.integers(1, 4)))
        ag = rng.choice(N, M, replace=False)
        mates = np.full(M, -1)
        if M >= 2:
            mates[:2] = ag[1], ag[0]
        q = rng.normal(0, rng.uniform(1, 60), (B, N, D))
        p = rng.normal(0, rng.uniform(0.1, 40), (B, N, D))
        f = rng.normal(0, 1, (B, M, D)) * rng.uniform(0, P.accel_limit)
        un = rng.normal(0, P.accel_limit, (B, M, D))
        on = SafetyFilter(P, ag, N, mates)
        off = SafetyFilter(P, ag, N, mates)
        off._pr[BARRIER.index.skip_far] = 0.0
        a, b = on.apply(q, p, f, un), off.apply(q, p, f, un)
        for x, y in zip(a.arrays()[:4], b.arrays()[:4], strict=True):
            assert np.array_equal(x, y)
        diff = a.barrier != b.barrier
        assert (a.barrier[diff] > b.barrier[diff]).all() and (b.barrier[diff] > 0).all()
        changed += diff.sum()
    assert changed > 50


def _hard_params(rng):
    """Parameters where sigma_min is computed from large cancelling terms: tiny steps, A_o
    within a hair of alpha, slow barrier rates (the rounding _far must cover)."""
    U = float(10 ** rng.uniform(0, 3))
    alpha = U * float(rng.uniform(0.05, 1))
    return SafetyParams(
        accel_limit=U,
        brake_accel=alpha,
        other_accel=alpha * (1 - float(10 ** rng.uniform(-7, -1))),
        dt=float(10 ** rng.uniform(-6, -2)),
        substeps=int(rng.choice([1, 2])),
        integrator=str(rng.choice(["semi_implicit", "exact"])),
        reaction_time=float(rng.choice([0.0, 10 ** rng.uniform(-3, -0.5)])),
        decay=float(10 ** rng.uniform(-3, 0)),
        margin=0.01,
        sensing_radius=float(rng.choice([100.0, 1e4])),
    )


def test_the_skip_changes_no_command_at_its_threshold_where_rounding_is_hardest():
    """One UAV on the line of sight at the skip's own threshold (bisected), closing, with
    the flocking command pushing towards it: the filter with and without the skip gives the
    same outputs, including a case the unpadded test got wrong (active only without it)."""
    rng = np.random.default_rng(31)
    cases = [
        (
            SafetyParams(accel_limit=6.760772096535446, brake_accel=5.4086176772283565,
                         other_accel=5.408548440505239, dt=2.3529257960149835e-06,
                         decay=0.0012333969252901512, margin=0.01, sensing_radius=100.0),
            4.9020404298977835, 0.0, 0.0, False,
        )
    ]  # fmt: skip
    for _ in range(1500):
        coop = bool(rng.integers(2))
        cases.append(
            (_hard_params(rng), None, float(rng.choice([0.0, 10 ** rng.uniform(-3, 2)])),
             float(rng.choice([0.0, rng.uniform(0, 2)])), coop)
        )  # fmt: skip
    tested = 0
    for P, d, W, fscale, coop in cases:
        ag, mates = ([0, 1], [1, 0]) if coop else ([0], None)
        on = SafetyFilter(P, ag, 2, mates)
        off = SafetyFilter(P, ag, 2, mates)
        off._pr[BARRIER.index.skip_far] = 0.0
        if d is None:  # bisect the skip's threshold for this closing speed
            fn = fscale * P.accel_limit
            far = _far_terms(on._pr, fn, coop)
            lo, hi = P.barrier_distance, P.sensing_radius
            if not _far(hi * hi * (1 - 1e-12), W * W, far):
                continue
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if _far(mid * mid, W * W, far) else (mid, hi)
            d = hi
        fn = fscale * P.accel_limit
        q = np.zeros((1, 2, 2))
        q[0, 1, 0] = d
        p = np.zeros((1, 2, 2))
        p[0, 0, 0] = W  # agent 0 closes on UAV 1 at W
        f = np.zeros((1, len(ag), 2))
        f[0, 0, 0] = fn  # and its flocking command pushes it on
        un = np.zeros((1, len(ag), 2))
        un[0, 0, 0] = P.accel_limit
        a, b = on.apply(q, p, f, un), off.apply(q, p, f, un)
        for x, y in zip(a.arrays()[:4], b.arrays()[:4], strict=True):
            assert np.array_equal(x, y), (P, d, W, fn, coop)
        tested += 1
    assert tested > 500


def test_a_fast_member_of_another_pair_is_not_left_out_by_the_shortened_search():
    """The skip's search radius comes from the unpaired UAVs' speeds and, when there are
    other pairs, from the filtered UAVs' too: a slow flock must not hide another pair's
    member closing fast from 25 m (its constraint binds; with the skip off it is the same)."""
    rng = np.random.default_rng(8)
    N = 24
    q = np.zeros((1, N, 2))
    p = np.zeros((1, N, 2))
    q[0, 1] = (0.0, 2.5)  # agent 0's partner
    q[0, 2], q[0, 3] = (25.0, 0.0), (25.0, 2.5)  # the other pair, closing at 60 m/s
    p[0, 2, 0] = p[0, 3, 0] = -60.0
    q[0, 4:] = rng.uniform(40.0, 90.0, (N - 4, 2))  # a slow flock, well away
    p[0, 4:] = rng.normal(0.0, 0.2, (N - 4, 2))
    agents, partners = [0, 1, 2, 3], [1, 0, 3, 2]
    P = SafetyParams(accel_limit=50.0, sensing_radius=100.0)
    on = SafetyFilter(P, agents, N, partners)
    off = SafetyFilter(P, agents, N, partners)
    off._pr[BARRIER.index.skip_far] = 0.0
    f = np.zeros((1, 4, 2))
    un = np.zeros((1, 4, 2))
    un[0, 0] = (50.0, 0.0)  # agent 0 pushes towards the other pair
    a, b = on.apply(q, p, f, un), off.apply(q, p, f, un)
    assert b.active[0, 0]  # the other pair's member binds
    for x, y in zip(a.arrays()[:4], b.arrays()[:4], strict=True):
        assert np.array_equal(x, y)


def test_barrier_leaves_out_a_partner_the_skip_drops_beyond_the_shortened_search():
    """A resting swarm: the search stops a few metres out, the partner 20 m away is still
    taken (at any distance) but, inside the sensing radius, the skip drops it, so it does
    not count in ``barrier`` either (docs/safety.md, "Skipping far UAVs")."""
    P = SafetyParams(accel_limit=50.0, sensing_radius=100.0)
    q = np.array([[[0.0, 0.0], [20.0, 0.0], [0.0, 50.0]]])
    p = np.zeros((1, 3, 2))
    zero = np.zeros((1, 2, 2))
    out = SafetyFilter(P, [0, 1], 3, [1, 0]).apply(q, p, zero, zero)
    assert np.isinf(out.barrier).all() and not out.active.any()


def _random_state(rng, B, N, D):
    return rng.uniform(-4, 4, (B, N, D)), rng.normal(0, 10, (B, N, D))


def test_batched_equals_one_by_one():
    rng = np.random.default_rng(9)
    B, N, D = 6, 9, 3
    P = SafetyParams(accel_limit=60.0, sensing_radius=6.0)
    ag = np.array([0, 1, 4, 7])
    q, p = _random_state(rng, B, N, D)
    f, un = rng.normal(0, 10, (B, 4, D)), rng.normal(0, 40, (B, 4, D))
    full = safety_filter(P, q, p, ag, f, un)
    assert full.active.any() and (~full.active).any()
    for b in range(B):
        one = safety_filter(P, q[b : b + 1], p[b : b + 1], ag, f[b : b + 1], un[b : b + 1])
        for x, y in zip(full.arrays(), one.arrays(), strict=True):
            assert np.array_equal(x[b : b + 1], y)


def test_edge_states_stay_finite():
    P = SafetyParams(accel_limit=50.0)
    filt = SafetyFilter(P, [0, 1], 4)
    q = np.zeros((4, 4, 2))
    p = np.zeros((4, 4, 2))
    q[0, 2] = q[0, 0]  # coincident with an unpaired UAV, at rest
    q[1, 1] = [P.barrier_distance, 0.0]  # partner at exactly D_s + margin, at rest
    q[1, 2:] = [[30.0, 0.0], [0.0, 30.0]]
    q[2] = [[0, 0], [0, 0], [0, 0], [0, 0]]  # everyone coincident
    q[3] = [[0, 0], [1, 0], [0, 1], [1, 1]] * np.array(1.5 * P.sensing_radius)  # none sensed
    un = np.full((4, 2, 2), 10.0)
    out = filt.apply(q, p, np.zeros((4, 2, 2)), un)
    for arr in (out.u, out.correction):
        assert np.isfinite(arr).all()
    assert (np.linalg.norm(out.u, axis=-1) <= P.accel_limit * (1 + 1e-12)).all()
    assert np.isinf(out.barrier[3]).all() and not out.active[3].any()
    assert np.array_equal(out.u[3], un[3])
    # on the barrier at rest, pushing towards the partner is blocked, pushing away is not
    un2 = np.zeros((1, 2, 2))
    un2[0, 0] = [10.0, 0.0]
    o2 = filt.apply(q[1:2], p[1:2], np.zeros((1, 2, 2)), un2)
    assert o2.u[0, 0, 0] <= 1e-9 and o2.active[0, 0] and not o2.infeasible[0, 0]
    assert np.array_equal(o2.u[0, 1], un2[0, 1])
    # a diverged (non-finite) state passes the command through, flagged
    qn = q.copy()
    qn[0, 3] = np.nan
    fn = np.zeros((4, 2, 2))
    fn[1, 0] = np.inf
    o3 = filt.apply(qn, p, fn, un)
    assert o3.infeasible[0].all() and np.array_equal(o3.u[0], un[0])
    assert o3.infeasible[1, 0] and not o3.infeasible[1, 1] and np.isnan(o3.barrier[1, 0])


def test_params_validation_and_config():
    cfg = make_config("paper", pair_accel_limit=50.0)
    P = SafetyParams.from_config(cfg, sensing_radius=12.0)
    assert (P.accel_limit, P.brake_accel, P.other_accel, P.dt) == (50.0, 40.0, 20.0, cfg.dt)
    assert (P.safety_distance, P.margin, P.barrier_distance) == (1.0, 0.01, 1.01)
    Q = SafetyParams.from_config(make_config("paper", safety_margin=0.25, safety_distance=2.0))
    assert (Q.margin, Q.barrier_distance, Q.brake_accel) == (0.25, 2.25, 0.8 * Q.accel_limit)
    assert P.position_gain == 1.0
    assert SafetyParams(accel_limit=1.0, integrator="exact").position_gain == 0.5
    assert SafetyParams(accel_limit=1.0, substeps=3).position_gain == pytest.approx(2 / 3)
    r = P.required_sensing_radius(20.0)
    assert r == pytest.approx(1.01 + 0.2 + (20.0 - 0.5 * 20.0 * 0.01) ** 2 / 40.0)
    with pytest.raises(TypeError, match="unknown safety parameter"):
        SafetyParams.from_config(cfg, gamma=1.0)
    bad = [
        (dict(accel_limit="1"), TypeError),
        (dict(accel_limit=0.0), ValueError),
        (dict(accel_limit=1.0, brake_accel=2.0), ValueError),
        (dict(accel_limit=1.0, brake_accel=0.5, other_accel=0.5), ValueError),
        (dict(accel_limit=1.0, sensing_radius=0.5), ValueError),
        (dict(accel_limit=1.0, margin=-0.01), ValueError),
        (dict(accel_limit=1.0, margin="0.1"), TypeError),
        (dict(accel_limit=1.0, margin=float("inf")), ValueError),
        (dict(accel_limit=1.0, decay=0.0), ValueError),
        (dict(accel_limit=1.0, substeps=1.5), TypeError),
        (dict(accel_limit=1.0, integrator="rk4"), ValueError),
        (dict(accel_limit=float("nan")), ValueError),
    ]
    for kw, exc in bad:
        with pytest.raises(exc, match=next(k for k in kw if k != "accel_limit" or len(kw) == 1)):
            SafetyParams(**kw)
    with pytest.raises(ValueError, match=r"sensing_radius=1.2 .*safety_distance \+ margin = 1.5"):
        SafetyParams(accel_limit=1.0, margin=0.5, sensing_radius=1.2)
    filt = SafetyFilter(P, [0, 1], 3)
    z = np.zeros((1, 3, 2))
    with pytest.raises(ValueError, match="u_nom"):
        filt.apply(z, z, np.zeros((1, 2, 2)), np.zeros((1, 3, 2)))
    with pytest.raises(ValueError, match="agents"):
        SafetyFilter(P, [0, 3], 3)


def test_active_means_a_barrier_constraint_and_correction_its_size():
    P = SafetyParams(accel_limit=50.0)
    filt = SafetyFilter(P, [0], 2)
    q = np.array([[[0.0, 0.0], [10.0, 0.0]]] * 3)
    p = np.zeros((3, 2, 2))
    p[2, 0] = [40.0, 0.0]  # closing at 40 m/s from 9 m: must brake
    un = np.array([[[0.0, 30.0]], [[0.0, 80.0]], [[0.0, 30.0]]])
    out = filt.apply(q, p, np.zeros((3, 1, 2)), un)
    assert np.array_equal(out.u[0], un[0]) and out.correction[0, 0] == 0.0
    assert not out.active[0, 0]
    # outside the bound only: projected onto the ball, not a safety intervention
    np.testing.assert_allclose(out.u[1, 0], [0.0, 50.0])
    assert not out.active[1, 0] and out.correction[1, 0] == pytest.approx(30.0)
    assert out.active[2, 0] and out.u[2, 0, 0] < 0 and out.barrier[2, 0] < out.barrier[0, 0]
    assert out.correction[2, 0] == pytest.approx(np.linalg.norm(out.u[2, 0] - un[2, 0]))


def test_partner_is_constrained_beyond_the_sensing_radius():
    # Partners 30 m apart (beyond R_s = 20 m) closing at 300 m/s: their braking distance at
    # 2 alpha = 1000 m/s^2 is 45 m, so by the time they are within 20 m no command within
    # the bound can stop them. Given as partners, both start braking now.
    P = SafetyParams(accel_limit=1000.0, brake_accel=500.0, sensing_radius=20.0)
    q = np.array([[[0.0, 0.0], [30.0, 0.0]]])
    p = np.array([[[150.0, 0.0], [-150.0, 0.0]]])
    f, un = np.zeros((1, 2, 2)), np.zeros((1, 2, 2))
    blind = SafetyFilter(P, [0, 1], 2).apply(q, p, f, un)
    assert not blind.active.any() and np.isinf(blind.barrier).all()
    seen = SafetyFilter(P, [0, 1], 2, partners=[1, 0]).apply(q, p, f, un)
    assert seen.active.all() and (seen.barrier < 0).all()
    assert seen.u[0, 0, 0] < 0 < seen.u[0, 1, 0]  # each brakes away from the other
    # the same closing run to the end: only the partner-aware filter keeps D_s
    closest = {}
    for name, mates in (("blind", None), ("seen", [1, 0])):
        filt = SafetyFilter(P, [0, 1], 2, partners=mates)
        x, v = q.copy(), p.copy()
        dmin = np.inf
        for _ in range(40):
            out = filt.apply(x, v, f, un)
            v = v + P.dt * out.u
            x = x + P.dt * v
            dmin = min(dmin, float(np.linalg.norm(x[0, 0] - x[0, 1])))
        closest[name] = dmin
    assert closest["seen"] >= P.safety_distance > closest["blind"]
    # bad partners: wrong shape or dtype, an index out of range, the agent itself
    for mates, exc in (([1], TypeError), ([1.0, 0.0], TypeError), ([2, 0], ValueError)):
        with pytest.raises(exc, match="partners"):
            SafetyFilter(P, [0, 1], 2, partners=mates)
    with pytest.raises(ValueError, match="partners"):
        SafetyFilter(P, [0, 1], 2, partners=[0, 0])


def test_core_filter_senses_each_agents_partner():

    core = PairFlockCore(make_config("paper", n_uavs=20, safety_filter="cbf"), num_swarms=1)
    assert np.array_equal(core.safety.filter.partners, core.partner_uavs)


def test_a_fast_closer_needs_the_radius_its_braking_distance_asks_for():
    # An unpaired UAV 120 m ahead closing at 60 m/s: at alpha - A_o = 20 m/s^2 its braking
    # distance is about 90 m (required_sensing_radius). With a 20 m radius it is first sensed
    # when no command within the bound can stop the agent; with 100 m it is sensed in time,
    # and the filter then brakes without chattering: it acts once, from the braking curve to
    # the stop (a sensing rule that took a UAV in only on the braking curve let it drop out
    # again after each braking step, and switched the command on and off every other step).
    near, far = SafetyParams(accel_limit=50.0, sensing_radius=20.0), SafetyParams(accel_limit=50.0)
    assert far.sensing_radius == 100.0 >= far.required_sensing_radius(60.0) > 90.0 > 20.0
    q = np.array([[[0.0, 0.0], [-50.0, 0.0], [120.0, 0.0]]])  # UAV 1: behind, left behind
    f = np.zeros((1, 1, 2))
    push = np.full((1, 1, 2), [1.0, 0.0])  # the controller keeps nudging towards UAV 2
    closest, switches, infeasible = {}, {}, {}
    for name, params in (("near", near), ("far", far)):
        filt = SafetyFilter(params, [0], 3)
        x, v = q.copy(), np.array([[[60.0, 0.0], [0.0, 0.0], [0.0, 0.0]]])
        dmin, active = np.inf, []
        infeasible[name] = 0
        for _ in range(400):
            out = filt.apply(x, v, f, push)
            v[0, 0] += params.dt * out.u[0, 0]
            x = x + params.dt * v
            dmin = min(dmin, float(np.linalg.norm(x[0, 0] - x[0, 2])))
            active.append(bool(out.active[0, 0]))
            infeasible[name] += int(out.infeasible[0, 0])
        closest[name] = dmin
        switches[name] = int(np.sum(np.diff(np.array(active, int)) != 0))
    assert closest["far"] >= far.barrier_distance - 1e-9 > far.safety_distance > closest["near"]
    assert infeasible["far"] == 0 < infeasible["near"]
    assert switches["far"] == 1  # on once, then on to the end (the nudge stays cancelled)


def _plain_sigma_min(e, v, eps, a, T, c, lam):
    """The barrier's closed form without a reaction time, in the order of operations it had
    before tau existed (a reference for bit-identity)."""
    beta = (c - 0.5) * a * T
    H = np.sign(e) * np.sqrt(2.0 * a * abs(e)) + v + beta
    K = v - eps + beta - (1.0 - lam) * H
    cT2 = c * T * T
    s0 = -(e + T * v) / cT2
    R0 = -(T * s0 + K)
    Ac = a * c * T
    R = abs(R0)
    z = R * R / (T * (R + Ac + np.sqrt(Ac * (2.0 * R + Ac))))
    s_b = s0 + z if R0 >= 0.0 else s0 - z
    return H, max(s0 + min(e, 0.0) / cT2, s_b)


def test_reaction_time_brakes_ahead_of_an_actuation_lag():
    # An agent pushes at the bound towards an unpaired UAV hovering 12 m ahead, but its
    # commands act 10 control periods (0.1 s) late, as through a vehicle's attitude loop.
    # The plain barrier brakes too late; with a reaction time of twice the lag it keeps
    # D_s + margin (as every filter does when nothing lags). Measured alongside (not
    # asserted): a slower rate alone (decay 0.02) also keeps it, at lags up to 0.2 s.
    P = SafetyParams(accel_limit=50.0, decay=0.1)

    def closest(params, delay):
        filt = SafetyFilter(params, [0], 2)
        x = np.array([[[0.0, 0.0], [12.0, 0.0]]])
        v = np.zeros_like(x)
        f, pipe, dmin = np.zeros((1, 1, 2)), [np.zeros(2)] * delay, np.inf
        for _ in range(500):
            out = filt.apply(x, v, f, np.full((1, 1, 2), [50.0, 0.0]))
            pipe.append(out.u[0, 0].copy())
            v[0, 0] += P.dt * pipe.pop(0)
            x = x + P.dt * v
            dmin = min(dmin, float(x[0, 1, 0] - x[0, 0, 0]))
        return dmin

    lag = 10
    tau = P.replace(reaction_time=2 * lag * P.dt)
    assert closest(P, lag) < P.safety_distance
    assert closest(tau, lag) >= P.barrier_distance - 1e-9
    assert min(closest(P, 0), closest(tau, 0)) >= P.barrier_distance - 1e-9
    # tau = 0 is the plain barrier bit for bit (the closed form as it was before tau);
    # for a closing UAV a reaction time shrinks the safe set
    rng = np.random.default_rng(3)
    for _ in range(300):
        e, v = rng.choice([rng.uniform(0, 5), -rng.exponential(0.3)]), rng.uniform(-40, 40)
        eps, a, c, lam = rng.choice([0.0, 0.3]), rng.uniform(1, 500), rng.choice([1.0, 0.75]), 0.5
        H0, s0 = _sigma_min(e, v, eps, a, 0.01, c, lam, 0.0)
        assert (H0, s0) == _plain_sigma_min(e, v, eps, a, 0.01, c, lam)
        if v < 0:
            assert _sigma_min(e, v, eps, a, 0.01, c, lam, 0.1)[0] <= H0
    # the sensing radius a closing speed needs grows by V tau
    T = P.replace(reaction_time=0.1)
    assert T.required_sensing_radius(30.0) == pytest.approx(P.required_sensing_radius(30.0) + 3.0)
    for kw, exc in ((dict(reaction_time=-0.1), ValueError), (dict(reaction_time="1"), TypeError)):
        with pytest.raises(exc, match="reaction_time"):
            SafetyParams(accel_limit=50.0, **kw)
