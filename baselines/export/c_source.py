"""``pairflock_policy.h`` / ``pairflock_policy.c``: the whole policy in C99, float32, no
heap, no dependency beyond ``<math.h>``.

The header declares four functions; a flight controller needs the first, or the other three
to hold the network's output over the decision period as in training::

    void pairflock_policy(const float *observation, float *action);
    void pairflock_policy_encode(const float *observation, float *features);
    void pairflock_policy_network(const float *features, float *net_action);
    void pairflock_policy_decode(const float *observation, const float *net_action,
                                 float *action);

``observation`` is the env's physical observation of one paired UAV (``PAIRFLOCK_OBS_SIZE``
floats, SI units, world frame; contract.json lists the fields), ``action`` the env action
(``PAIRFLOCK_ACTION_SIZE`` floats): the world-frame pair acceleration in units of
``PAIRFLOCK_PAIR_ACCEL_LIMIT`` m/s^2. ``pairflock_policy`` = encode, network, decode: what
``make_pair_policy("sb3:<model>", env).predict(observation)`` returns without a state (a
decision every call). The network function alone is what SB3's ``predict(features,
deterministic=True)`` and ``policy.onnx`` compute. Weights are ``static const`` arrays (in
flash on a microcontroller); activations live on the stack (two buffers of the widest layer).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from baselines.export.c_interface import c_float, interface_source
from baselines.export.network import PolicyNetwork

__all__ = ["HEADER", "SOURCE", "c_header", "c_source", "network_source"]

HEADER = "pairflock_policy.h"
SOURCE = "pairflock_policy.c"

_ACT = {"identity": 0, "tanh": 1, "relu": 2, "hardtanh": 3}

_DENSE = r"""
static float pf_act(float s, int act, float lo, float hi)
{
    if (act == 1) return tanhf(s);
    if (act == 2) return s > 0.0f ? s : 0.0f;
    if (act == 3) return s < lo ? lo : (s > hi ? hi : s);
    return s;
}

/* y = act(W x + b), W row-major (n_out, n_in); four rows at a time (independent sums, each
   in the order b + w_0 x_0 + w_1 x_1 + ..., so the result does not depend on the blocking) */
