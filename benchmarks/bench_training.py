"""Training speed: SB3 on the native batched VecEnv vs PettingZoo -> SuperSuit -> SB3, and
the speed of run configs.

    python benchmarks/bench_training.py                 # PPO, N = 20, 16 swarms, 3 repeats
    python benchmarks/bench_training.py --algo sac --steps 20000 --num-swarms 8
    python benchmarks/bench_training.py --config train/configs/pair_mix_a50.yaml \\
        --config train/configs/pair_n20_a50.yaml        # run configs instead

Both routes run the same task (the raw world-frame observation, action and reward, since that
is what the PettingZoo env offers), the same number of rows (swarms x paired UAVs), the same
algorithm and hyperparameters, in this one process with one torch thread. For each route it
measures (a) environment steps per second with random actions and (b) SB3 training steps per
second including learning (``model.learn``), after a warm-up; the routes alternate
``--repeats`` times and the median is reported. Writes ``--out`` (JSON, with package versions
and the git commit). Timings on a shared machine are noisy: compare the ratio, and rerun on a
quiet one for absolute numbers.

With ``--config`` it measures run configs instead (a task mix too): for each settings file,
the run's own VecEnv (one task, or the concatenated task envs of a mix) and model are built as
``python -m train`` builds them; after a warm-up of one rollout and update, ``model.learn`` is
timed for ``--steps`` decisions, in CPU time of this process (one thread: what a dedicated core
gives, and far steadier than wall time on a shared machine) and in wall time. The configs
alternate ``--repeats`` times; medians are reported. One periodic evaluation (the policy on
every evaluation task and seed, full episodes) is timed too, and the whole run is estimated as
``total_steps`` / rate + evaluations + baselines. ``--smoke`` runs every part once, tiny (a
check of the script, not a measurement).
"""

from __future__ import annotations

from baselines.runtime.threads import pin_threads

pin_threads()  # one thread for OpenMP/MKL/OpenBLAS/numba, before numpy and torch load

import argparse  # noqa: E402
import os  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
import stable_baselines3 as sb3  # noqa: E402
from tqdm import tqdm  # noqa: E402

from baselines.controllers.sb3 import SB3PairPolicy  # noqa: E402
from baselines.evaluation.specs import parse_assignment  # noqa: E402
from baselines.runtime.cli import ArgumentParser, at_least, user_errors  # noqa: E402
from baselines.runtime.files import write_json  # noqa: E402
from baselines.runtime.record import run_record  # noqa: E402
from pairflock_env import parallel_env  # noqa: E402
from pairflock_env.envs.sb3 import PairFlockSB3VecEnv  # noqa: E402
from train.hyperparameters import DEFAULT_HYPERPARAMETERS  # noqa: E402
from train.mix.tasks import evaluation_tasks  # noqa: E402
from train.model import build_model  # noqa: E402
from train.run import evaluate_policy_rows, make_vec_env  # noqa: E402
from train.settings import env_interface_kwargs, load_yaml, settings_from_sources  # noqa: E402

try:
    import supersuit as ss
except ImportError:  # pragma: no cover - a dev dependency
    ss = None

__all__ = ["estimate_run_s", "main", "make_route", "measure_config", "run_configs"]

ROUTES = ("native", "supersuit")


