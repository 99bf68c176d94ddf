"""SB3 training throughput: the native batched VecEnv vs PettingZoo -> SuperSuit -> SB3.

    python -m train.throughput                       # PPO, N = 20, 16 swarms, 3 repeats
    python -m train.throughput --algo sac --steps 20000 --num-swarms 8
    python -m train.throughput --config train/configs/pair_mix_a50.yaml \
        --config train/configs/pair_n20_a50.yaml      # run configs instead (train.config_speed)

Both routes run the same task (the raw world-frame observation, action and reward, since that
is what the PettingZoo env offers), the same number of rows (swarms x paired UAVs), the same
algorithm and hyperparameters, in this one process with one torch thread. For each route it
measures (a) environment steps per second with random actions and (b) SB3 training steps per
second including learning (``model.learn``), after a warm-up; the routes alternate
``--repeats`` times and the median is reported. Writes ``--out`` (JSON, with package versions
and the git commit). Timings on a shared machine are noisy: compare the ratio, and rerun on a
quiet one for absolute numbers.

With ``--config`` it measures run configs instead (a task mix too): ``model.learn`` of each
config's own VecEnv and model in CPU and wall time, one evaluation, and an estimate of the
whole run on one core (:mod:`train.config_speed`); ``--steps`` and ``--repeats`` apply.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from baselines.evaluation.parallel import pin_threads

__all__ = ["main", "make_route"]

ROUTES = ("native", "supersuit")


def make_route(route: str, num_swarms: int, overrides: dict[str, Any], seed: int):
    """The SB3 VecEnv of a route (raw world frame on both)."""
    if route == "native":
        from pairflock_env.envs.sb3 import PairFlockSB3VecEnv
        from train.settings import env_interface_kwargs

        world = env_interface_kwargs("world", {})
        return PairFlockSB3VecEnv(num_swarms=num_swarms, seed=seed, **world, **overrides)
    if route == "supersuit":
        try:
            import supersuit as ss
        except ImportError as e:  # pragma: no cover - depends on the install
            raise SystemExit("the supersuit route needs: pip install supersuit") from e
        from pairflock_env import parallel_env

        v = ss.pettingzoo_env_to_vec_env_v1(parallel_env(seed=seed, **overrides))
        venv = ss.concat_vec_envs_v1(v, num_swarms, num_cpus=0, base_class="stable_baselines3")
        inner = venv.venv
        if not hasattr(inner, "seed"):
            # SuperSuit 3.9+ dropped ConcatVecEnv.seed, which SB3's model constructor calls
            # (AttributeError: 'ConcatVecEnv' object has no attribute 'seed'). The usual
            # workaround: seed through the next reset instead.
            def _seed(s: int | None = None) -> list[int | None]:
                inner.reset(seed=s)
                return [s] * inner.num_envs

            inner.seed = _seed
        return venv
    raise ValueError(f"route={route!r} is invalid: must be one of {ROUTES}")


def _env_rate(venv, steps: int, seed: int) -> float:
    import numpy as np

    rng = np.random.default_rng(seed)
    venv.reset()
    n = venv.num_envs
    t0 = time.perf_counter()
    k = 0
    while k * n < steps:
        venv.step(rng.uniform(-1, 1, (n, venv.action_space.shape[0])).astype(np.float32))
        k += 1
    return k * n / (time.perf_counter() - t0)


def _learn_rate(venv, algo: str, hp: dict[str, Any], steps: int, seed: int) -> float:
    import stable_baselines3 as sb3

    model = getattr(sb3, algo.upper())("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **hp)
    warm = hp.get("n_steps", 1) * venv.num_envs if algo == "ppo" else 2 * venv.num_envs
    model.learn(warm)  # warm-up: JIT, allocations, first update
    t0 = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    return (model.num_timesteps - warm) / (time.perf_counter() - t0)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m train.throughput",
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--algo", choices=("ppo", "sac", "td3"), default="ppo", help="algorithm (default ppo)"
    )
    p.add_argument("--n-uavs", type=int, default=20, help="swarm size N (default 20)")
    p.add_argument("--num-swarms", type=int, default=16, help="swarms per VecEnv (default 16)")
    p.add_argument(
        "--steps",
        type=int,
        default=100_000,
        help="timed training steps per measurement (default 100000)",
    )
    p.add_argument(
        "--env-steps",
        type=int,
        default=50_000,
        help="timed random-action env steps per measurement (default 50000)",
    )
    p.add_argument("--repeats", type=int, default=3, help="alternating repeats (default 3)")
    p.add_argument(
        "--hp",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="SB3 hyperparameter for both routes (default: train.settings defaults "
        "with n_steps=128, batch_size=1024 for PPO)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    p.add_argument(
        "--config",
        type=Path,
        action="append",
        default=[],
        metavar="YAML",
        help="measure this run config instead of the two routes (repeatable; train.config_speed)",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("results/throughput.json"),
        help="result file (default results/throughput.json)",
    )
    return p


def _hyperparameters(args: argparse.Namespace) -> dict[str, Any]:
    """The training defaults of the algorithm, sized for a throughput run, plus ``--hp``."""
    from train.settings import DEFAULT_HYPERPARAMETERS, parse_assignment

    hp = {k: v for k, v in DEFAULT_HYPERPARAMETERS[args.algo].items() if k != "action_noise_std"}
    hp["policy_kwargs"] = dict(hp.get("policy_kwargs", {}))
    if args.algo == "ppo":
        hp.update(n_steps=128, batch_size=1024)
    else:
        hp.update(buffer_size=max(args.steps * 2, 10_000), learning_starts=0)
    for item in args.hp:
        k, v = parse_assignment(item, "--hp")
        hp[k] = v
    return hp


def _measure(args, hp, overrides) -> dict[str, dict[str, list[float]]]:
    """Both routes, alternating, ``--repeats`` times."""
    from tqdm import tqdm

    results: dict[str, dict[str, list[float]]] = {r: {"env": [], "learn": []} for r in ROUTES}
    with tqdm(total=args.repeats * len(ROUTES), desc="throughput", unit="run") as bar:
        for rep in range(args.repeats):
            for route in ROUTES:
                venv = make_route(route, args.num_swarms, overrides, args.seed + rep)
                results[route]["env"].append(_env_rate(venv, args.env_steps, args.seed))
                rate = _learn_rate(venv, args.algo, hp, args.steps, args.seed)
                results[route]["learn"].append(rate)
                venv.close()
                bar.update()
    return results


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m train.throughput`` / ``pairflock-throughput``; returns the exit status."""
    pin_threads()
    args = build_parser().parse_args(argv)
    for name in ("n_uavs", "num_swarms", "steps", "env_steps", "repeats"):
        if getattr(args, name) < 1:
            raise SystemExit(
                f"--{name.replace('_', '-')}={getattr(args, name)} is invalid: must be >= 1"
            )
    pin_threads(load_torch=True)
    import numpy as np

    from baselines.evaluation.io import run_record, write_json

    if args.config:
        return _configs(args)
    hp = _hyperparameters(args)
    overrides = {"n_uavs": args.n_uavs, "pair_accel_limit": 50.0, "max_cycles": 1000}
    results = _measure(args, hp, overrides)
    med = {r: {k: float(np.median(v)) for k, v in d.items()} for r, d in results.items()}
    ratio = {k: med["native"][k] / med["supersuit"][k] for k in ("env", "learn")}
    rows = args.num_swarms * 2
    record = run_record(
        algo=args.algo,
        n_uavs=args.n_uavs,
        num_swarms=args.num_swarms,
        rows=rows,
        steps=args.steps,
        env_steps=args.env_steps,
        repeats=args.repeats,
        hyperparameters=hp,
        task=overrides,
        measurements=results,
        median=med,
        ratio=ratio,
        load_average=list(os.getloadavg()),
        cpu_count=os.cpu_count(),
    )
    write_json(args.out, record)
    print(
        f"{args.algo.upper()}, N={args.n_uavs}, {args.num_swarms} swarms ({rows} rows), "
        f"median of {args.repeats}:\n"
        f"  env steps/s (random actions): native {med['native']['env']:.0f}, "
        f"supersuit {med['supersuit']['env']:.0f}, ratio {ratio['env']:.2f}x\n"
        f"  training steps/s (incl. learning): native {med['native']['learn']:.0f}, "
        f"supersuit {med['supersuit']['learn']:.0f}, ratio {ratio['learn']:.2f}x"
    )
    print(f"wrote {args.out}")
    return 0


def _configs(args: argparse.Namespace) -> int:
    """``--config`` mode: the training speed of run configs."""
    from baselines.evaluation.io import run_record, write_json
    from train.config_speed import report, run_configs

    for path in args.config:
        if not path.is_file():
            raise SystemExit(f"--config {str(path)!r} does not exist")
    results = run_configs(args.config, args.steps, args.repeats)
    record = run_record(
        steps=args.steps,
        repeats=args.repeats,
        configs=results,
        load_average=list(os.getloadavg()),
        cpu_count=os.cpu_count(),
    )
    write_json(args.out, record)
    print(report(results, args.steps, args.repeats))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
