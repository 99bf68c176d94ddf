"""Speed of the swarm layer (``safety_scope="swarm"``, docs/swarm-safety.md), one thread,
CPU time of this process (steadier than wall time on a shared machine).

    python benchmarks/bench_swarm_safety.py --share            # N = 100, B = 256: its share
    python benchmarks/bench_swarm_safety.py --flight           # 10,000 UAVs, the whole flight
    python benchmarks/bench_swarm_safety.py --flight --layers off swarm
    python benchmarks/bench_swarm_safety.py --smoke            # every part once, tiny

``--share`` flies sliding mode with the layer on (paper preset, N = 100, B = 256 swarms)
from the reset for ``--seconds`` and times, for every ``core.step``, the whole step and the
safety stage inside it: the medians over steps of both and of the stage's share, and the
share of the summed times; then the same steps' parts (stage, neighbour pass, vehicle,
observation, rest).

``--flight`` flies one swarm of ``--n`` UAVs (preset ``large``, zero pair actions unless
``--policy``) for the whole episode under each of ``--layers`` (off: the paper's law;
pairs: the pair filter; swarm: the layer), and prints UAV-steps per CPU second over every
5 s of flight and over the whole flight, and where the time went. Flights run one after the
other (a whole flight cannot be interleaved); compare them in the same run.
"""

from __future__ import annotations

from baselines.runtime.threads import pin_threads

pin_threads()  # one thread for OpenMP/MKL/OpenBLAS/numba, before numpy loads

import time  # noqa: E402

import numpy as np  # noqa: E402

from baselines.controllers import make_pair_policy  # noqa: E402
from baselines.runtime.cli import ArgumentParser  # noqa: E402
from pairflock_env import PairFlockCore, make_config  # noqa: E402

CLOCK = time.process_time
#: the core's parts timed inside a step: (label, object path, attribute)
PARTS = (
    ("safety stage (the layer)", "safety", "apply"),
    ("neighbour pass (flocking sweep, pairs)", "", "_neighbor_pass"),
    ("vehicle", "vehicle", "advance"),
    ("observation", "", "_observation"),
)
LAYERS = {
    "off": {},
    "pairs": {"safety_filter": "cbf"},
    "swarm": {"safety_filter": "cbf", "safety_scope": "swarm"},
}


def _timed(obj, name: str, acc: dict, label: str) -> None:
    """Replace obj.name by a wrapper adding its CPU time to acc[label] (this instance)."""
    fn = getattr(obj, name)

    def wrapper(*a, **kw):
        t0 = CLOCK()
        try:
            return fn(*a, **kw)
        finally:
            acc[label] = acc.get(label, 0.0) + CLOCK() - t0

    setattr(obj, name, wrapper)


def _instrument(core) -> dict:
    acc: dict[str, float] = {}
    for label, path, name in PARTS:
        _timed(getattr(core, path) if path else core, name, acc, label)
    return acc


def _actor(core, policy: str):
    """actions(res) for the core: zeros, or the named pair policy's."""
    B, M, D = core.num_swarms, core.n_agents, core.config.dim
    if policy == "zero":
        zero = np.zeros((B, M, D))
        return lambda res: zero
    pol = make_pair_policy(policy, core.config)

    def act(res):
        a, _ = pol.predict(res.obs.reshape(B * M, -1), deterministic=True)
        return np.asarray(a, np.float64).reshape(B, M, D)

    return act


