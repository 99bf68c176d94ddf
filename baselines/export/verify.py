"""Checks of an export: observations from the policy's own task, onnxruntime's and the
compiled C's outputs on them, the C object's size and its time per call.

The C is checked through a small harness program (:data:`HARNESS`, written next to the
export in a build folder) that reads float32 rows from a file, runs one of the exported
functions on each and writes the outputs; asked for repeats it also times the calls
(``clock_gettime`` of the process's CPU time, steadier than the wall clock on a shared
machine; the median pass). The object's flash size is the size of its ``.text``
and ``.rodata`` sections, read from the ELF object the compiler writes.
"""

from __future__ import annotations

import os
import shutil
import struct
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

from baselines.evaluation.rollout import rollout

try:  # the export extra
    import onnxruntime
except ModuleNotFoundError:  # pragma: no cover - the extra is missing
    onnxruntime = None

__all__ = [
    "C_FLAGS",
    "HARNESS",
    "compile_harness",
    "elf_sections",
    "find_cc",
    "flash_size",
    "object_sections",
    "onnx_actions",
    "rollout_observations",
    "run_harness",
]

#: warnings are errors: the exported C compiles clean as strict C99
C_FLAGS = ("-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror")

HARNESS = r"""#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "pairflock_policy.h"

/* harness MODE IN OUT N REPEATS: MODE 0 policy, 1 network, 2 encode; IN float32 rows */
static void run(int mode, const float *in, float *out, long n, int k_in, int k_out)
{
    long r;
    for (r = 0; r < n; ++r) {
        if (mode == 0) pairflock_policy(in + r * k_in, out + r * k_out);
        else if (mode == 1) pairflock_policy_network(in + r * k_in, out + r * k_out);
        else pairflock_policy_encode(in + r * k_in, out + r * k_out);
    }
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    int mode, reps, k_in, k_out, i;
    long n;
    float *in, *out;
    double *ns;
    FILE *f;
    if (argc != 6) return 2;
    mode = atoi(argv[1]); n = atol(argv[4]); reps = atoi(argv[5]);
    k_in = mode == 1 ? PAIRFLOCK_FEATURE_SIZE : PAIRFLOCK_OBS_SIZE;
    k_out = mode == 0 ? PAIRFLOCK_ACTION_SIZE : mode == 1 ? PAIRFLOCK_ACTION_SIZE
                                                         : PAIRFLOCK_FEATURE_SIZE;
    in = malloc(sizeof(float) * n * k_in); out = malloc(sizeof(float) * n * k_out);
    ns = malloc(sizeof(double) * (reps > 0 ? reps : 1));
    f = fopen(argv[2], "rb");
    if (!f || fread(in, sizeof(float), n * k_in, f) != (size_t)(n * k_in)) return 3;
    fclose(f);
    run(mode, in, out, n, k_in, k_out);
    for (i = 0; i < reps; ++i) {
        struct timespec a, b;
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
        run(mode, in, out, n, k_in, k_out);
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
        ns[i] = ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / n;
    }
    if (reps > 0) {
        qsort(ns, reps, sizeof(double), cmp);
        printf("%.1f\n", ns[reps / 2]);
    }
    f = fopen(argv[3], "wb");
    if (!f || fwrite(out, sizeof(float), n * k_out, f) != (size_t)(n * k_out)) return 4;
    fclose(f);
    return 0;
}
"""

_MODES = {"policy": 0, "network": 1, "encode": 2}


def find_cc(cc: str | None = None) -> str | None:
    """The C compiler to use: ``cc``, else ``$CC``, else ``cc`` on the PATH (None: none)."""
    return shutil.which(cc or os.environ.get("CC") or "cc")


def _compile(cc: str, args: list[str], what: str) -> None:
    res = subprocess.run([cc, *args], capture_output=True, text=True, check=False)
    if res.returncode != 0:
        raise RuntimeError(f"{what} did not compile:\n{res.stderr.strip()}")


def compile_harness(export_dir: str | Path, build_dir: str | Path, cc: str, opt: str = "-O2"):
    """Compile the exported C with :data:`HARNESS` into ``build_dir``; returns the program."""
    export_dir, build_dir = Path(export_dir), Path(build_dir)
    build_dir.mkdir(parents=True, exist_ok=True)
    (build_dir / "harness.c").write_text(HARNESS)
    exe = build_dir / f"harness{opt}"
    sources = [str(build_dir / "harness.c"), str(export_dir / "pairflock_policy.c")]
    _compile(cc, [*C_FLAGS, opt, f"-I{export_dir}", *sources, "-o", str(exe), "-lm"], "harness")
    return exe


