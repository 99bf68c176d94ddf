"""Cost of the CBF safety filter next to one core step, measured in the same run.

    python benchmarks/bench_safety.py             # N = 100, B = 256, M = 2 (the paper task)
    python benchmarks/bench_safety.py --quick     # fewer repeats
    python benchmarks/bench_safety.py --n 50 --b 64
    python benchmarks/bench_safety.py --assumptions   # what the filter's parameters face
    python benchmarks/bench_safety.py --in-step       # the filter's share of a filtered step
    python benchmarks/bench_safety.py --vecenv        # SB3 VecEnv throughput, filter off/on

Times ``SafetyFilter.apply`` (preallocated outputs) on three states of the paper task with
``pair_accel_limit=50`` and compares each with the median time of ``PairFlockCore.step`` at
the same size:

* ``start``: the reset state (the pair in the corners, nothing within the sensing radius of
  most agents): the cost of the neighbour scan alone;
* ``crossing``: after 2 s of the sliding-mode controller with the filter in the loop, when
  the pair crosses the swarm;
* ``all active``: the same state with every nominal command pointed at the agent's nearest
  UAV at full bound (the worst nominal for the filter; agents whose neighbours are far
  enough still pass it unchanged).

``--assumptions`` instead runs the sliding-mode controller without the filter (paper
preset, 8 seeds, first 25 s) and prints percentiles of what the filter's parameters must
cover: the acceleration of unpaired UAVs towards a paired UAV within the sensing radius
(``other_accel``), the closing speeds there (``sensing_radius``), the paired UAVs' own
flocking command (the budget ``accel_limit - brake_accel`` it leaves) and the partners'
closing speed.

``--in-step`` instead runs the sliding-mode controller with ``safety_filter="cbf"`` in the
core (N = 100, B = 256 by default) from the reset through the pair's crossing of the swarm
and times, in CPU time of this process, every stage of each ``core.step`` (validate,
decode, the safety stage, desired acceleration, vehicle, neighbour pass, observation, the rest
of the refresh): the medians over steps of each part and of the safety stage's share of the whole
step, over all steps and over the steps where some agent's filter was active.

``--vecenv`` measures what training sees: the SB3 VecEnv of the learned pair policy's task
(pair interface, N = 20, 32 swarms, ``pair_accel_limit=50``, ``obs_neighbors=12``) under
random actions, filter off and on alternately, in agent-steps per CPU second (medians).
``--smoke`` runs every part once, tiny (a check of the script, not a measurement).

Filter and core batches are timed alternately (calibrated batch sizes, one thread); the
table gives the medians and the median of the per-repeat ratio, the figure to read on a
shared machine, where absolute times are noisy. The column "no skip" times the same filter
with the far-UAV skip switched off (every UAV within the sensing radius gets its barrier
computed; the commands are the same bit for bit): what the skip saves.
"""

from __future__ import annotations

from baselines.runtime.threads import pin_threads

pin_threads()  # one thread for OpenMP/MKL/OpenBLAS/numba, before numpy loads

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from baselines.controllers.sliding_mode import SlidingModeController  # noqa: E402
from baselines.runtime.cli import ArgumentParser, at_least  # noqa: E402
from pairflock_env import PairFlockCore, make_config  # noqa: E402
from pairflock_env.envs.sb3 import PairFlockSB3VecEnv  # noqa: E402
from pairflock_env.safety import SafetyFilter, SafetyParams  # noqa: E402
from pairflock_env.safety.cbf.kernels import BARRIER  # noqa: E402


def states(N: int, B: int, limit: float, params: dict):
    """(config, core, filter, [(name, q, p, f, u_nom)]) for the three benchmark states."""
    cfg = make_config("paper", n_uavs=N, max_cycles=10**9, pair_accel_limit=limit)
    core = PairFlockCore(cfg, num_swarms=B)
    res = core.reset(seed=0)
    smc = SlidingModeController(cfg)
    ia = core.agent_uavs
    filt = SafetyFilter(SafetyParams.from_config(cfg, **params), ia, N, core.partner_uavs)
    buf = filt.allocate(B, cfg.dim)

    def nominal(obs):
        act, _ = smc.predict(obs.reshape(-1, obs.shape[-1]))
        return np.clip(act.reshape(B, ia.size, cfg.dim), -1, 1) * limit

    out = [("start", core.q.copy(), core.p.copy(), core.flock_accel.copy(), nominal(res.obs))]
    for _ in range(200):  # 2 s with the filter in the loop: the pair is in the swarm
        filt.apply(core.q, core.p, core.flock_accel[:, ia], nominal(res.obs), buf)
        res = core.step(buf.u / limit)
    q, p, f = core.q.copy(), core.p.copy(), core.flock_accel.copy()
    out.append(("crossing", q, p, f, nominal(res.obs)))
    x = q[:, None] - q[:, ia, None]  # (B, M, N, dim)
    d = np.linalg.norm(x, axis=-1)
    d[:, np.arange(ia.size), ia] = np.inf
    tgt = np.take_along_axis(x, d.argmin(-1)[..., None, None], axis=2)[:, :, 0]
    out.append(("all active", q, p, f, limit * tgt / np.linalg.norm(tgt, axis=-1)[..., None]))
    return cfg, core, filt, out