def make_route(route: str, num_swarms: int, overrides: dict[str, Any], seed: int):
    """The SB3 VecEnv of a route (raw world frame on both)."""
    if route == "native":
        world = env_interface_kwargs("world", {})
        return PairFlockSB3VecEnv(num_swarms=num_swarms, seed=seed, **world, **overrides)
    if route == "supersuit":
        if ss is None:  # pragma: no cover - depends on the install
            raise ModuleNotFoundError("the supersuit route needs: pip install supersuit")

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
    model = getattr(sb3, algo.upper())("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **hp)
    warm = hp.get("n_steps", 1) * venv.num_envs if algo == "ppo" else 2 * venv.num_envs
    model.learn(warm)  # warm-up: JIT, allocations, first update
    t0 = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    return (model.num_timesteps - warm) / (time.perf_counter() - t0)


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python benchmarks/bench_training.py``."""
    p = ArgumentParser(
        prog="python benchmarks/bench_training.py",
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--algo", choices=("ppo", "sac", "td3"), default="ppo", help="algorithm (default ppo)"
    )
    p.add_argument("--n-uavs", type=at_least(2), default=20, help="swarm size N (default 20)")
    p.add_argument(
        "--num-swarms", type=at_least(1), default=16, help="swarms per VecEnv (default 16)"
    )
    p.add_argument(
        "--steps",
        type=at_least(1),
        default=100_000,
        help="timed training steps per measurement (default 100000)",
    )
    p.add_argument(
        "--env-steps",
        type=at_least(1),
        default=50_000,
        help="timed random-action env steps per measurement (default 50000)",
    )
    p.add_argument("--repeats", type=at_least(1), default=3, help="alternating repeats (default 3)")
    p.add_argument(
        "--hp",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="SB3 hyperparameter for both routes (default: train.settings defaults "
        "with n_steps=128, batch_size=1024 for PPO)",
    )
    p.add_argument("--seed", type=at_least(0), default=0, help="seed (default 0)")
    p.add_argument(
        "--config",
        type=Path,
        action="append",
        default=[],
        metavar="YAML",
        help="measure this run config instead of the two routes (repeatable)",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("results/throughput.json"),
        help="result file (default results/throughput.json)",
    )
    p.add_argument(
        "--smoke",
        action="store_true",
        help="both routes once, tiny (N = 6, 2 rows, 64 steps): checks the script, measures "
        "nothing",
    )
    return p


def _hyperparameters(args: argparse.Namespace) -> dict[str, Any]:
    """The training defaults of the algorithm, sized for a throughput run, plus ``--hp``."""
    hp = {k: v for k, v in DEFAULT_HYPERPARAMETERS[args.algo].items() if k != "action_noise_std"}
    hp["policy_kwargs"] = dict(hp.get("policy_kwargs", {}))
    if args.algo == "ppo":
        hp.update(n_steps=16 if args.smoke else 128, batch_size=32 if args.smoke else 1024)
    else:
        hp.update(buffer_size=max(args.steps * 2, 10_000), learning_starts=0)
    for item in args.hp:
        k, v = parse_assignment(item, "--hp")
        hp[k] = v
    return hp


def _measure(args, hp, overrides) -> dict[str, dict[str, list[float]]]:
    """Both routes, alternating, ``--repeats`` times."""
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
    """``python benchmarks/bench_training.py``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.smoke:
        args.n_uavs, args.num_swarms, args.steps, args.env_steps, args.repeats = 6, 1, 64, 64, 1
    with user_errors(parser, ModuleNotFoundError):
        return _configs(args) if args.config else _routes(args)


def _routes(args: argparse.Namespace) -> int:
    """The two routes: measure, write ``--out``, print the medians and ratios."""
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


def _settings(path: Path):
    return settings_from_sources(load_yaml(path))


def measure_config(path: Path, steps: int) -> dict[str, float]:
    """Decisions per CPU second and per wall second of ``model.learn`` for the config at
    ``path`` (after a warm-up), and the CPU seconds of one evaluation."""
    s = _settings(path)
    venv = make_vec_env(s)
    model = build_model(s, venv)
    n_steps = s.algo_hyperparameters().get("n_steps", 2)
    model.learn(n_steps * venv.num_envs)  # warm-up: JIT, allocations, first update
    start, c0, w0 = model.num_timesteps, time.process_time(), time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    done = model.num_timesteps - start
    iface = venv.unwrapped.interface.to_dict()
    c0 = time.process_time()
    for task in evaluation_tasks(s):
        cfg = task.config(s.preset)
        evaluate_policy_rows(SB3PairPolicy(model, cfg, iface), cfg, s.eval_seeds)
    eval_s = time.process_time() - c0
    venv.close()
    return {"rows": venv.num_envs, "cpu": done / cpu, "wall": done / wall, "eval_cpu_s": eval_s}


def estimate_run_s(settings: Any, rate: float, eval_s: float) -> float:
    """CPU seconds of the whole run: learning at ``rate`` decisions/s, every periodic and the
    final evaluation, and the baselines (about one evaluation each, once)."""
    n_evals = 1
    if settings.eval_every > 0:
        n_evals = 1 + settings.total_steps // settings.eval_every
        n_evals += int(settings.total_steps % settings.eval_every != 0)
    return settings.total_steps / rate + (n_evals + len(settings.eval_baselines)) * eval_s


def run_configs(paths: Sequence[Path], steps: int, repeats: int) -> dict[str, Any]:
    """Every config, alternating, ``repeats`` times; per config the medians and the estimate."""
    raw: dict[str, list[dict[str, float]]] = {str(p): [] for p in paths}
    with tqdm(total=repeats * len(paths), desc="throughput", unit="run") as bar:
        for _ in range(repeats):
            for p in paths:
                raw[str(p)].append(measure_config(Path(p), steps))
                bar.update()
    out: dict[str, Any] = {}
    for p, ms in raw.items():
        med = {k: statistics.median(m[k] for m in ms) for k in ("cpu", "wall", "eval_cpu_s")}
        s = _settings(Path(p))
        out[p] = {
            "rows": ms[0]["rows"],
            "measurements": ms,
            "median": med,
            "total_steps": s.total_steps,
            "estimated_run_cpu_min": estimate_run_s(s, med["cpu"], med["eval_cpu_s"]) / 60,
        }
    return out


def report(results: dict[str, Any], steps: int, repeats: int) -> str:
    """The terminal lines of :func:`run_configs`'s results."""
    lines = [f"model.learn, {steps} decisions per measurement, median of {repeats}:"]
    for p, r in results.items():
        m = r["median"]
        lines.append(
            f"  {Path(p).stem}: {r['rows']} rows, {m['cpu']:.0f} decisions/CPU-s "
            f"({m['wall']:.0f}/wall-s here), one evaluation {m['eval_cpu_s']:.1f} CPU-s; "
            f"{r['total_steps']:.3g} decisions ~ {r['estimated_run_cpu_min']:.1f} min on one core"
        )
    return "\n".join(lines)


def _configs(args: argparse.Namespace) -> int:
    """``--config`` mode: the training speed of run configs."""
    for path in args.config:
        if not path.is_file():
            raise FileNotFoundError(f"--config {str(path)!r} does not exist")
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
