"""The exported policies: parity, flash size and time per call (docs/export.md).

    python benchmarks/bench_export.py            # the committed policies, >= 10,000 obs each
    python benchmarks/bench_export.py --quick    # pair_quad3d, >= 1,000 obs, 3 repeats

Per policy (``baselines/models``): the export of ``pairflock-export``; the largest
differences on the observations the policy meets in its own task between SB3 (``predict`` on
the encoded observation; the ``sb3:`` policy's action) and onnxruntime / the C compiled by
``cc``; the object's ``.text`` and ``.rodata`` at ``-Os`` for this machine and, when
``arm-none-eabi-gcc`` is installed, for a Cortex-M4F (the Crazyflie's STM32F405; compiled
against a declarations-only ``math.h``, as newlib is not needed to size the object); and the
time per call on this machine at ``-O2`` of the whole chain (``pairflock_policy``), the network
alone and the encode, and of onnxruntime on one row from Python: medians over repeats, the
timers interleaved (one pass of each, then the next repeat), as the machine is shared.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from baselines.controllers.zoo import model_names  # noqa: E402
from baselines.export import build, verify  # noqa: E402

#: Cortex-M4F with its single-precision FPU, as on the Crazyflie 2.x
ARM_FLAGS = ("-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16")
_STUB_MATH = "float tanhf(float); float log1pf(float); float sqrtf(float);\n" \
    "#define INFINITY (__builtin_inff())\n"  # fmt: skip


def arm_flash(folder: Path, build_dir: Path) -> dict[str, int] | None:
    """.text/.rodata of the export compiled for a Cortex-M4F at -Os (None: no toolchain)."""
    cc = shutil.which("arm-none-eabi-gcc")
    if cc is None:
        return None
    stub = build_dir / "stub"
    stub.mkdir(exist_ok=True)
    (stub / "math.h").write_text(_STUB_MATH)
    obj = build_dir / "arm.o"
    args = [cc, *verify.C_FLAGS, *ARM_FLAGS, "-Os", f"-I{stub}", "-c",
            str(folder / "pairflock_policy.c"), "-o", str(obj)]  # fmt: skip
    subprocess.run(args, check=True)
    return verify.flash_size(verify.elf_sections(obj.read_bytes()))


def parity(lp: build.LoadedPolicy, folder: Path, exe: Path, obs: np.ndarray) -> dict:
    features = lp.interface.encode(obs)
    net, _ = lp.policy.model.predict(features, deterministic=True)
    env, _ = lp.policy.predict(obs)
    width = lp.network.output_size
    out = {"observations": len(obs)}
    if verify.onnxruntime is not None:
        out["onnx"] = np.abs(verify.onnx_actions(folder / build.ONNX, features) - net).max()
    c_net, _ = verify.run_harness(exe, features, "network", width)
    c_env, _ = verify.run_harness(exe, obs, "policy", width)
    out |= {"c_network": np.abs(c_net - net).max(), "c_policy": np.abs(c_env - env).max()}
    return out


def timings(lp: build.LoadedPolicy, folder: Path, exe: Path, obs: np.ndarray, repeats: int):
    """Median microseconds per call of each timer, interleaved over ``repeats``."""
    features = lp.interface.encode(obs)
    width, fsize = lp.network.output_size, lp.interface.observation_size
    runs = {
        "C pairflock_policy": lambda: verify.run_harness(exe, obs, "policy", width, 1)[1],
        "C network": lambda: verify.run_harness(exe, features, "network", width, 1)[1],
        "C encode": lambda: verify.run_harness(exe, obs, "encode", fsize, 1)[1],
    }
    if verify.onnxruntime is not None:
        sess = verify.onnxruntime.InferenceSession(str(folder / build.ONNX))
        row = features[:1]

        def ort_one() -> float:
            t0 = time.perf_counter()
            for _ in range(200):
                sess.run(None, {"features": row})
            return (time.perf_counter() - t0) / 200 * 1e9

        runs["onnxruntime, 1 row from Python"] = ort_one
    got: dict[str, list[float]] = {k: [] for k in runs}
    for _ in range(repeats):
        for k, fn in runs.items():
            got[k].append(fn() / 1000.0)
    return {k: statistics.median(v) for k, v in got.items()}


def bench(name: str, n_obs: int, repeats: int, cc: str) -> None:
    lp = build.load_policy(f"sb3:{name}")
    with tempfile.TemporaryDirectory() as tmp:
        folder, build_dir = Path(tmp) / "export", Path(tmp) / "build"
        build.write_export(lp, folder, with_onnx=build.onnx.onnx is not None)
        exe = verify.compile_harness(folder, build_dir, cc)
        obs = verify.rollout_observations(lp.policy, lp.config, n_obs)
        par = parity(lp, folder, exe, obs)
        host = verify.flash_size(verify.object_sections(folder, build_dir, cc, "-Os"))
        arm = arm_flash(folder, build_dir)
        times = timings(lp, folder, exe, obs[:2000], repeats)
    print(f"\n{name}: {lp.interface.layout.size} observation floats -> "
          f"{lp.network.input_size} features -> {lp.network.parameters} parameters "
          f"({lp.network.describe()['layers']})")  # fmt: skip
    diffs = ", ".join(f"{k} {v:.2e}" for k, v in par.items() if k != "observations")
    print(f"  max |diff| on {par['observations']} observations: {diffs}")
    print(f"  -Os {platform.machine()}: .text {host['text']} + .rodata {host['rodata']} = "
          f"{host['flash']} bytes")  # fmt: skip
    if arm is not None:
        print(f"  -Os Cortex-M4F: .text {arm['text']} + .rodata {arm['rodata']} = "
              f"{arm['flash']} bytes")  # fmt: skip
    for k, v in times.items():
        print(f"  {k}: {v:.2f} us per call (median of {repeats})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one policy, 1,000 obs, 3 repeats")
    ap.add_argument("--cc", default=None, help="C compiler (default: $CC or cc)")
    args = ap.parse_args()
    cc = verify.find_cc(args.cc)
    if cc is None:
        raise SystemExit("bench_export: no C compiler (cc) on the PATH")
    names = ["pair_quad3d"] if args.quick else model_names()
    n_obs, repeats = (1000, 3) if args.quick else (10_000, 9)
    version = subprocess.run([cc, "--version"], capture_output=True, text=True).stdout
    print(f"{platform.processor() or platform.machine()}, {version.splitlines()[0]}, "
          f"Python {platform.python_version()}")  # fmt: skip
    for name in names:
        bench(name, n_obs, repeats, cc)


if __name__ == "__main__":
    main()