def assumptions(N: int, seeds: int = 8, radius: float = 20.0, steps: int | None = None) -> None:
    """Percentiles of the quantities behind the filter's assumptions (module docstring),
    for the UAVs within ``radius`` of a paired UAV (20 m: the filter's sensing radius when
    docs/safety-results.md quoted them; the default is 100 m now), over the first ``steps`` control
    steps (default: half an episode, 25 s)."""
    cfg = make_config("paper", n_uavs=N)
    core = PairFlockCore(cfg, num_swarms=seeds)
    res = core.reset(seed=list(range(seeds)))
    smc = SlidingModeController(cfg)
    ia = core.agent_uavs
    unp = np.setdiff1d(np.arange(N), ia)
    rec: dict[str, list] = {"toward": [], "closing": [], "own": [], "partner": []}
    for _ in range(cfg.episode_steps // 2 if steps is None else steps):
        q, p, acc = core.q, core.p, core.flock_accel
        for i in ia:
            x = q[:, i : i + 1] - q[:, unp]
            d = np.linalg.norm(x, axis=-1)
            n = x / d[..., None]
            near = d < radius
            rec["toward"].append(np.einsum("bud,bud->bu", n, acc[:, unp])[near])
            rec["closing"].append(-np.einsum("bud,bud->bu", n, p[:, i : i + 1] - p[:, unp])[near])
            rec["own"].append(np.linalg.norm(acc[:, i], axis=-1))
        y = q[:, ia[1]] - q[:, ia[0]]
        rate = np.einsum("bd,bd->b", y, p[:, ia[1]] - p[:, ia[0]]) / np.linalg.norm(y, axis=-1)
        rec["partner"].append(-rate)
        act, _ = smc.predict(res.obs.reshape(-1, res.obs.shape[-1]))
        res = core.step(act.reshape(seeds, ia.size, cfg.dim))
    print(f"\n## What the filter faces: smc, paper preset, N = {N}, {seeds} seeds, 25 s\n")
    print("| quantity | p50 | p90 | p99 | p99.9 | max |\n|---|---|---|---|---|---|")
    names = {
        "toward": f"unpaired UAV's acceleration towards a paired UAV within {radius} m (m/s^2)",
        "closing": f"closing speed to unpaired UAVs within {radius} m (m/s)",
        "own": "paired UAV's own flocking command |f_i| (m/s^2)",
        "partner": "partners' closing speed (m/s)",
    }
    for k, label in names.items():
        v = np.percentile(np.concatenate(rec[k]), [50, 90, 99, 99.9, 100])
        print(f"| {label} | " + " | ".join(f"{x:.1f}" for x in v) + " |")


#: the core's stages timed by --in-step: (label, object path, attribute)
STAGES = (
    ("1. validate", "", "check_actions"),
    ("2. decode", "", "decode_actions"),
    ("2b. safety filter", "safety", "apply"),
    ("3. desired acceleration", "", "_desired_acceleration"),
    ("4. vehicle", "vehicle", "advance"),
    ("5a. flocking + pair pass", "", "_neighbor_pass"),
    ("5b. observation", "", "_observation"),
)


#: --in-step's clock: this process's CPU time (one thread), which other processes on a
#: shared machine do not inflate the way they inflate wall time
_CLOCK = time.process_time


def _timed(obj, name: str, acc: dict, label: str) -> None:
    """Replace obj.name by a wrapper adding its CPU time to acc[label] (this instance)."""
    fn = getattr(obj, name)

    def wrapper(*a, **kw):
        t0 = _CLOCK()
        try:
            return fn(*a, **kw)
        finally:
            acc[label] = acc.get(label, 0.0) + _CLOCK() - t0

    setattr(obj, name, wrapper)


def in_step(
    N: int,
    B: int,
    limit: float,
    steps: int,
    radius: float | None = None,
    preset: str = "paper",
    pairs: int | None = None,
    scan: bool = False,
) -> None:
    """Per-stage times of core.step with the filter on (module docstring)."""
    extra = {} if pairs is None else {"pairs": tuple((2 * k, 2 * k + 1) for k in range(pairs))}
    cfg = make_config(
        preset,
        **extra,
        n_uavs=N,
        pair_accel_limit=limit,
        safety_filter="cbf",
        **({} if radius is None else {"safety_sensing_radius": radius}),
    )
    core = PairFlockCore(cfg, num_swarms=B)
    if scan:  # the filter scans all N UAVs per agent although the core has a grid
        apply = core.safety.apply
        core.safety.apply = lambda q, p, f, u, grid=None: apply(q, p, f, u)
    res = core.reset(seed=0)
    smc = SlidingModeController(cfg)
    acc: dict[str, float] = {}
    for label, path, name in STAGES:
        _timed(getattr(core, path) if path else core, name, acc, label)
    rows, active = [], []
    for _ in range(steps):
        act, _ = smc.predict(res.obs.reshape(-1, res.obs.shape[-1]))
        act = act.reshape(B, core.n_agents, cfg.dim)
        acc.clear()
        t0 = _CLOCK()
        res = core.step(act)
        total = _CLOCK() - t0
        parts = {label: acc.get(label, 0.0) for label, _, _ in STAGES}
        parts["5c. rewards, infos, rest"] = total - sum(parts.values())
        parts["total core.step"] = total
        rows.append(parts)
        active.append(bool(res.info["safety_active"].any()))
    _step_table(rows, np.array(active), N, B, limit, steps, cfg, scan)


def _step_table(rows, active, N, B, limit, steps, cfg, scan=False) -> None:
    look = f", safety_sensing_radius = {cfg.safety_sensing_radius:g} m"
    if scan:
        look += ", the filter scanning all N"
    print(
        f"\n## Stages of core.step with safety_filter='cbf' (smc, preset {cfg.preset!r}, "
        f"N = {N}, {len(cfg.pairs)} pairs, B = {B}, neighbor_search {cfg.neighbor_search!r}, "
        f"pair_accel_limit = {limit:g}{look}, {steps} steps from the reset; CPU time, medians "
        "over steps)\n"
    )
    sel = {"all steps": np.ones(len(rows), bool), "steps with an active filter": active}
    print("| stage | " + " | ".join(f"{k} (ms)" for k in sel) + " |")
    print("|---|" + "---|" * len(sel))
    for key in rows[0]:
        cells = [
            f"{1e3 * statistics.median(r[key] for r, m in zip(rows, mask, strict=True) if m):.3f}"
            if mask.any()
            else "-"
            for mask in sel.values()
        ]
        print(f"| {key} | " + " | ".join(cells) + " |")
    share = [r["2b. safety filter"] / r["total core.step"] for r in rows]
    cells = [
        f"{100 * statistics.median(x for x, m in zip(share, mask, strict=True) if m):.1f} %"
        if mask.any()
        else "-"
        for mask in sel.values()
    ]
    print("| **safety filter / core.step** | " + " | ".join(cells) + " |")
    print(f"\nsteps with an active filter: {int(active.sum())} of {len(rows)}")


def vecenv(repeats: int = 5, steps: int = 200, n_uavs: int = 20, num_swarms: int = 32) -> None:
    """Agent-steps per CPU second of the learning VecEnv, filter off vs on."""
    kw = dict(n_uavs=n_uavs, pair_accel_limit=50.0, obs_neighbors=12, num_swarms=num_swarms)
    settings = {
        "none": dict(safety_filter="none"),
        "cbf": dict(safety_filter="cbf"),  # the default 100 m sensing radius
        "cbf, 20 m radius": dict(safety_filter="cbf", safety_sensing_radius=20.0),
    }
    envs = {m: PairFlockSB3VecEnv(seed=0, **s, **kw) for m, s in settings.items()}
    rng = np.random.default_rng(0)
    rates: dict[str, list[float]] = {m: [] for m in envs}
    for env in envs.values():
        env.reset()
    for _ in range(repeats):
        for m, env in envs.items():
            acts = rng.uniform(-1, 1, (steps, env.num_envs, env.action_space.shape[0]))
            t0 = time.process_time()
            for a in acts:
                env.step(a)
            rates[m].append(steps * env.num_envs / (time.process_time() - t0))
    print(f"\n## SB3 VecEnv, random actions ({kw}; agent-steps per CPU second)\n")
    print("| safety_filter | agent-steps/s | relative |\n|---|---|---|")
    base = statistics.median(rates["none"])
    for m, r in rates.items():
        print(f"| {m} | {statistics.median(r):,.0f} | {statistics.median(r) / base:.2f} |")


def _calls(fn, min_time: float) -> int:
    """Calls of fn per timed batch: doubled until a batch takes min_time (after a warm-up)."""
    fn()
    n = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        if time.perf_counter() - t0 >= min_time:
            return n
        n *= 2


def _ms(fn, n: int) -> float:
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return 1e3 * (time.perf_counter() - t0) / n


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python benchmarks/bench_safety.py``."""
    ap = ArgumentParser(
        prog="python benchmarks/bench_safety.py", description=__doc__.splitlines()[0]
    )
    ap.add_argument("--n", type=at_least(2), default=100, help="UAVs per swarm")
    ap.add_argument("--b", type=at_least(1), default=256, help="swarms")
    ap.add_argument("--limit", type=float, default=50.0, help="pair_accel_limit, m/s^2")
    ap.add_argument("--quick", action="store_true", help="fewer repeats")
    ap.add_argument("--assumptions", action="store_true", help="print what the filter faces")
    ap.add_argument(
        "--in-step", action="store_true", help="time the stages of a filtered core.step"
    )
    ap.add_argument("--steps", type=at_least(1), default=400, help="--in-step: control steps")
    ap.add_argument(
        "--radius",
        type=float,
        default=None,
        help="--in-step: safety_sensing_radius (m; default: the preset's)",
    )
    ap.add_argument(
        "--preset",
        default="paper",
        help="--in-step: the task's preset (e.g. large: 10 pairs, the grid search)",
    )
    ap.add_argument(
        "--pairs", type=int, default=None, help="--in-step: K pairs (0, 1), (2, 3), ..."
    )
    ap.add_argument(
        "--scan",
        action="store_true",
        help="--in-step: the filter scans all N UAVs per agent, not the core's grid",
    )
    ap.add_argument("--vecenv", action="store_true", help="SB3 VecEnv throughput off vs on")
    ap.add_argument(
        "--smoke",
        action="store_true",
        help="every part once, tiny (N = 8, one swarm): checks the script, measures nothing",
    )
    return ap


def main(argv=None) -> None:
    """Run the part asked for (default: the filter against one core step)."""
    args = build_parser().parse_args(argv)
    if args.smoke:
        filter_table(8, 1, args.limit, repeats=1, min_time=0.0)
        in_step(8, 1, args.limit, 5, None, "paper", None, False)
        assumptions(8, seeds=1, radius=1e4, steps=5)
        vecenv(repeats=1, steps=5, n_uavs=8, num_swarms=1)
    elif args.vecenv:
        vecenv()
    elif args.assumptions:
        assumptions(args.n)
    elif args.in_step:
        in_step(
            args.n, args.b, args.limit, args.steps, args.radius, args.preset, args.pairs, args.scan
        )
    else:
        repeats, min_time = (5, 0.1) if args.quick else (15, 0.3)
        filter_table(args.n, args.b, args.limit, repeats, min_time)


def filter_table(N: int, B: int, limit: float, repeats: int, min_time: float) -> None:
    """The filter on the three states of :func:`states` against one core step, interleaved."""
    cfg, core, filt, cases = states(N, B, limit, {})
    buf = filt.allocate(B, cfg.dim)
    full = SafetyFilter(filt.params, core.agent_uavs, N, core.partner_uavs)
    full._pr[BARRIER.index.skip_far] = 0.0  # the kernel's far-UAV skip off: every UAV
    buf_full = full.allocate(B, cfg.dim)
    actions = np.zeros((B, core.n_agents, cfg.dim))

    def step():
        core.step(actions)

    n_step = _calls(step, min_time)
    print(f"\n## Safety filter vs one core step (N = {N}, B = {B}, M = {core.n_agents})\n")
    print(f"params: {filt.params}\n")
    print(
        "| state | active | infeasible | filter (ms) | no skip (ms) | core.step (ms) "
        "| filter / step |"
    )
    print("|---|---|---|---|---|---|---|")
    for name, q, p, f, un in cases:
        fa = f[:, core.agent_uavs]

        def apply(q=q, p=p, fa=fa, un=un):
            filt.apply(q, p, fa, un, buf)

        def apply_full(q=q, p=p, fa=fa, un=un):
            full.apply(q, p, fa, un, buf_full)

        n_f, n_full = _calls(apply, min_time), _calls(apply_full, min_time)
        # interleaved, so that the medians see the same load of a shared machine
        runs = [
            (_ms(apply, n_f), _ms(apply_full, n_full), _ms(step, n_step)) for _ in range(repeats)
        ]
        f_ms, full_ms, s_ms = (statistics.median(r[k] for r in runs) for k in range(3))
        ratio = statistics.median(x / y for x, _, y in runs)
        # the skip's promise, checked on each state: commands and flags bit for bit
        if not all(
            np.array_equal(x, y)
            for x, y in zip(buf.arrays()[:4], buf_full.arrays()[:4], strict=True)
        ):
            raise RuntimeError(f"state {name!r}: the skip changed a filtered command or flag")
        print(
            f"| {name} | {buf.active.mean():.0%} | {buf.infeasible.mean():.0%} | {f_ms:.3f} | "
            f"{full_ms:.3f} | {s_ms:.2f} | {100 * ratio:.1f} % |"
        )


if __name__ == "__main__":
    main()