def run_harness(exe: str | Path, rows: np.ndarray, mode: str, width: int, repeats: int = 0):
    """Outputs (n, width) of the exported function ``mode`` ("policy", "network", "encode")
    on ``rows`` (n, k) float32, and the median nanoseconds per call over ``repeats`` timed
    passes (None without repeats)."""
    rows = np.ascontiguousarray(rows, dtype=np.float32)
    folder = Path(exe).parent
    src, dst = folder / f"in_{mode}.bin", folder / f"out_{mode}.bin"
    rows.tofile(src)
    args = [str(exe), str(_MODES[mode]), str(src), str(dst), str(len(rows)), str(repeats)]
    res = subprocess.run(args, capture_output=True, text=True, check=False)
    if res.returncode != 0:
        raise RuntimeError(f"the harness failed with status {res.returncode}: {res.stderr}")
    out = np.fromfile(dst, dtype=np.float32).reshape(len(rows), width)
    return out, (float(res.stdout) if repeats else None)


def object_sections(export_dir: str | Path, build_dir: str | Path, cc: str, opt: str = "-Os"):
    """Section sizes (bytes, by name) of ``pairflock_policy.c`` compiled alone with ``opt``."""
    obj = Path(build_dir) / f"pairflock_policy{opt}.o"
    Path(build_dir).mkdir(parents=True, exist_ok=True)
    src = str(Path(export_dir) / "pairflock_policy.c")
    _compile(cc, [*C_FLAGS, opt, "-c", src, "-o", str(obj)], "pairflock_policy.c")
    return elf_sections(obj.read_bytes())


def elf_sections(data: bytes) -> dict[str, int]:
    """{name: size} of the sections of a 64- or 32-bit little-endian ELF object."""
    if data[:4] != b"\x7fELF" or data[5] != 1:
        raise ValueError("not a little-endian ELF object: read its size with `size` instead")
    wide = data[4] == 2
    if wide:
        shoff, shentsize, shnum, shstrndx = struct.unpack_from("<Q10xHHH", data, 0x28)
    else:
        shoff, shentsize, shnum, shstrndx = struct.unpack_from("<I10xHHH", data, 0x20)
    fmt = "<IIQQQQ" if wide else "<IIIIII"
    heads = [struct.unpack_from(fmt, data, shoff + i * shentsize) for i in range(shnum)]
    names = heads[shstrndx][4]  # the string table's file offset

    def name(h: tuple) -> str:
        end = data.index(b"\0", names + h[0])
        return data[names + h[0] : end].decode()

    return {name(h): h[5] for h in heads}


def flash_size(sections: dict[str, int]) -> dict[str, int]:
    """``.text`` and ``.rodata`` bytes (their sub-sections included) and their sum."""
    text = sum(v for k, v in sections.items() if k == ".text" or k.startswith(".text."))
    ro = sum(v for k, v in sections.items() if k == ".rodata" or k.startswith(".rodata."))
    return {"text": text, "rodata": ro, "flash": text + ro}


def onnx_actions(path: str | Path, features: np.ndarray) -> np.ndarray:
    """onnxruntime's output of ``policy.onnx`` on ``features`` (n, k) float32."""
    if onnxruntime is None:
        raise ModuleNotFoundError(
            "checking policy.onnx needs onnxruntime: pip install 'pairflock-env[export]'",
            name="onnxruntime",
        )
    session = onnxruntime.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    feed = {session.get_inputs()[0].name: np.ascontiguousarray(features, np.float32)}
    return session.run(None, feed)[0]


def rollout_observations(policy: Any, config: Any, n: int, first_seed: int = 0) -> np.ndarray:
    """At least ``n`` physical observations (float32 rows) met by ``policy`` flying whole
    episodes of ``config`` (seeds ``first_seed``, ``first_seed + 1``, ... in one batch)."""
    per_episode = config.episode_steps * config.n_agents
    seeds = list(range(first_seed, first_seed + max(1, -(-n // per_episode))))
    rows: list[np.ndarray] = []

    def grab(k: int, core: Any, res: Any, live: np.ndarray) -> None:
        rows.append(np.array(res.obs[live], dtype=np.float32).reshape(-1, res.obs.shape[-1]))

    rollout(config, policy, seeds, on_step=grab)
    return np.concatenate(rows)
