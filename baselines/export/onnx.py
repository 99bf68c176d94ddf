"""``policy.onnx``: the policy network as an ONNX graph (opset 17), built node by node.

The graph is written from the :class:`~baselines.export.network.PolicyNetwork` (the same
arrays the C source holds) rather than traced through ``torch.onnx.export``: the layers are
few and known, the classic tracer is on its way out of current torch and the dynamo exporter needs
``onnxscript``; building the graph needs only ``onnx``. Input ``features`` (batch,
input_size) float32, the encoded observation; output ``action`` (batch, action_size)
float32, what SB3's ``predict(features, deterministic=True)`` returns. Each dense layer is a
``Gemm`` (transB = 1, as torch's Linear) followed by its activation; the output transform is
SB3's: ``Min``/``Max`` with the box, or ``low + 0.5 (a + 1) (high - low)`` for a squashed
policy, in SB3's operation order.

``onnx`` comes with the ``export`` extra; without it :func:`onnx_model` raises
``ModuleNotFoundError`` naming the install command.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from baselines.export.network import PolicyNetwork

try:  # the export extra: pip install 'pairflock-env[export]'
    import onnx
    from onnx import TensorProto, helper, numpy_helper
except ModuleNotFoundError:  # pragma: no cover - the extra is missing
    onnx = None

__all__ = ["INPUT", "IR_VERSION", "OPSET", "OUTPUT", "onnx_model", "write_onnx"]

#: the ONNX operator set the graph declares (Gemm, Tanh, Relu, Clip, Min, Max, Add, Mul)
OPSET = 17
#: the IR version of opset 17 (ONNX 1.12): readable by onnxruntime >= 1.12
IR_VERSION = 8
INPUT = "features"
OUTPUT = "action"


def _need_onnx() -> None:
    if onnx is None:
        raise ModuleNotFoundError(
            "writing policy.onnx needs onnx: pip install 'pairflock-env[export]' "
            "(or pass --no-onnx)",
            name="onnx",
        )


class _Graph:
    """Nodes and initializers, named in order."""

    def __init__(self) -> None:
        self.nodes: list = []
        self.inits: list = []

    def const(self, name: str, value: np.ndarray) -> str:
        self.inits.append(numpy_helper.from_array(np.asarray(value, np.float32), name))
        return name

    def node(self, op: str, inputs: list[str], out: str, **attrs) -> str:
        self.nodes.append(helper.make_node(op, inputs, [out], name=out, **attrs))
        return out


def _layers(g: _Graph, net: PolicyNetwork) -> str:
    x = INPUT
    for i, layer in enumerate(net.layers):
        w, b = g.const(f"W{i}", layer.weight), g.const(f"b{i}", layer.bias)
        x = g.node("Gemm", [x, w, b], f"dense{i}", transB=1)
        if layer.activation == "tanh":
            x = g.node("Tanh", [x], f"tanh{i}")
        elif layer.activation == "relu":
            x = g.node("Relu", [x], f"relu{i}")
        elif layer.activation == "hardtanh":
            lo, hi = layer.limits
            x = g.node("Clip", [x, g.const(f"lo{i}", lo), g.const(f"hi{i}", hi)], f"clip{i}")
    return x


def _output(g: _Graph, net: PolicyNetwork, x: str) -> None:
    low = g.const("action_low", net.low)
    if net.output == "unscale":  # SB3: low + (0.5 * (a + 1.0) * (high - low))
        one, half = g.const("one", 1.0), g.const("half", 0.5)
        span = g.const("action_span", net.high - net.low)
        x = g.node("Add", [x, one], "shifted")
        x = g.node("Mul", [half, x], "halved")
        x = g.node("Mul", [x, span], "spanned")
        g.node("Add", [low, x], OUTPUT)
    else:  # np.clip(a, low, high)
        x = g.node("Max", [x, low], "above_low")
        g.node("Min", [x, g.const("action_high", net.high)], OUTPUT)


def onnx_model(net: PolicyNetwork, metadata: Mapping[str, str] | None = None):
    """The ``onnx.ModelProto`` of ``net`` (checked by ``onnx.checker``); ``metadata`` is
    stored as the model's metadata_props (strings)."""
    _need_onnx()
    g = _Graph()
    _output(g, net, _layers(g, net))
    graph = helper.make_graph(
        g.nodes,
        "pairflock_policy",
        [helper.make_tensor_value_info(INPUT, TensorProto.FLOAT, ["batch", net.input_size])],
        [helper.make_tensor_value_info(OUTPUT, TensorProto.FLOAT, ["batch", net.output_size])],
        g.inits,
    )
    model = helper.make_model(
        graph,
        opset_imports=[helper.make_opsetid("", OPSET)],
        producer_name="pairflock-export",
        ir_version=IR_VERSION,
        doc_string="Deterministic action of a pairflock pair policy from its encoded "
        "observation (see contract.json).",
    )
    helper.set_model_props(model, {str(k): str(v) for k, v in (metadata or {}).items()})
    onnx.checker.check_model(model, full_check=True)
    return model


def write_onnx(net: PolicyNetwork, path: str, metadata: Mapping[str, str] | None = None) -> int:
    """Write ``net`` as ONNX to ``path``; returns the file's size in bytes."""
    data = onnx_model(net, metadata).SerializeToString()
    with open(path, "wb") as f:
        f.write(data)
    return len(data)