static void pf_dense(const float *W, const float *b, int n_out, int n_in, const float *x,
                     float *y, int act, float lo, float hi)
{
    int i = 0, j;
    for (; i + 4 <= n_out; i += 4) {
        const float *w0 = W + (long)i * n_in, *w1 = w0 + n_in, *w2 = w1 + n_in, *w3 = w2 + n_in;
        float s0 = b[i], s1 = b[i + 1], s2 = b[i + 2], s3 = b[i + 3];
        for (j = 0; j < n_in; ++j) {
            float xj = x[j];
            s0 += w0[j] * xj;
            s1 += w1[j] * xj;
            s2 += w2[j] * xj;
            s3 += w3[j] * xj;
        }
        y[i] = pf_act(s0, act, lo, hi);
        y[i + 1] = pf_act(s1, act, lo, hi);
        y[i + 2] = pf_act(s2, act, lo, hi);
        y[i + 3] = pf_act(s3, act, lo, hi);
    }
    for (; i < n_out; ++i) {
        const float *w = W + (long)i * n_in;
        float s = b[i];
        for (j = 0; j < n_in; ++j) s += w[j] * x[j];
        y[i] = pf_act(s, act, lo, hi);
    }
}
"""

_CHAIN = r"""
void pairflock_policy(const float *observation, float *action)
{
    float features[PF_FEAT_SIZE], net_action[PAIRFLOCK_ACTION_SIZE];
    pairflock_policy_encode(observation, features);
    pairflock_policy_network(features, net_action);
    pairflock_policy_decode(observation, net_action, action);
}
"""


def _array(name: str, values: np.ndarray) -> str:
    flat = [c_float(v) for v in np.asarray(values, np.float32).reshape(-1)]
    rows = [", ".join(flat[i : i + 8]) for i in range(0, len(flat), 8)]
    body = ",\n    ".join(rows)
    return f"static const float {name}[{len(flat)}] = {{\n    {body}\n}};"


def _output_lines(net: PolicyNetwork, x: str) -> list[str]:
    lines = []
    for i in range(net.output_size):
        lo, hi = c_float(net.low[i]), c_float(net.high[i])
        if net.output == "unscale":  # SB3: low + (0.5 * (a + 1.0) * (high - low))
            span = c_float(np.float32(net.high[i]) - np.float32(net.low[i]))
            lines.append(f"    net_action[{i}] = {lo} + (0.5f * ({x}[{i}] + 1.0f) * {span});")
        else:  # np.clip(a, low, high)
            v = f"{x}[{i}]"
            lines.append(f"    net_action[{i}] = {v} < {lo} ? {lo} : ({v} > {hi} ? {hi} : {v});")
    return lines


def network_source(net: PolicyNetwork) -> str:
    """The weight arrays and ``pairflock_policy_network``."""
    parts = [_DENSE]
    for i, layer in enumerate(net.layers):
        parts.append(_array(f"pf_w{i}", layer.weight))
        parts.append(_array(f"pf_b{i}", layer.bias))
    width = max(x.sizes[1] for x in net.layers)
    body = [
        "void pairflock_policy_network(const float *features, float *net_action)",
        "{",
        f"    float h[2][{width}];",
    ]
    src = "features"
    for i, layer in enumerate(net.layers):
        n_in, n_out = layer.sizes
        lo, hi = layer.limits or (0.0, 0.0)
        dst = f"h[{i % 2}]"
        body.append(
            f"    pf_dense(pf_w{i}, pf_b{i}, {n_out}, {n_in}, {src}, {dst}, "
            f"{_ACT[layer.activation]}, {c_float(lo)}, {c_float(hi)});"
        )
        src = dst
    body += [*_output_lines(net, src), "}"]
    return "\n\n".join([*parts, "\n".join(body)])


def c_header(net: PolicyNetwork, interface: Any, banner: str) -> str:
    """The text of ``pairflock_policy.h``; ``banner`` is a comment block (provenance)."""
    cfg = interface.config
    defines = {
        "PAIRFLOCK_OBS_SIZE": (interface.layout.size, "floats of the physical observation"),
        "PAIRFLOCK_FEATURE_SIZE": (net.input_size, "floats of the encoded observation"),
        "PAIRFLOCK_ACTION_SIZE": (net.output_size, "floats of an action"),
        "PAIRFLOCK_DECISION_PERIOD": (
            interface.decision_period,
            "control steps a network output is held",
        ),
        "PAIRFLOCK_CONTROL_DT": (c_float(cfg.dt), "s, the control period"),
        "PAIRFLOCK_PAIR_ACCEL_LIMIT": (
            c_float(cfg.pair_accel_limit),
            "m/s^2 per unit of action",
        ),
    }
    lines = [banner, "#ifndef PAIRFLOCK_POLICY_H", "#define PAIRFLOCK_POLICY_H", ""]
    lines += [f"#define {k} {v} /* {why} */" for k, (v, why) in defines.items()]
    lines += [
        "",
        "/* physical observation -> env action (world-frame pair acceleration / "
        "PAIRFLOCK_PAIR_ACCEL_LIMIT) */",
        "void pairflock_policy(const float *observation, float *action);",
        "/* the three stages; call encode + network every PAIRFLOCK_DECISION_PERIOD control "
        "steps */",
        "/* (and at an episode's first step), decode every control step with the fresh "
        "observation */",
        "void pairflock_policy_encode(const float *observation, float *features);",
        "void pairflock_policy_network(const float *features, float *net_action);",
        "void pairflock_policy_decode(const float *observation, const float *net_action, "
        "float *action);",
        "",
        "#endif /* PAIRFLOCK_POLICY_H */",
        "",
    ]
    return "\n".join(lines)


def c_source(net: PolicyNetwork, interface: Any, banner: str) -> str:
    """The text of ``pairflock_policy.c``."""
    if net.input_size != interface.observation_size:
        raise ValueError(
            f"the network takes {net.input_size} features, the interface gives "
            f"{interface.observation_size}"
        )
    parts = [
        banner,
        "#include <math.h>",
        f'#include "{HEADER}"',
        interface_source(interface),
        network_source(net),
        _CHAIN,
    ]
    return "\n".join(parts)