def share(n: int, b: int, seconds: float, policy: str) -> None:
    """The layer's share of a step (module docstring)."""
    cfg = make_config("paper", n_uavs=n, **LAYERS["swarm"])
    core = PairFlockCore(cfg, num_swarms=b)
    res = core.reset(seed=0)
    act = _actor(core, policy)
    acc = _instrument(core)
    core.step(act(res))  # compile
    steps, stage, parts = [], [], {}
    for _ in range(max(1, round(seconds / cfg.dt))):
        a = act(res)
        acc.clear()
        t0 = CLOCK()
        res = core.step(a)
        steps.append(CLOCK() - t0)
        stage.append(acc.get(PARTS[0][0], 0.0))
        for k, v in acc.items():
            parts[k] = parts.get(k, 0.0) + v
    s, g = np.array(steps), np.array(stage)
    print(f"\n## The layer's share of a step: N = {n}, B = {b}, {policy}, {len(s)} steps\n")
    print("| step median (ms) | layer median (ms) | share, median over steps | share of sums |")
    print("|---|---|---|---|")
    print(
        f"| {1e3 * np.median(s):.2f} | {1e3 * np.median(g):.2f} | "
        f"{100 * np.median(g / s):.0f} % | {100 * g.sum() / s.sum():.0f} % |"
    )
    _where(parts, s.sum(), len(s))


def _where(parts: dict[str, float], total: float, steps: int) -> None:
    print("\n| part | ms per step | share |\n|---|---|---|")
    rest = total - sum(parts.values())
    for k, v in [*parts.items(), ("rest of the step", rest)]:
        print(f"| {k} | {1e3 * v / steps:.2f} | {100 * v / total:.0f} % |")


def flight(n: int, layer: str, policy: str, seed: int, horizon: float | None) -> None:
    """One whole flight (module docstring)."""
    kw = {} if horizon is None else {"horizon": horizon}
    cfg = make_config("large", n_uavs=n, **kw, **LAYERS[layer])
    core = PairFlockCore(cfg, num_swarms=1)
    res = core.reset(seed=[seed])
    act = _actor(core, policy)
    core.step(act(res))  # compile (one step of the flight's start, not timed)
    res = core.reset(seed=[seed])
    acc = _instrument(core)
    window = max(1, round(5.0 / cfg.dt))
    print(f"\n## {n:,} UAVs, {layer}, {policy}, seed {seed}: UAV-steps per CPU second\n")
    print("| flight time (s) | this window | so far | closest two UAVs so far (m) |")
    print("|---|---|---|---|")
    total, t_win, closest = 0.0, 0.0, np.inf
    for k in range(1, cfg.episode_steps + 1):
        a = act(res)
        t0 = CLOCK()
        res = core.step(a)
        dt = CLOCK() - t0
        total, t_win = total + dt, t_win + dt
        closest = min(closest, float(res.info["swarm_min_separation"][0]))
        if k % window == 0 or k == cfg.episode_steps:
            w = k % window or window
            print(
                f"| {k * cfg.dt:.0f} | {n * w / t_win:,.0f} | {n * k / total:,.0f} | "
                f"{closest:.4f} |"
            )
            t_win = 0.0
    print(f"\nwhole flight: {n * cfg.episode_steps / total:,.0f} UAV-steps/s ({total:.1f} s CPU)")
    _where(acc, total, cfg.episode_steps)


def main() -> None:
    p = ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--share", action="store_true", help="the layer's share at N = 100, B = 256")
    p.add_argument("--flight", action="store_true", help="whole flights of --n UAVs")
    p.add_argument("--smoke", action="store_true", help="every part once, tiny")
    p.add_argument("--n", type=int, default=None, help="UAVs (share: 100, flight: 10000)")
    p.add_argument("--b", type=int, default=256, help="swarms of --share")
    p.add_argument("--seconds", type=float, default=10.0, help="flight time of --share (s)")
    p.add_argument("--layers", nargs="+", default=["swarm"], choices=list(LAYERS))
    p.add_argument("--policy", default=None, help="share: smc; flight: zero")
    p.add_argument("--seed", type=int, default=72000)
    a = p.parse_args()
    if a.smoke:
        share(20, 2, 0.05, "smc")
        flight(300, "swarm", "zero", a.seed, 0.2)
        return
    if not (a.share or a.flight):
        p.error("choose --share, --flight or --smoke")
    if a.share:
        share(a.n or 100, a.b, a.seconds, a.policy or "smc")
    if a.flight:
        for layer in a.layers:
            flight(a.n or 10000, layer, a.policy or "zero", a.seed, None)


if __name__ == "__main__":
    main()
