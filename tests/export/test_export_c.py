"""pairflock_policy.c compiled by the system C compiler (strict C99, warnings as errors) gives
the sb3: policy's action within 1e-5 on >= 10,000 observations each committed policy meets in
its own task (the whole chain: encode, network, decode), its network SB3's predict within
1e-5 (the features within 1e-4); it is plain C (math.h only, no heap); its size at -Os and
its time per call are printed."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import export_cases as cases

from baselines.export import c_source, verify

CC = verify.find_cc()
#: the functions of <math.h> the C may call
LIBM = {"tanhf", "log1pf", "sqrtf"}
#: encoded features, float32 in C against float64 rounded to float32 in Python
FEATURE_TOL = 1e-4
pytestmark = pytest.mark.skipif(
    CC is None, reason="no C compiler: cc (or $CC) is not on the PATH, the C export is not built"
)


def _harness(spec: str):
    return verify.compile_harness(cases.exported(spec), cases.scratch(), CC)


@pytest.mark.slow
@pytest.mark.parametrize("name", cases.MODELS)
def test_c_equals_the_sb3_policy_on_its_own_observations(name):
    spec = f"sb3:{name}"
    lp, obs = cases.loaded(spec), cases.observations(spec)
    features, net, env = cases.reference(spec)
    exe, width = _harness(spec), lp.network.output_size
    c_features, _ = verify.run_harness(exe, obs, "encode", lp.interface.observation_size)
    c_net, _ = verify.run_harness(exe, features, "network", width)
    c_env, _ = verify.run_harness(exe, obs, "policy", width)
    # the float32 encode rounds a few features (the closest-approach time of a neighbour
    # whose offset and velocity nearly cancel in x . w) by ~1e-5; the action stays within 1e-5
    np.testing.assert_allclose(c_features, features, rtol=0, atol=FEATURE_TOL)
    np.testing.assert_allclose(c_net, net, rtol=0, atol=cases.TOL)
    np.testing.assert_allclose(c_env, env, rtol=0, atol=cases.TOL)
    print(
        f"{name}: C vs SB3 on {len(obs)} observations, max |diff|: features "
        f"{np.abs(c_features - features).max():.2e}, network {np.abs(c_net - net).max():.2e}, "
        f"policy {np.abs(c_env - env).max():.2e}"
    )


@pytest.mark.parametrize("case", sorted(cases.TINY))
def test_c_of_every_algorithm_interface_and_dimension(case):
    """SAC (2-D), TD3 (3-D), PPO squashed without neighbour slots, the world interface."""
    spec = cases.tiny(case)
    lp, obs = cases.loaded(spec), cases.observations(spec, 600)
    exe = _harness(spec)
    want, _ = lp.policy.predict(obs)
    got, _ = verify.run_harness(exe, obs, "policy", lp.network.output_size)
    np.testing.assert_allclose(got, want, rtol=0, atol=cases.TOL)


def test_the_c_is_plain_c99_with_math_h_only_and_no_heap():
    spec = "sb3:pair_quad3d"
    folder, build = cases.exported(spec), cases.scratch()
    src = (folder / c_source.SOURCE).read_text() + (folder / c_source.HEADER).read_text()
    assert re.findall(r"#include\s*(\S+)", src) == ["<math.h>", '"pairflock_policy.h"']
    for word in ("malloc", "calloc", "realloc", "free(", "printf", "double"):
        assert word not in src, word
    header = (folder / c_source.HEADER).read_text()
    assert "void pairflock_policy(const float *observation, float *action);" in header
    sections = verify.object_sections(folder, build, CC, "-Os")  # -std=c99 -pedantic -Werror
    assert verify.flash_size(sections)["rodata"] >= 4 * cases.loaded(spec).network.parameters
    nm = shutil.which("nm")
    if nm is not None:  # the object needs nothing but libm
        obj = build / "pairflock_policy-Os.o"
        out = subprocess.run([nm, "-u", str(obj)], capture_output=True, text=True, check=True)
        assert {line.split()[-1] for line in out.stdout.splitlines()} <= LIBM


@pytest.mark.parametrize("name", ["pair_n20_a50", "pair_quad3d"])
def test_flash_size_at_os_and_time_per_call(name):
    spec = f"sb3:{name}"
    lp = cases.loaded(spec)
    flash = verify.flash_size(verify.object_sections(cases.exported(spec), cases.scratch(), CC))
    obs = cases.observations(spec)[:2000]
    _, ns = verify.run_harness(_harness(spec), obs, "policy", lp.network.output_size, repeats=5)
    assert 4 * lp.network.parameters <= flash["rodata"] < 4 * lp.network.parameters + 4096
    assert 0 < flash["text"] < 16384 and 0 < ns < 1e6
    print(f"{name} ({CC}, -Os): .text {flash['text']} B + .rodata {flash['rodata']} B = "
          f"{flash['flash']} B; {ns / 1000:.1f} us per call (-O2, this machine)")  # fmt: skip
